"""TOML in and out for study and tracker configurations.

Reading uses the standard library's ``tomllib``. Writing covers what configs hold: scalars,
lists of scalars (or of lists), and nested tables. Unknown keys and wrong types are reported by
pydantic as one-line :class:`InputError` messages.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from sonartrack.core.errors import InputError
from sonartrack.core.settings import may_be_off, render_toml


def dumps(data: dict) -> str:
    """Serialise a nested dict to TOML text (core/settings.py ``render_toml``: the one TOML writer).

    Parameters
    ----------
    data : dict
        Scalars, lists and nested tables.

    Returns
    -------
    str
        TOML text.
    """
    return render_toml(data)


def load(path: str | Path) -> dict:
    """Read the TOML file ``path`` (str or pathlib.Path).

    Returns
    -------
    dict
        Its tables and values.

    Raises
    ------
    InputError
        If the path is missing or a directory, the file is not UTF-8, or it is not valid TOML.
    """
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


def validate(model_cls, data: dict, source: str = "config", given: frozenset[str] = frozenset()):
    """Build a pydantic model from ``data``; the first validation error becomes a one-line InputError.

    A value outside a declared bound (``gt``/``ge``/``lt``/``le`` of ``core/settings.py`` ``setting``) names the
    key, the value, the whole declared range with its unit, and says to check the unit (a km/s sound speed, a
    1e300).

    Parameters
    ----------
    model_cls : type of pydantic.BaseModel
        The settings class.
    data : dict
        Values, nested as the class's groups.
    source : str, default "config"
        What the values came from, named in the message.
    given : frozenset of str, optional
        Dotted keys set by command-line options; an error there is said to be the option's.

    Returns
    -------
    pydantic.BaseModel
        The validated instance of ``model_cls``.

    Raises
    ------
    InputError
        On the first validation error.
    """
    from pydantic import ValidationError

    try:
        return model_cls.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = tuple(err.get("loc", ()))
        where = ".".join(str(x) for x in loc)
        origin = "command-line option" if where in given else source
        if err.get("type") in RANGE_ERRORS and isinstance(err.get("input"), int | float):
            raise InputError(f"{origin}: {range_message(model_cls, loc, err)}") from None
        if not loc:  # a check across fields (a model validator): its own message says which keys and the fix
            raise InputError(f"{origin}: {str(err.get('msg')).removeprefix('Value error, ')}") from None
        info = _field_at(model_cls, loc)
        off = ' (or "off" to switch it off)' if info is not None and may_be_off(info.annotation) else ""
        raise InputError(f"{origin}: '{where}': {str(err.get('msg')).removeprefix('Value error, ')}{off}") from None


#: pydantic's error types of a numeric bound
RANGE_ERRORS = frozenset({"greater_than", "greater_than_equal", "less_than", "less_than_equal"})


def _field_at(model_cls, loc: tuple):
    """The pydantic FieldInfo at error location ``loc`` of ``model_cls`` (nested groups, lists of groups), or None."""
    from typing import get_args

    from pydantic import BaseModel

    cls, info = model_cls, None
    for part in loc:
        if isinstance(part, int):
            continue
        if not (isinstance(cls, type) and issubclass(cls, BaseModel)) or part not in cls.model_fields:
            return None
        info = cls.model_fields[part]
        kinds = [info.annotation, *get_args(info.annotation)]
        kinds += [a for k in kinds[1:] for a in get_args(k)]  # list[Group] | None: the group inside the list
        cls = next((k for k in kinds if isinstance(k, type) and issubclass(k, BaseModel)), None)
    return info


def range_message(model_cls, loc: tuple, err: dict) -> str:
    """One-line message for a value outside its declared range: the bounds as declared, and the fix.

    Parameters
    ----------
    model_cls : type of pydantic.BaseModel
        The settings class.
    loc : tuple
        The error's location (nested keys; list indices are skipped).
    err : dict
        The pydantic error (``input``, ``msg``).

    Returns
    -------
    str
        "'key' = value is outside its range lo <= key <= hi (unit): check its unit ...".
    """
    name = ".".join(str(x) for x in loc)
    value = err["input"] if isinstance(err["input"], int) else f"{err['input']:g}"
    info = _field_at(model_cls, loc)
    lower, upper = "", ""
    for m in info.metadata if info is not None else ():
        for attr, side, op in (("gt", "lo", "<"), ("ge", "lo", "<="), ("lt", "hi", "<"), ("le", "hi", "<=")):
            bound = getattr(m, attr, None)
            if bound is not None and side == "lo":
                lower = f"{bound:g} {op} "
            elif bound is not None:
                upper = f" {op} {bound:g}"
    if not lower and not upper:  # not found in the declaration: pydantic's own account of the one bound
        return f"'{name}' = {value}: {err.get('msg')}: check its unit (see --print-config)"
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    unit = extra.get("unit", "")
    dimensioned = bool(unit) and unit != "1"
    fix = "check its unit (see --print-config)" if dimensioned else "give a value in that range"
    return (f"'{name}' = {value} is outside its range {lower}{name.rsplit('.', 1)[-1]}{upper}"
            f"{f' ({unit})' if dimensioned else ''}: {fix}")
