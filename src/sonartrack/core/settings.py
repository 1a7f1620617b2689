"""Settings: each group declared once, with type, default, unit and a one-line doc beside each field.

Every group of settings in sonartrack (a tracker, a detector, a study's scenario) is a subclass of
:class:`Settings`, and each field is declared with :func:`setting`::

    class TrackerSettings(Settings):
        pd: float = setting(0.8, "probability of detection of a target", unit="1", gt=0, le=1)

The same declaration serves every face: studies nest it in their config, TOML files nest it as a
table (``[tracker]``), command-line options take their help text from it (``cli/_settings.py``), and
``--print-config`` prints the resolved values with their units and docs (:func:`to_commented_toml`).
Settings are frozen pydantic models with unknown keys refused, so a misspelt TOML key is an error, not
a silently ignored value.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel, ConfigDict, Field


class Settings(BaseModel):
    """Base of every settings group: frozen, unknown keys refused, NaN refused."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


def setting(default: Any = ..., doc: str = "", *, unit: str = "", default_factory=None, **constraints) -> Any:
    """A settings field: ``default``, a one-line ``doc``, its ``unit`` ("1" for dimensionless), and
    pydantic constraints (``gt``, ``ge``, ``le``, ``lt``, ``min_length``, ...)."""
    extra = {"unit": unit}
    if default_factory is not None:
        return Field(default_factory=default_factory, description=doc, json_schema_extra=extra, **constraints)
    return Field(default, description=doc, json_schema_extra=extra, **constraints)


def field_unit(model_cls: type[BaseModel], name: str) -> str:
    """The unit declared for field ``name`` of a settings class ('' if none)."""
    extra = model_cls.model_fields[name].json_schema_extra or {}
    return str(extra.get("unit", "")) if isinstance(extra, dict) else ""


def field_help(model_cls: type[BaseModel], name: str) -> str:
    """'doc (unit)' of field ``name``: the text a command-line option shows.

    Round brackets, because typer's rich help would read '[dB]' as a markup tag and drop it."""
    f = model_cls.model_fields[name]
    unit = field_unit(model_cls, name)
    doc = f.description or name
    return f"{doc} ({unit})" if unit and unit != "1" else doc


def toml_value(v) -> str:
    """A TOML literal for a scalar or a (nested) list of scalars."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def render_toml(data: dict, comments: dict | None = None, _prefix: str = "") -> str:
    """Nested JSON-like ``data`` as TOML text: plain keys first, then tables (dicts), then arrays of tables
    (lists of dicts). ``comments`` has the same shape (a string per key, a dict per table, a list of dicts per
    array of tables); a key with a comment is followed by ``# comment``, and a None value with a comment is
    written as a commented-out ``# key = (not set)`` line (without one it is left out: TOML has no null)."""
    comments = comments or {}
    lines: list[str] = []
    tables, arrays = [], []
    for key, value in data.items():
        note = comments.get(key)
        if isinstance(value, dict):
            tables.append((key, value, note if isinstance(note, dict) else None))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            arrays.append((key, value, note if isinstance(note, list) else [None] * len(value)))
        elif value is None:
            if isinstance(note, str):
                lines.append(f"# {key} = (not set)  # {note}")
        else:
            lines.append(f"{key} = {toml_value(value)}" + (f"  # {note}" if isinstance(note, str) else ""))
    for key, value, note in tables:
        lines += ["", f"[{_prefix}{key}]", render_toml(value, note, f"{_prefix}{key}.").rstrip("\n")]
    for key, items, notes in arrays:
        for item, note in zip(items, notes, strict=True):
            lines += ["", f"[[{_prefix}{key}]]", render_toml(item, note, f"{_prefix}{key}.").rstrip("\n")]
    return "\n".join(lines).strip("\n") + "\n"


def _field_comments(settings: BaseModel) -> dict:
    """``render_toml`` comments of a settings object: 'doc (unit)' per field, nested for groups."""
    cls = type(settings)
    out: dict = {}
    for name in cls.model_fields:
        value = getattr(settings, name)
        if isinstance(value, BaseModel):
            out[name] = _field_comments(value)
        elif isinstance(value, list | tuple) and value and all(isinstance(v, BaseModel) for v in value):
            out[name] = [_field_comments(v) for v in value]
        else:
            out[name] = field_help(cls, name)
    return out


def to_commented_toml(settings: BaseModel) -> str:
    """The resolved settings as TOML, each key followed by ``# doc (unit)``; nested groups as tables, lists of
    groups as arrays of tables. The output is valid TOML and reads back to the same settings."""
    return render_toml(settings.model_dump(mode="json"), _field_comments(settings))
