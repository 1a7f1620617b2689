"""io/toml.py: user TOML files are read as UTF-8 text or refused in one line."""

import pytest

from sonartrack.core.errors import InputError
from sonartrack.io import toml as toml_io


def test_toml_that_is_not_text_or_is_a_directory_is_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(InputError, match="not UTF-8 text"):
        toml_io.load(bad)
    with pytest.raises(InputError, match="is a directory"):
        toml_io.load(tmp_path)
