"""Hydrophone calibration: recorded samples (volts) to pressure (Pa), and levels in dB re 1 uPa.

A hydrophone of receiving sensitivity S (dB re 1 V/uPa) behind a preamplifier of gain G (dB) gives
10^((S + G) / 20) volts per micropascal, so a recorded voltage v is the pressure

    p = v / 10^((S + G) / 20)  uPa  =  v 1e-6 / 10^((S + G) / 20)  Pa

(the definition of a receiving sensitivity in volts per unit pressure, with levels re 1 uPa as ISO 18405:2017
"Underwater acoustics - Terminology" states them; a gain in dB multiplies the voltage by 10^(G / 20)). A
recorder stores v / V_fs, V_fs being the voltage of its full-scale sample (``full_scale_v``; default 1 V, i.e.
the samples are volts). Levels are
L = 20 log10(p_rms / 1 uPa) dB re 1 uPa. Without a calibration the samples are taken to be pascals already,
as ``sonartrack simulate`` writes them.

File: TOML with ``sensitivity_db``, ``gain_db`` and optional ``full_scale_v``, each one number (every
channel) or a list (one per channel)::

    sensitivity_db = -165.0        # dB re 1 V/uPa
    gain_db = [20.0, 20.0, 26.0]   # dB
    full_scale_v = 2.5             # V at sample value 1.0

or CSV with one row per channel: ``channel, sensitivity_db, gain_db[, full_scale_v]`` (channels 0..N-1, each
once, any order).

Values are checked where physics bounds them: a sensitivity within :data:`SENSITIVITY_RANGE_DB`, a gain within
:data:`GAIN_RANGE_DB`, a full scale within :data:`FULL_SCALE_RANGE_V` (a recorder's input range is 0.1 to 60 V;
1e-6 V allows float files stored in microvolts; 1000 is millivolts given as volts). The levels a calibration
gives are checked against the sea (:func:`level_warnings`): the median broadband level of a recording lies
within :data:`PLAUSIBLE_LEVEL_DB` or the calibration (or its absence) is named as the likely cause.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require

#: reference pressure of underwater levels (Pa)
P_REF_PA = 1e-6
#: plausible hydrophone sensitivities (dB re 1 V/uPa); a value above is likely dB re 1 V/Pa (120 dB higher)
SENSITIVITY_RANGE_DB = (-250.0, -100.0)
GAIN_RANGE_DB = (-60.0, 100.0)
#: plausible voltages of sample value 1.0 (V): a recorder's full scale (0.1-60 V), or 1e-3 / 1e-6 for float
#: samples stored in mV / uV
FULL_SCALE_RANGE_V = (1e-6, 100.0)
#: plausible median broadband level of a recording at sea (dB re 1 uPa). Floor: the quietest sea (Wenz 1962's
#: lower limit, thermal noise above ~50 kHz: about 20 dB re 1 uPa^2/Hz at its lowest) over the >= 100 Hz of any
#: recording's band is above 40 dB; 20 dB leaves 20 dB for a band-limited hydrophone. Ceiling: a median of 180 dB
#: needs the loudest ships (190 dB re 1 uPa m broadband; McKenna et al. 2012, JASA 131: 177-188 dB for container
#: ships) within 3 m of the hydrophone for half the recording (20 log10 r spreading); pile driving and airguns
#: are loud in pulses, not in the median window
PLAUSIBLE_LEVEL_DB = (20.0, 180.0)
_KEYS = ("sensitivity_db", "gain_db", "full_scale_v")


@dataclass(frozen=True, slots=True)
class Calibration:
    """Per-channel sensitivity (dB re 1 V/uPa), gain (dB) and full-scale voltage (V); arrays of one entry apply
    to every channel. :meth:`identity` is the default: the samples are pascals."""

    sensitivity_db: np.ndarray
    gain_db: np.ndarray
    full_scale_v: np.ndarray
    is_identity: bool = False

    @classmethod
    def identity(cls) -> Calibration:
        """Samples already in pascals (p = x).

        Returns
        -------
        Calibration
            S = -120 dB re 1 V/uPa, G = 0 dB, V_fs = 1 V (1 Pa per unit), flagged ``is_identity``.
        """
        return cls(np.array([-120.0]), np.array([0.0]), np.array([1.0]), True)

    @property
    def channels(self) -> int | None:
        """Channels the file describes; None when one value applies to every channel."""
        n = max(a.size for a in (self.sensitivity_db, self.gain_db, self.full_scale_v))
        return None if n == 1 else n

    def pa_per_unit(self, channels: int) -> np.ndarray:
        """Pascals per sample unit, (channels,): V_fs 1e-6 / 10^((S + G) / 20) (module doc).

        Parameters
        ----------
        channels : int
            Channels of the recording.

        Returns
        -------
        ndarray
            One factor per channel (Pa).
        """
        require(self.channels in (None, channels), f"the calibration gives {self.channels} channels but the "
                                                   f"recording has {channels}: give one value per channel, or one "
                                                   "for all")
        if self.is_identity:
            return np.ones(channels)
        gain = 10.0 ** ((self.sensitivity_db + self.gain_db) / 20.0)
        return np.broadcast_to(self.full_scale_v * P_REF_PA / gain, (channels,)).copy()

    def to_pascals(self, block: np.ndarray) -> np.ndarray:
        """A (channels, m) block of samples as pressure (Pa), a new array.

        Parameters
        ----------
        block : ndarray, shape (channels, m)
            Recorded samples (full-scale units).

        Returns
        -------
        ndarray, shape (channels, m), float64
            Pressure (Pa): each channel times its :meth:`pa_per_unit`.
        """
        x = np.asarray(block, dtype=np.float64)
        return x * self.pa_per_unit(x.shape[0])[:, None]


def level_db_re_1upa(pressure_pa) -> np.ndarray:
    """20 log10(|p| / 1 uPa): the level (dB re 1 uPa) of a pressure amplitude or rms (Pa); -inf at 0.

    Parameters
    ----------
    pressure_pa : float or array_like
        Pressure amplitude or rms (Pa).

    Returns
    -------
    ndarray
        Level (dB re 1 uPa), shape of the input.
    """
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(np.abs(np.asarray(pressure_pa, dtype=float)) / P_REF_PA)


def rms_level_db(block_pa: np.ndarray) -> np.ndarray:
    """Per-channel rms level (dB re 1 uPa) of a (channels, m) block of pressure (Pa).

    Parameters
    ----------
    block_pa : ndarray, shape (channels, m)
        Pressure (Pa).

    Returns
    -------
    ndarray, shape (channels,)
        20 log10(p_rms / 1 uPa) (dB re 1 uPa).
    """
    x = np.asarray(block_pa, dtype=float)
    return level_db_re_1upa(np.sqrt(np.mean(x * x, axis=-1)))


def _values(raw, key: str, path) -> np.ndarray:
    v = np.atleast_1d(np.asarray(raw, dtype=object))
    require(v.ndim == 1 and v.size >= 1 and all(isinstance(a, int | float) and not isinstance(a, bool) for a in v),
            f"calibration {path}: {key} must be a number or a list of numbers, got {raw!r}")
    out = v.astype(float)
    require(np.isfinite(out).all(), f"calibration {path}: {key} holds NaN/inf: give finite numbers")
    return out


def _checked(s: np.ndarray, g: np.ndarray, v: np.ndarray, path) -> Calibration:
    lo, hi = SENSITIVITY_RANGE_DB
    bad = s[(s < lo) | (s > hi)]
    require(bad.size == 0, f"calibration {path}: sensitivity {bad[:1].sum():g} dB lies outside {lo:g}..{hi:g} dB re "
                           "1 V/uPa (a value near -50 is dB re 1 V/Pa: subtract 120)")
    glo, ghi = GAIN_RANGE_DB
    bad = g[(g < glo) | (g > ghi)]
    require(bad.size == 0, f"calibration {path}: gain {bad[:1].sum():g} dB lies outside {glo:g}..{ghi:g} dB: give "
                           "the preamplifier gain in dB")
    vlo, vhi = FULL_SCALE_RANGE_V
    bad = v[(v < vlo) | (v > vhi)]
    require(bad.size == 0, f"calibration {path}: full_scale_v {bad[:1].sum():g} V lies outside {vlo:g}..{vhi:g} V "
                           "(the voltage of sample value 1.0: a recorder's full scale is 0.1 to 60 V; a value near "
                           "1000 is millivolts: give volts, 1000 mV = 1 V)")
    sizes = {a.size for a in (s, g, v)} - {1}
    require(len(sizes) <= 1, f"calibration {path}: lists of different lengths {sorted(sizes)}: give one value per "
                             "channel, or one number for all")
    return Calibration(s, g, v)


def _read_toml(p: Path) -> Calibration:
    from sonartrack.io.toml import load

    data = load(p)
    unknown = sorted(set(data) - set(_KEYS))
    require(not unknown, f"calibration {p}: unknown key(s) {unknown}: use {', '.join(_KEYS)}")
    require("sensitivity_db" in data, f"calibration {p} has no sensitivity_db (dB re 1 V/uPa): add it")
    return _checked(_values(data["sensitivity_db"], "sensitivity_db", p), _values(data.get("gain_db", 0.0),
                    "gain_db", p), _values(data.get("full_scale_v", 1.0), "full_scale_v", p), p)


def _read_csv(p: Path) -> Calibration:
    with open(p, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    require(rows and {"channel", "sensitivity_db"} <= set(rows[0]),
            f"calibration {p} needs the columns channel, sensitivity_db[, gain_db, full_scale_v] and a row per channel")
    try:
        table = {int(r["channel"]): [float(r["sensitivity_db"]), float(r.get("gain_db") or 0.0),
                                     float(r.get("full_scale_v") or 1.0)] for r in rows}
    except (TypeError, ValueError) as e:
        raise InputError(f"calibration {p}: a cell is not a number ({e}): give numbers in every row") from None
    require(sorted(table) == list(range(len(rows))), f"calibration {p}: channels {sorted(table)} must be 0..N-1, "
                                                     "each once")
    cols = np.array([table[k] for k in range(len(rows))]).T
    require(np.isfinite(cols).all(), f"calibration {p} holds NaN/inf: give finite numbers")
    return _checked(cols[0], cols[1], cols[2], p)


def read_calibration(path) -> Calibration:
    """Read a calibration file (module doc): .toml or .csv.

    Parameters
    ----------
    path : str or Path or None
        The file; None gives :meth:`Calibration.identity` (samples are pascals).

    Returns
    -------
    Calibration
        Sensitivities, gains and full-scale voltages, checked.
    """
    if path is None:
        return Calibration.identity()
    p = Path(path)
    require(p.is_file(), f"calibration file not found: {p}: give a .toml or .csv file (module sonartrack.io."
                         "calibration describes both)")
    suffix = p.suffix.lower()
    require(suffix in (".toml", ".csv"), f"calibration {p}: give a .toml or .csv file, not {suffix or 'no suffix'}")
    return _read_toml(p) if suffix == ".toml" else _read_csv(p)


def sensitivity_db_re_v_per_upa(v_per_pa: float) -> float:
    """Sensitivity in dB re 1 V/uPa of a hydrophone giving ``v_per_pa`` volts per pascal (20 log10(v / 1e6)).

    Parameters
    ----------
    v_per_pa : float
        Sensitivity (V/Pa), > 0.

    Returns
    -------
    float
        Sensitivity (dB re 1 V/uPa).
    """
    require(v_per_pa > 0, f"a sensitivity must be > 0 V/Pa, got {v_per_pa:g}")
    return 20.0 * math.log10(v_per_pa * P_REF_PA)


def level_warnings(level_db, calibration: Calibration, name: str) -> list[str]:
    """A warning when the median broadband level of a recording lies outside any sea (:data:`PLAUSIBLE_LEVEL_DB`),
    naming the likely cause: the calibration, or its absence (samples taken as pascals).

    Parameters
    ----------
    level_db : array_like
        Broadband level of each window (dB re 1 uPa); NaN (a gap) and -inf (digital silence) are left out.
    calibration : Calibration
        The calibration the levels were computed with.
    name : str
        The recording's name in the line.

    Returns
    -------
    list of str
        One ``warning: ...`` line, or none when the median is plausible or no window has a finite level.
    """
    level = np.asarray(level_db, dtype=float)
    level = level[np.isfinite(level)]
    lo, hi = PLAUSIBLE_LEVEL_DB
    if level.size == 0 or lo <= (median := float(np.median(level))) <= hi:
        return []
    high = median > hi
    where = (f"above any sea (> {hi:g} dB: the loudest ship within 3 m)" if high else
             f"below any sea (< {lo:g} dB: quieter than the quietest ocean)")
    if calibration.is_identity:
        cause = ("the samples are taken as pascals because no calibration was given: give the recorder's "
                 "calibration (--calibration: sensitivity_db, gain_db, full_scale_v)")
    elif high:
        cause = ("check the calibration: full_scale_v in millivolts given as volts (+60 dB)? a sensitivity too low "
                 "(more negative) or a preamplifier gain left out?")
    else:
        cause = ("check the calibration: a full_scale_v too small (it is the voltage at sample value 1.0)? a gain "
                 "counted twice (in sensitivity_db and in gain_db), or a sensitivity too high?")
    return [f"warning: {name}: the median broadband level is {median:.1f} dB re 1 uPa, {where}; the levels "
            f"(levels.csv) are not to be believed: {cause}"]
