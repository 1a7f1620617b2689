"""The track system's settings (``sonartrack track --config`` TOML): the tracker's, nested, plus the input's.

Two trees, one per input: :class:`ContactsTrackSettings` (contacts, Cartesian or raw bistatic) and
:class:`PeaksTrackSettings` (bearing peaks). The sound speed appears once, in ``[bistatic]``: only raw
bistatic contacts need it.

The tracker settings are the library's own declarations (tracking/settings.py), nested as a
``[tracker]`` table; ``sonartrack track --print-config`` prints the resolved file. Example for
``--contacts``::

    default_sigma_m = 200.0     # only for Cartesian contacts without covariance columns

    [bistatic]                  # only for raw bistatic contacts
    sigma_bearing_deg = 0.5

    [tracker]
    q = [1e-4, 0.05]            # one value: single-model IPDA; several: IMM-IPDA (m^2/s^3)
    pd = 0.8

and for ``--peaks``::

    associator = "jpda_a"

    [tracker]
    q = 0.01
    gate_deg = 10.0
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import model_validator

from sonartrack.core.settings import Settings, setting
from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings


def _tracker_keys_at_top(model_cls, tracker_cls, data):
    """A tracker key given at the top level (the old flat layout) gets a message saying where it goes.

    Parameters
    ----------
    model_cls, tracker_cls : type
        The settings class being validated and its nested tracker settings class.
    data : object
        The raw input of the validation (a dict from TOML, or anything pydantic accepts).

    Returns
    -------
    object
        ``data`` unchanged when no tracker key is at the top level.
    """
    if isinstance(data, dict):
        stray = sorted(k for k in data if k in tracker_cls.model_fields and k not in model_cls.model_fields)
        if stray:
            raise ValueError(f"tracker settings belong in a [tracker] table: move {', '.join(stray)} under [tracker]")
    return data


class BistaticInputErrors(Settings):
    """Input errors of raw bistatic contacts, for their covariance J Sigma J^T (models/bistatic.py; P4's values)."""

    sigma_time_s: float = setting(0.01, "travel-time error", unit="s", ge=0)
    sigma_bearing_deg: float = setting(0.5, "bearing error of the receiving array", unit="deg", gt=0)
    sigma_heading_deg: float = setting(0.0, "array heading error", unit="deg", ge=0)
    sigma_sound_speed_mps: float = setting(7.5, "error of the assumed mean sound speed", unit="m/s", ge=0)
    sigma_position_m: float = setting(30.0, "Tx and Rx position error per axis", unit="m", ge=0)
    sound_speed_mps: float = setting(1500.0, "mean sound speed where the contacts file has no sound_speed_mps",
                                     unit="m/s", ge=1300, le=1700)
    max_range_m: float = setting(100_000.0, "largest target range from the transmitter or the receiver: a travel "
                                 "time whose range sum c t exceeds twice this is refused (milliseconds?)", unit="m",
                                 gt=0, le=1e7)

    def errors(self):
        """The input errors in SI units, as the bistatic measurement model takes them.

        Returns
        -------
        BistaticErrors
            Travel-time (s), bearing and heading (rad), sound-speed (m/s) and position (m) errors.
        """
        from sonartrack.models.bistatic import BistaticErrors

        return BistaticErrors(self.sigma_time_s, float(np.deg2rad(self.sigma_bearing_deg)),
                              float(np.deg2rad(self.sigma_heading_deg)), self.sigma_sound_speed_mps,
                              self.sigma_position_m)


class ContactsTrackSettings(Settings):
    """``sonartrack track --contacts``: the IPDA / IMM-IPDA tracker and the contacts' errors."""

    default_sigma_m: float | None = setting(None, "position error of Cartesian contacts without covariance columns",
                                            unit="m", gt=0)
    bistatic: BistaticInputErrors = setting(default_factory=BistaticInputErrors,
                                            doc="input errors of raw bistatic contacts")
    tracker: PositionTrackerSettings = setting(default_factory=PositionTrackerSettings, doc="the position tracker")

    @model_validator(mode="before")
    @classmethod
    def _flat_layout(cls, data):
        return _tracker_keys_at_top(cls, PositionTrackerSettings, data)


class PeaksTrackSettings(Settings):
    """``sonartrack track --peaks``: the JPDA / JPDA_A bearing tracker with automatic initiation."""

    associator: Literal["jpda", "jpda_a"] = setting("jpda_a", "jpda ignores peak amplitudes; jpda_a weighs them "
                                                              "(with eq. 9 track strengths)", unit="")
    tracker: BearingTrackerSettings = setting(default_factory=BearingTrackerSettings, doc="the bearing tracker")

    @model_validator(mode="before")
    @classmethod
    def _flat_layout(cls, data):
        return _tracker_keys_at_top(cls, BearingTrackerSettings, data)
