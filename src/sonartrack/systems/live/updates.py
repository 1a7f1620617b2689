"""The live chain's display updates: JSON-able dicts with a ``type`` (the contract of /work/team/LIVE.md).

Numbers are lists of float, angles in degrees, times in seconds since the stream's start (``t_s``). The target rows
come from the same columns as targets.csv (systems/passive/tables.py): each target's batch ML solution at its last
time, blank where the range is not determined (the reason said instead), with its 95 % position ellipse.
"""

from __future__ import annotations

import math

import numpy as np

#: chi-square quantile of 2 degrees of freedom at 95 %: the ellipse x^T P^-1 x = this holds 95 % of the position
CHI2_2DOF_95 = 5.991464547107979
#: points of a drawn ellipse
ELLIPSE_POINTS = 36


def _num(x) -> float | None:
    """A JSON number, or None for NaN / inf."""
    x = float(x)
    return x if math.isfinite(x) else None


def btr_update(t_s: float, cone_deg: np.ndarray, level: np.ndarray) -> dict:
    """One bearing-time row: the window's normalised level z per beam."""
    return {"type": "btr", "t_s": float(t_s), "cone_deg": [float(c) for c in cone_deg],
            "level_db": [float(v) for v in np.asarray(level, float)]}


def tracks_update(t_s: float, rows: dict) -> dict:
    """The tracker's live tracks after a scan."""
    return {"type": "tracks", "t_s": float(t_s),
            "tracks": [{"id": int(i), "cone_deg": float(c), "status": "confirmed" if ok else "tentative"}
                       for i, c, ok in zip(rows["track_id"], rows["bearing_deg"], rows["confirmed"], strict=True)]}


def lofar_update(track_id: int, t_s: float, freq_hz: np.ndarray, power: np.ndarray) -> dict:
    """One LOFAR row of a track's beam: the period's power in dB (re the input units squared per Hz)."""
    level = 10.0 * np.log10(np.maximum(np.asarray(power, float), 1e-300))
    return {"type": "lofar", "track": int(track_id), "t_s": float(t_s), "freq_hz": [float(f) for f in freq_hz],
            "level_db": [float(v) for v in level]}


def ellipse_points(x_m: float, y_m: float, cov: np.ndarray, points: int = ELLIPSE_POINTS) -> list[list[float]]:
    """The 95 % ellipse of a position estimate: x + L u sqrt(chi2) on the unit circle, L L^T = cov."""
    cov = np.asarray(cov, float)
    if not np.all(np.isfinite(cov)):
        return []
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    a = np.linspace(0.0, 2.0 * np.pi, points, endpoint=False)
    circle = np.stack([np.cos(a), np.sin(a)])
    xy = (v * np.sqrt(np.maximum(w, 0.0) * CHI2_2DOF_95)) @ circle
    return [[float(x_m + dx), float(y_m + dy)] for dx, dy in xy.T]


def target_row(tg, cols: dict, last: int) -> dict:
    """One target's row: its batch ML (targets.csv's columns ``cols``, row ``last``) with ellipse, mirror, legs."""
    sol = tg.ml.solution
    determined = bool(cols["range_determined"][last])
    x, y = float(cols["x_m"][last]), float(cols["y_m"][last])
    cov = np.asarray(sol.covariance, float)[-1, :2, :2]
    mirror = None
    if tg.mirror_ml is not None and len(tg.mirror_ml.solution.time_s):
        mx, my = np.asarray(tg.mirror_ml.solution.state, float)[-1, :2]
        mirror = {"x_m": float(mx), "y_m": float(my)}
    legs = []
    if tg.legs is not None and tg.legs.fit is not None:
        legs = [{"course_deg": _num(leg.course_deg), "speed_kn": _num(leg.speed_kn)} for leg in tg.legs.fit.legs]
    tonal = None if tg.tonal is None else _num(tg.tonal.line_hz)
    reason = None if determined else (str(cols["undetermined_reason"][last]) or "not determined")
    return {"id": int(tg.target_id), "track": int(tg.track.track_id), "side": _side(tg.side.side),
            "bearing_deg": _num(cols["bearing_deg"][last]),
            "range_m": _num(cols["range_m"][last]) if determined else None,
            "range_sd_m": _num(cols["range_std_m"][last]) if determined else None, "reason": reason,
            "tonal_hz": tonal, "course_deg": _num(cols["course_deg"][last]) if determined else None,
            "speed_mps": _num(cols["speed_kn"][last] * 0.514444) if determined else None,
            "x_m": _num(x) if determined else None, "y_m": _num(y) if determined else None,
            "ellipse": ellipse_points(x, y, cov) if determined else [], "mirror": mirror, "legs": legs}


def _side(side: str) -> str:
    return side if side in ("starboard", "port") else "undecided"


def targets_update(t_s: float, result) -> dict:
    """The targets of a chain result (systems/passive/chain.py PassiveResult)."""
    from sonartrack.tma.solution_table import solution_columns

    rows = []
    for tg in result.targets:
        cols = solution_columns(tg.ml.solution, tg.ml.ownship)
        if len(cols["time_s"]):
            rows.append(target_row(tg, cols, len(cols["time_s"]) - 1))
    return {"type": "targets", "t_s": float(t_s), "rows": rows}


def ownship_update(t_s: float, nav, coasting: bool, latlon: tuple[float, float] | None = None,
                   array_half_m: float = 20.0) -> dict | None:
    """The ownship and the array at ``t_s`` (None without navigation); ``nav`` "coasting" with a warning during a
    navigation dropout."""
    if nav is None:
        return None
    t = min(float(t_s), float(nav.time_s[-1]))
    x, y = float(np.interp(t, nav.time_s, nav.x_m)), float(np.interp(t, nav.time_s, nav.y_m))
    head = float(np.interp(t, nav.time_s, nav.heading_rad))
    (axy,), ah = nav.array_at(np.array([t]))
    dx, dy = array_half_m * math.sin(float(ah[0])), array_half_m * math.cos(float(ah[0]))
    out = {"type": "ownship", "t_s": float(t_s), "x_m": x, "y_m": y, "heading_deg": math.degrees(head) % 360.0,
           "array": [[float(axy[0] + dx), float(axy[1] + dy)], [float(axy[0] - dx), float(axy[1] - dy)]],
           "lat_deg": None if latlon is None else latlon[0], "lon_deg": None if latlon is None else latlon[1],
           "nav": "coasting" if coasting else "ok"}
    if coasting:
        out["warning"] = "navigation dropout: ownship coasting on its last fix"
    return out
