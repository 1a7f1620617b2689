"""Passive sonar performance against range at one receiver depth: TL, SNR, detection ranges.

Along the TL field of a source at depth zs (:mod:`sonartrack.acoustics.transmission_loss`), at the
receiver depth zr:

    TL_avg(r) = -10 log10( mean over |r' - r| < w/2 of 10^(-TL(r', zr)/10) )   (incoherent average, w = 1 km)
    SNR(r)    = SL - TL_avg(r) + DI - NL                                      (Urick ch. 2; paper P3, eq. 30)

The detection ranges are the intervals where SNR > threshold; the convergence zones those of them
that begin after a shadow of at least 2 km (:mod:`sonartrack.acoustics.sonar_equation`). This is
what ``sonartrack tl`` computes; :class:`TLSettings` is its one declaration of settings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydantic import field_validator, model_validator

from sonartrack.acoustics.environment import Environment
from sonartrack.acoustics.sonar_equation import DI_DB, NL_DB, SL_DB, convergence_zones, detection_ranges, passive_snr_db
from sonartrack.acoustics.transmission_loss import FieldStore, TLField, smooth_tl, tl_field
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting
from sonartrack.core.units import KM_M

#: largest maximum range accepted (km); a larger value is taken for metres given by mistake
MAX_RANGE_KM = 500.0


class TLSettings(Settings):
    """Settings of a TL / detection-range computation (``sonartrack tl``; paper P3's values by default)."""

    freq_hz: float = setting(200.0, "frequency of the tonal (RAM's grid grows as f^2: above 5 kHz it does not fit "
                             "in memory at useful ranges)", unit="Hz", gt=0, le=5000)
    source_depth_m: float = setting(50.0, "source (target) depth, inside the water column", unit="m")
    receiver_depth_m: float | None = setting(None, "receiver (array) depth; default: the source depth", unit="m")
    rmax_km: float = setting(50.0, "maximum range of the field", unit="km", gt=0)
    sl_db: float = setting(SL_DB, "source level", unit="dB", ge=0, le=300)
    nl_db: float = setting(NL_DB, "noise level", unit="dB", ge=-100, le=300)
    di_db: float = setting(DI_DB, "directivity index of the array", unit="dB", ge=-50, le=100)
    threshold_db: float = setting(0.0, "detection threshold on the SNR", unit="dB", ge=-200, le=200)
    average_m: float = setting(1000.0, "range window of the incoherent TL average (up to the maximum range)", unit="m",
                             gt=0)

    @field_validator("rmax_km")
    @classmethod
    def _kilometres(cls, v: float) -> float:
        # a range given in metres is the usual slip: say so rather than compute an 8000 km field
        if v > MAX_RANGE_KM:
            raise ValueError(f"{v:g} km: the maximum range is in kilometres, not metres")
        return v

    @model_validator(mode="after")
    def _average_within_field(self):
        if self.average_m > self.rmax_km * KM_M:
            raise ValueError(f"average_m = {self.average_m:g} m is longer than the field's maximum range rmax_km = "
                             f"{self.rmax_km:g} km: shorten average_m (it is in metres) or lengthen rmax_km")
        return self

    @property
    def zr_m(self) -> float:
        """The receiver depth used (the source depth unless given)."""
        return self.source_depth_m if self.receiver_depth_m is None else self.receiver_depth_m


@dataclass(frozen=True, slots=True)
class RangePerformance:
    """TL and SNR against range at one receiver depth, with the intervals where SNR > threshold."""

    ranges_m: np.ndarray
    tl_db: np.ndarray
    tl_avg_db: np.ndarray
    snr_db: np.ndarray
    detection_ranges_m: list[tuple[float, float]]
    convergence_zones_m: list[tuple[float, float]]
    receiver_depth_m: float
    threshold_db: float

    def columns(self) -> dict[str, np.ndarray]:
        """The table ``range_m, tl_db, tl_avg_db, snr_db`` as named columns.

        Returns
        -------
        dict of str to ndarray
            Range (m), TL, averaged TL and SNR (dB).
        """
        return {"range_m": self.ranges_m, "tl_db": self.tl_db, "tl_avg_db": self.tl_avg_db, "snr_db": self.snr_db}


def range_performance(field: TLField, receiver_depth_m: float, *, sl_db: float = SL_DB, di_db: float = DI_DB,
                      nl_db: float = NL_DB, threshold_db: float = 0.0, average_m: float = 1000.0) -> RangePerformance:
    """TL, averaged TL, SNR and detection ranges along ``field`` at ``receiver_depth_m`` (module docstring).

    Parameters
    ----------
    field : TLField
        TL field of the source.
    receiver_depth_m : float
        Receiver depth (m), inside the water column.
    sl_db : float, default 140.0
        Source level (dB; paper P3).
    di_db : float, default 12.5
        Directivity index (dB).
    nl_db : float, default 73.0
        Noise level (dB).
    threshold_db : float, default 0.0
        Detection threshold on the SNR (dB).
    average_m : float, default 1000.0
        Incoherent range-averaging window (m).

    Returns
    -------
    RangePerformance
        The curves and the detection intervals and convergence zones (m).

    Raises
    ------
    InputError
        If the receiver depth is outside the water column.
    """
    water_m = float(field.depths_m[-1])
    require(0 < receiver_depth_m < water_m,
            f"receiver depth {receiver_depth_m:g} m must lie inside the water column (0..{water_m:g} m)")
    line = field.at_depth(receiver_depth_m)
    avg = smooth_tl(field.ranges_m, line, average_m)
    snr = passive_snr_db(sl_db, avg, di_db, nl_db)
    return RangePerformance(field.ranges_m, line, avg, snr, detection_ranges(field.ranges_m, snr, threshold_db),
                            convergence_zones(field.ranges_m, snr, threshold_db), float(receiver_depth_m),
                            float(threshold_db))


def tl_performance(env: Environment, settings: TLSettings,
                   store: FieldStore | None = None) -> tuple[TLField, RangePerformance]:
    """The TL field of ``env`` and the performance against range it gives, for the settings of ``sonartrack tl``.

    Parameters
    ----------
    env : Environment
        The environment.
    settings : TLSettings
        Frequency, depths, maximum range, sonar-equation terms, threshold and averaging window.
    store : FieldStore, optional
        Cache of fields (see :func:`~sonartrack.acoustics.transmission_loss.tl_field`).

    Returns
    -------
    field : TLField
        The TL field.
    performance : RangePerformance
        TL, SNR and detection ranges at the receiver depth.

    Raises
    ------
    InputError
        If the receiver depth is outside the water column (or as ``tl_field``).
    """
    s = settings
    require(0 < s.zr_m < env.water_depth_m,
            f"receiver depth {s.zr_m:g} m must lie inside the water column (0..{env.water_depth_m:g} m)")
    field = tl_field(env, s.freq_hz, s.source_depth_m, rmax_m=s.rmax_km * KM_M, store=store)
    perf = range_performance(field, s.zr_m, sl_db=s.sl_db, di_db=s.di_db, nl_db=s.nl_db, threshold_db=s.threshold_db,
                             average_m=s.average_m)
    return field, perf


def _intervals_km(intervals: list[tuple[float, float]], n: int) -> str:
    return ", ".join(f"{a / KM_M:.1f}-{b / KM_M:.1f} km" for a, b in intervals[:n])


def performance_summary(env_name: str, settings: TLSettings, perf: RangePerformance) -> str:
    """One line: the case and where the SNR exceeds the threshold (first six intervals, first four CZs).

    Parameters
    ----------
    env_name : str
        Environment name.
    settings : TLSettings
        The settings used.
    perf : RangePerformance
        The result.

    Returns
    -------
    str
        The summary line (ranges in km).
    """
    s = settings
    det = _intervals_km(perf.detection_ranges_m, 6) or "none"
    cz = f"; convergence zones at {_intervals_km(perf.convergence_zones_m, 4)}" if perf.convergence_zones_m else ""
    return (f"tl {env_name}: {s.freq_hz:g} Hz, source {s.source_depth_m:g} m, receiver {s.zr_m:g} m, "
            f"to {s.rmax_km:g} km; SNR > {s.threshold_db:g} dB (SL {s.sl_db:g}, DI {s.di_db:g}, NL {s.nl_db:g}) "
            f"at {det}{cz}")
