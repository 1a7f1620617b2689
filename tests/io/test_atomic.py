"""Atomic writes: a failed write leaves the old file intact and no temporary behind."""

import pandas as pd
import pytest

from sonartrack.io.atomic import atomic_path, write_csv


def test_failed_write_keeps_the_old_file(tmp_path):
    target = tmp_path / "out.csv"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("disk full")
    assert target.read_text() == "old\n"
    assert list(tmp_path.iterdir()) == [target]


def test_successful_write_replaces(tmp_path):
    target = write_csv(pd.DataFrame({"a": [1, 2]}), tmp_path / "t.csv")
    assert target.read_text().splitlines() == ["a", "1", "2"]
    assert list(tmp_path.iterdir()) == [target]

