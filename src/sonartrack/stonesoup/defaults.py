"""The defaults of sonartrack's Stone Soup components, read from sonartrack's settings declarations.

A Stone Soup ``Property(default=...)`` is fixed when its class is created. Each default that has a
declaration in sonartrack (the tracker's P_D, gate probability, existence chain, initial existence,
confirmation and deletion thresholds: tracking/settings.py, ``PositionTrackerSettings``) is taken from
that declaration through :func:`tracker_default` rather than written again, so that the Stone Soup
component and sonartrack's own tracker start from the same values, and a changed declaration changes both.
"""

from __future__ import annotations

from typing import Any

from sonartrack.core.settings import Settings
from sonartrack.tracking.settings import PositionTrackerSettings


def declared_default(settings_cls: type[Settings], name: str) -> Any:
    """The default declared for field ``name`` of a settings class.

    Parameters
    ----------
    settings_cls : type[Settings]
        The settings class that declares the field (e.g. ``PositionTrackerSettings``).
    name : str
        Field name.

    Returns
    -------
    Any
        The declared default (a default factory is called), in the field's unit.
    """
    return settings_cls.model_fields[name].get_default(call_default_factory=True)


def tracker_default(name: str) -> Any:
    """The default of field ``name`` of ``PositionTrackerSettings`` (the IPDA / IMM-IPDA tracker, paper P4).

    Parameters
    ----------
    name : str
        Field name, e.g. ``"pd"``, ``"initial_existence"``.

    Returns
    -------
    Any
        The declared default, in the field's unit (see its declaration).
    """
    return declared_default(PositionTrackerSettings, name)
