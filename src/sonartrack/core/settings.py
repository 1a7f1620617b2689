"""Settings: each group declared once, with type, default, unit and a one-line doc beside each field.

Every group of settings in sonartrack (a tracker, a detector, a study's scenario) is a subclass of
:class:`Settings`, and each field is declared with :func:`setting`::

    class TrackerSettings(Settings):
        pd: float = setting(0.8, "probability of detection of a target", unit="1", gt=0, le=1)

The same declaration serves every face: studies nest it in their config, TOML files nest it as a
table (``[tracker]``), command-line options take their help text from it (``cli/_settings.py``), and
``--print-config`` prints the resolved values with their units and docs (:func:`to_commented_toml`).
Settings are frozen pydantic models with unknown keys refused, so a misspelt TOML key is an error, not
a silently ignored value. TOML has no null: a field that may be None ("off") while its default is a value is
switched off in a file by the string ``"off"`` (:data:`OFF`), and ``--print-config`` writes it so.
"""

from __future__ import annotations

import math
import sys
import types
import typing
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, create_model, model_validator
from pydantic.fields import FieldInfo

#: the TOML spelling of None for a field that may be switched off (TOML has no null)
OFF = "off"


def may_be_off(annotation) -> bool:
    """Whether a field of this annotation takes None and not also the string "off" as a value of its own."""
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) not in (typing.Union, types.UnionType) or type(None) not in args:
        return False
    literals = [typing.get_args(a) for a in args if typing.get_origin(a) is typing.Literal]
    return str not in args and not any(OFF in values for values in literals)


