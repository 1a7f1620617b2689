"""TOML in and out for study and tracker configurations.

Reading uses the standard library's ``tomllib``. Writing covers what configs hold: scalars,
lists of scalars (or of lists), and nested tables. Unknown keys and wrong types are reported by
pydantic as one-line :class:`InputError` messages.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from sonartrack.core.errors import InputError
from sonartrack.core.settings import render_toml


def dumps(data: dict) -> str:
    """Serialise a nested dict to TOML text (core/settings.py ``render_toml``: the one TOML writer)."""
    return render_toml(data)


def load(path: str | Path) -> dict:
    """Read a TOML file; a missing or malformed file raises a one-line :class:`InputError`."""
    p = Path(path)
    if p.is_dir():
        raise InputError(f"config path {p} is a directory: give the TOML file inside it")
    if not p.is_file():
        raise InputError(f"config file not found: {p}")
    try:
        return tomllib.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(f"config file {p} is not UTF-8 text (a binary file, or another encoding): "
                         "give a TOML text file saved as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"config file {p} is not valid TOML: {exc}") from None


def validate(model_cls, data: dict, source: str = "config"):
    """Build a pydantic model from ``data``; the first validation error becomes an InputError."""
    from pydantic import ValidationError

    try:
        return model_cls.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(x) for x in err.get("loc", ())) or "(top level)"
        raise InputError(f"{source}: '{where}': {err.get('msg')}") from None
