"""The settings that differ from the defaults: one row per changed leaf of a settings tree (name, value, default, unit).

A run's settings (a :class:`~sonartrack.core.settings.Settings` tree) are compared with a default instance of the
same class, leaf by leaf: a nested group is walked into and compared with the group its parent declares as default
(which may differ from the group class's own defaults: a system's tree sets its stages' values), a list of groups
item by item when the lengths agree, any other value as a whole. A field without a default (required) is always
listed, with the default :data:`NO_DEFAULT`. The pages (report/settings_table.py) show these rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel, ValidationError

from sonartrack.core.settings import field_unit

#: the default shown for a field that has none (it is required, so the run always gives it)
NO_DEFAULT = "(none: required)"


@dataclass(frozen=True, slots=True)
class SettingChange:
    """One setting whose value is not its default: ``name`` the dotted path in the tree (``tracker.gate_deg``;
    ``ships[1].speed_kn`` in a list of groups), the run's ``value`` and the ``default`` (plain Python: numbers,
    text, lists, dicts), the declared ``unit`` and one-line ``doc``."""

    name: str
    value: Any
    default: Any
    unit: str
    doc: str


def _plain(v) -> Any:
    """A value as plain Python (a group as its dict, tuples as lists), for comparing and showing."""
    if isinstance(v, BaseModel):
        return v.model_dump(mode="json")
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


def default_settings(cls: type[BaseModel], like: BaseModel | None = None) -> BaseModel | None:
    """A default instance of settings class ``cls``: ``cls()``, or, when fields are required, ``cls`` with the
    required fields taken from ``like`` (None when even that does not validate).

    Parameters
    ----------
    cls : type of pydantic.BaseModel
        The settings class.
    like : pydantic.BaseModel, optional
        An instance whose required fields are borrowed.

    Returns
    -------
    pydantic.BaseModel or None
        The default instance.
    """
    try:
        return cls()
    except ValidationError:
        pass
    if like is None:
        return None
    required = {k: getattr(like, k) for k, f in cls.model_fields.items() if f.is_required()}
    try:
        return cls(**required)
    except ValidationError:
        return None


def _field_default(cls: type[BaseModel], name: str, default: BaseModel | None) -> Any:
    info = cls.model_fields[name]
    if info.is_required():
        return NO_DEFAULT
    if default is not None:
        return getattr(default, name)
    return info.get_default(call_default_factory=True)


def _walk(value: BaseModel, default: BaseModel | None, prefix: str) -> list[SettingChange]:
    cls = type(value)
    out: list[SettingChange] = []
    for name, info in cls.model_fields.items():
        v, d, path = getattr(value, name), _field_default(cls, name, default), prefix + name
        if isinstance(v, BaseModel) and type(d) is type(v):
            out += _walk(v, d, path + ".")
            continue
        groups = isinstance(v, (list, tuple)) and v and all(isinstance(x, BaseModel) for x in v)
        if groups and isinstance(d, (list, tuple)) and len(d) == len(v) and all(
                type(a) is type(b) for a, b in zip(v, d, strict=True)):
            for k, (a, b) in enumerate(zip(v, d, strict=True)):
                out += _walk(a, b, f"{path}[{k}].")
            continue
        if d is NO_DEFAULT or _plain(v) != _plain(d):
            out.append(SettingChange(path, _plain(v), d if d is NO_DEFAULT else _plain(d), field_unit(cls, name),
                                     info.description or ""))
    return out


def settings_changes(settings: BaseModel, default: BaseModel | None = None) -> list[SettingChange]:
    """The settings of a run that differ from the defaults (module doc), in declaration order.

    Parameters
    ----------
    settings : pydantic.BaseModel
        The run's settings tree.
    default : pydantic.BaseModel, optional
        What to compare with; default: :func:`default_settings` of the same class (else each field's declared
        default).

    Returns
    -------
    list of SettingChange
        One per changed leaf; empty when every setting is at its default.
    """
    if default is None:
        default = default_settings(type(settings), settings)
    if default is not None and type(default) is not type(settings):
        raise TypeError(f"cannot compare {type(settings).__name__} with a {type(default).__name__}")
    return _walk(settings, default, "")
