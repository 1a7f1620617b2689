"""The advise system's files: target solutions or bearings, and the ownship's navigation, in; ``advice.csv`` out.

A target is either

* the last row of a ``tma_solution.csv`` written by ``sonartrack tma`` (tma/solution_table.py's columns). That
  table holds standard deviations, not the full covariance, so the covariance is rebuilt from them: the position
  block from ``range_std_m`` along the line of sight and ``range_m * bearing_std_deg`` across it, the velocity
  block from ``speed_std_kn`` along the course and ``speed * course_std_deg`` across it, each ellipse taken as
  aligned with those axes and position and velocity errors as uncorrelated (an approximation stated in a warning:
  a bearings file gives the full covariance); a last row whose range is not determined is refused;
* a bearings file (``time_s, bearing_deg``, io/tma_files.py) solved here by the constant-velocity batch ML.

The ownship file is ``sonartrack tma``'s (``time_s, x_m, y_m``). ``advice.csv`` holds one row per candidate leg:
``course_deg, turn_delay_s, turn_time_s, range_sd_m`` (the objective), ``range_sd_m_<k>`` per target, and
``advised`` / ``alternative`` flags, written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.core.units import KNOT_MPS

from .run import AdviceResult, TargetNow, target_from_bearings

CSV_NAME = "advice.csv"
PNG_NAME = "advice.png"
SOLUTION_COLUMNS = ["time_s", "x_m", "y_m", "vx_mps", "vy_mps", "range_m", "bearing_deg", "range_std_m",
                    "bearing_std_deg", "speed_std_kn", "course_std_deg"]
#: the warning every target read from a solution table carries
TABLE_COVARIANCE_NOTE = ("{path}: tma_solution.csv holds standard deviations, not the full covariance: the advice "
                         "takes position and velocity errors as uncorrelated (give --bearings for the full covariance)")


def covariance_from_sds(state, range_m: float, bearing_rad: float, range_sd_m: float, bearing_sd_rad: float,
                        speed_sd_mps: float, course_sd_rad: float) -> np.ndarray:
    """A 4 x 4 covariance rebuilt from the solution table's standard deviations (module doc).

    Parameters
    ----------
    state : array_like, shape (4,)
        [x, y, vx, vy] (m, m/s).
    range_m, bearing_rad : float
        Range (m) and bearing (rad, clockwise from north) from the ownship.
    range_sd_m, bearing_sd_rad, speed_sd_mps, course_sd_rad : float
        Their sds and the speed's and course's.

    Returns
    -------
    ndarray, shape (4, 4)
        Block-diagonal covariance (m^2, m^2/s^2).
    """
    def block(angle, along_sd, across_sd):
        u = np.array([np.sin(angle), np.cos(angle)])
        w = np.array([np.cos(angle), -np.sin(angle)])
        return along_sd**2 * np.outer(u, u) + across_sd**2 * np.outer(w, w)

    vx, vy = float(state[2]), float(state[3])
    P = np.zeros((4, 4))
    P[:2, :2] = block(bearing_rad, range_sd_m, range_m * bearing_sd_rad)
    P[2:, 2:] = block(np.arctan2(vx, vy), speed_sd_mps, np.hypot(vx, vy) * course_sd_rad)
    return P


def read_solution_target(path) -> tuple[TargetNow, str]:
    """The last row of a ``tma_solution.csv`` as a target (module doc), and the approximation's warning.

    Parameters
    ----------
    path : path-like
        The solution table.

    Returns
    -------
    TargetNow, str
        The target at its last time, and the warning line.
    """
    from sonartrack.io.tables import check_columns, numeric_column, read_table

    what = "solution"
    df = read_table(path, what)
    check_columns(df, SOLUTION_COLUMNS, what, path)
    last = df.iloc[[-1]].reset_index(drop=True)
    if "range_determined" in df.columns:
        flag = str(last["range_determined"].iloc[0]).strip().lower()
        reason = str(last.get("undetermined_reason", [""])[0]) if "undetermined_reason" in df.columns else ""
        require(flag not in ("false", "0", "0.0"),
                f"solution file {path}: the last row's range is not determined"
                f"{f' ({reason})' if reason and reason != 'nan' else ''}: no advice can rest on it")
    v = {c: float(numeric_column(last, c, what, path)[0]) for c in SOLUTION_COLUMNS}
    for c in ("range_std_m", "bearing_std_deg", "speed_std_kn", "course_std_deg"):
        require(v[c] > 0, f"solution file {path}: column '{c}' is {v[c]:g} in the last row: a standard deviation "
                          "must be positive")
    require(v["range_m"] > 0, f"solution file {path}: the last row's range_m is {v['range_m']:g}: the target "
                              "must not sit on the ownship")
    X = np.array([v["x_m"], v["y_m"], v["vx_mps"], v["vy_mps"]])
    P = covariance_from_sds(X, v["range_m"], np.radians(v["bearing_deg"]), v["range_std_m"],
                            np.radians(v["bearing_std_deg"]), v["speed_std_kn"] * KNOT_MPS,
                            np.radians(min(v["course_std_deg"], 180.0)))
    return TargetNow(str(path), v["time_s"], X, P), TABLE_COVARIANCE_NOTE.format(path=path)


def read_targets(solutions, bearings, ownship, sigma_bearing_deg: float):
    """The targets of the solution and bearings files, and the median bearing interval (s) of the bearings files.

    Parameters
    ----------
    solutions, bearings : list of path-like
        ``tma_solution.csv`` files and bearings files.
    ownship : OwnshipTrack
        The ownship's navigation (for the bearings' batch ML).
    sigma_bearing_deg : float
        The bearings' sd (deg).

    Returns
    -------
    targets : list of TargetNow
    warnings : list of str
    interval_s : float or None
        None without bearings files.
    """
    from sonartrack.io.tma_files import read_bearings

    targets, warnings, intervals = [], [], []
    for p in solutions:
        tg, note = read_solution_target(p)
        targets.append(tg)
        warnings.append(note)
    for p in bearings:
        rec = read_bearings(p)
        intervals.append(float(np.median(np.diff(rec.time_s))) if len(rec.time_s) > 1 else np.nan)
        targets.append(target_from_bearings(rec, ownship, np.radians(sigma_bearing_deg), f"bearings file {p}"))
    if not targets:
        raise InputError("give at least one target: --solution tma_solution.csv (of sonartrack tma) or --bearings "
                         "FILE, and --ownship FILE")
    return targets, warnings, (float(np.nanmedian(intervals)) if intervals else None)


def write_advice_csv(result: AdviceResult, out) -> Path:
    """Write every candidate leg's predicted range sd of ``result`` (what
    :func:`~sonartrack.systems.advise.run.run_advice` returned) as ``advice.csv`` in the output folder ``out``,
    atomically (module doc); returns the file's path."""
    import pandas as pd

    from sonartrack.io.atomic import write_csv

    a = result.advice
    cols = {"course_deg": a.course_deg, "turn_delay_s": a.turn_delay_s, "turn_time_s": a.time_s + a.turn_delay_s,
            "range_sd_m": a.range_sd_m}
    for k in range(a.range_sd_per_target_m.shape[1]):
        cols[f"range_sd_m_{k + 1}"] = a.range_sd_per_target_m[:, k]
    flags = np.zeros(len(a.course_deg), bool)
    flags[a.alternatives] = True
    cols["advised"] = np.arange(len(a.course_deg)) == a.best
    cols["alternative"] = flags
    p = Path(out) / CSV_NAME
    p.parent.mkdir(parents=True, exist_ok=True)
    return write_csv(pd.DataFrame(cols), p, float_format="%.6g", index=False)