class Settings(BaseModel):
    """Base of every settings group: frozen, unknown keys refused, NaN refused; ``"off"`` means None where None
    is allowed."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _off_means_none(cls, data):
        # TOML cannot write None, so a file says "off" (any case) for a field that can be switched off
        if not isinstance(data, dict):
            return data
        fields = cls.model_fields
        return {k: None if (isinstance(v, str) and v.strip().lower() == OFF and k in fields
                            and may_be_off(fields[k].annotation)) else v for k, v in data.items()}


def setting(default: Any = ..., doc: str = "", *, unit: str = "", default_factory=None, **constraints) -> Any:
    """Declare a settings field: its default, a one-line doc, its unit and pydantic constraints.

    Parameters
    ----------
    default : object, optional
        Default value; ``...`` (the default) makes the field required.
    doc : str, default ""
        One-line description (shown by ``--print-config`` and the command-line help).
    unit : str, default ""
        Unit of the value ("1" for dimensionless, "" for none, e.g. a name).
    default_factory : callable, optional
        Makes the default (for lists and nested groups); used instead of ``default``.
    **constraints
        pydantic constraints (``gt``, ``ge``, ``le``, ``lt``, ``min_length``, ...).

    Returns
    -------
    pydantic.fields.FieldInfo
        The field, to be assigned in a :class:`Settings` subclass.
    """
    extra = {"unit": unit}
    if default_factory is not None:
        return Field(default_factory=default_factory, description=doc, json_schema_extra=extra, **constraints)
    return Field(default, description=doc, json_schema_extra=extra, **constraints)


def derived_settings(base: type[Settings], name: str, doc: str, *, drop: tuple[str, ...] = (),
                     defaults: dict[str, tuple[Any, str]] | None = None) -> type[Settings]:
    """A settings class for one stage of a system: ``base``'s fields less ``drop``, with the defaults and docs of
    ``defaults`` (field -> (value, doc)) replaced.

    A system declares each physical quantity (array, sound speed, window, threshold) once at the root of its
    settings tree, so the stage's own group must not declare it again (``drop``); and where the system runs a
    library component with other defaults than the library's (the passive chain's tracker on a normalised
    statistic), the new values are the system's declarations, with docs that describe them (``defaults``), so
    ``--print-config`` never prints a value beside a doc written for another one.

    Parameters
    ----------
    base : type[Settings]
        The library's settings class of the stage (its validators still run: :meth:`build` makes a ``base``).
    name, doc : str
        Class name and docstring of the derived class.
    drop : tuple of str
        Fields of ``base`` that the system's root declares; :meth:`build` takes their values.
    defaults : dict
        Field name -> (new default, new one-line doc); the unit and bounds stay ``base``'s.

    Returns
    -------
    type[Settings]
        A frozen settings class with a method ``build(**root_values) -> base``.
    """
    defaults = defaults or {}
    unknown = (set(drop) | set(defaults)) - set(base.model_fields)
    if unknown:
        raise TypeError(f"{base.__name__} has no field(s) {sorted(unknown)}")
    fields: dict[str, Any] = {}
    for field_name, info in base.model_fields.items():
        if field_name in drop:
            continue
        if field_name in defaults:
            value, new_doc = defaults[field_name]
            info = FieldInfo.merge_field_infos(info, default=value, default_factory=None, description=new_doc)
        fields[field_name] = (info.annotation, info)

    def build(self, **root_values):
        return base(**self.model_dump(), **root_values)

    def check_with_base(self):
        # the library class's own cross-field checks, with the dropped fields at the library's defaults
        if not any(base.model_fields[k].is_required() for k in drop):
            base(**self.model_dump())
        return self

    # the caller's module: pickle (a study's worker processes) finds a class by its module and name
    module = sys._getframe(1).f_globals.get("__name__", __name__)
    cls = create_model(name, __base__=Settings, __doc__=doc, __module__=module,
                       __validators__={"_check_with_base": model_validator(mode="after")(check_with_base)}, **fields)
    cls.build = build
    return cls


def field_unit(model_cls: type[BaseModel], name: str) -> str:
    """The unit declared for field ``name`` of a settings class.

    Parameters
    ----------
    model_cls : type of pydantic.BaseModel
        The settings class.
    name : str
        Field name.

    Returns
    -------
    str
        The unit ('' if none).
    """
    extra = model_cls.model_fields[name].json_schema_extra or {}
    return str(extra.get("unit", "")) if isinstance(extra, dict) else ""


def field_help(model_cls: type[BaseModel], name: str) -> str:
    """'doc (unit)' of field ``name``: the text a command-line option shows.

    Round brackets, because typer's rich help would read '[dB]' as a markup tag and drop it; a
    dimensionless ("1") or unitless field shows its doc alone.

    Parameters
    ----------
    model_cls, name : type of pydantic.BaseModel, str
        The settings class and the field's name (as :func:`field_unit`).

    Returns
    -------
    str
        The help text (the field name if it has no doc).
    """
    f = model_cls.model_fields[name]
    unit = field_unit(model_cls, name)
    doc = f.description or name
    return f"{doc} ({unit})" if unit and unit != "1" else doc


def toml_value(v) -> str:
    """A TOML literal for a scalar or a (nested) list of scalars.

    Parameters
    ----------
    v : bool, int, float, str, list or tuple
        The value (NaN and infinities become TOML's ``nan``/``inf``).

    Returns
    -------
    str
        The literal.

    Raises
    ------
    TypeError
        For any other type.
    """
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
    """Nested JSON-like ``data`` as TOML text: plain keys first, then tables (dicts), then arrays of tables.

    ``comments`` has the same shape (a string per key, a dict per table, a list of dicts per array of
    tables); a key with a comment is followed by ``# comment``, and a None value with a comment is written
    as a commented-out ``# key = (not set)`` line (without one it is left out: TOML has no null).

    Parameters
    ----------
    data : dict
        Values: scalars, lists of scalars, dicts (tables), lists of dicts (arrays of tables).
    comments : dict, optional
        Comments, shaped as ``data``.

    Returns
    -------
    str
        TOML text ending in a newline.
    """
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
    """The resolved settings as TOML, each key followed by ``# doc (unit)``.

    Nested groups become tables, lists of groups arrays of tables. The output is valid TOML and reads back
    to the same settings.

    Parameters
    ----------
    settings : pydantic.BaseModel
        A settings object.

    Returns
    -------
    str
        TOML text.
    """
    return render_toml(_dump_with_off(settings), _field_comments(settings))


def _dump_with_off(settings: BaseModel) -> dict:
    """``model_dump(mode="json")`` with a None written ``"off"`` where the field may be None and its default is a
    value (so the TOML reads back to None, not to the default); a None whose default is None, or in a required
    field (a value still to be given), stays unset."""
    cls, out = type(settings), settings.model_dump(mode="json")
    for name, field in cls.model_fields.items():
        value = getattr(settings, name)
        if isinstance(value, BaseModel):
            out[name] = _dump_with_off(value)
        elif isinstance(value, list | tuple) and value and all(isinstance(v, BaseModel) for v in value):
            out[name] = [_dump_with_off(v) for v in value]
        elif (value is None and may_be_off(field.annotation) and not field.is_required()
              and field.get_default(call_default_factory=True) is not None):
            out[name] = OFF
    return out
