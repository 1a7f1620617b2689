"""TOML in and out for study and tracker configurations.

Reading uses the standard library's ``tomllib``. Writing covers what configs hold: scalars,
lists of scalars (or of lists), and nested tables. Unknown keys and wrong types are reported by
pydantic as one-line :class:`InputError` messages.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from sonartrack.core.errors import InputError
from sonartrack.core.settings import toml_value


def _scalar(v) -> str:
    if v is None:
        raise TypeError("TOML has no null: leave the key out instead")
    return toml_value(v)


def dumps(data: dict, _prefix: str = "") -> str:
    """Serialise a nested dict to TOML text (tables after plain keys, as TOML requires)."""
    lines, tables = [], []
    for k, v in data.items():
        if v is None:
            continue
        if isinstance(v, dict):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {_scalar(v)}")
    for k, v in tables:
        name = f"{_prefix}{k}"
        lines.append("")
        lines.append(f"[{name}]")
        lines.append(dumps(v, _prefix=name + ".").rstrip("\n"))
    return "\n".join(lines).strip("\n") + "\n"


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
