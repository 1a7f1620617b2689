"""The target solution as a table: position, velocity, course, speed, range and bearing over time, each with
its standard deviation (what ``sonartrack tma`` writes to ``tma_solution.csv`` and prints).

Columns, one row per solution time: ``time_s, x_m, y_m, vx_mps, vy_mps, course_deg, speed_kn, range_m,
bearing_deg``, the standard deviation of each (``*_std`` columns, same unit), ``range_determined`` (False
where the data cannot resolve range: the range, course and speed of that row mean nothing) and
``undetermined_reason`` (why not, tma/verdict.py; empty where determined), from the solution's
covariance by first-order propagation; range and bearing are from the ownship to the target; courses and
bearings in degrees clockwise from north, 0..360.

An IMM solution (imm-ekf, imm-mgekf) appends, after those: ``mode_prob_<name>`` per mode of its bank in the
bank's order (``cv`` for the quietest mode, ``q<intensity>`` for the others, e.g. ``mode_prob_cv,
mode_prob_q0.001, mode_prob_q0.1``), ``manoeuvre_prob`` (the manoeuvre modes' probability together: the modes
whose intensity is at least ``imm.manoeuvre_q_min``) and ``manoeuvre`` (True where ``manoeuvre_prob`` exceeds
``imm.manoeuvre_level``). Other methods have no mode, so no such column: no number where there is none.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.units import KNOT_MPS
from sonartrack.tma.records import OwnshipTrack, TmaSolution


def _propagated_std(J, P_block) -> np.ndarray:
    """sqrt(J P J^T) row by row: the first-order standard deviation of a scalar function with gradient J."""
    return np.sqrt(np.maximum(np.einsum("ni,nij,nj->n", J, P_block, J), 0.0))


def solution_columns(solution: TmaSolution, ownship: OwnshipTrack) -> dict[str, np.ndarray]:
    """The solution table's columns (module docstring), standard deviations by first-order propagation:

        course = atan2(vx, vy):  J = [vy, -vx] / s^2 on (vx, vy);   speed s = |v|:  J = [vx, vy] / s
        bearing = atan2(dx, dy): J = [dy, -dx] / r^2 on (x, y);     range r = |d|:  J = [dx, dy] / r

    with d = target - ownship position. A course is undefined at zero speed: its std saturates at 180 deg.

    Parameters
    ----------
    solution : TmaSolution
        Absolute states [x, y, vx, vy] (m, m/s) and covariances over time.
    ownship : OwnshipTrack
        Ownship positions (m; x east, y north).

    Returns
    -------
    dict of str to ndarray, each shape (n,)
        time_s, x_m, y_m, vx_mps, vy_mps, course_deg and bearing_deg (0..360, clockwise from north), speed_kn,
        range_m, their standard deviations (``*_std_*``), range_determined and undetermined_reason (str); then an
        IMM's mode columns (:func:`mode_columns`).
    """
    t = np.asarray(solution.time_s, float)
    X = np.asarray(solution.state, float)
    P = np.asarray(solution.covariance, float)
    own = ownship.position_at(t)
    dx, dy = X[:, 0] - own[:, 0], X[:, 1] - own[:, 1]
    vx, vy = X[:, 2], X[:, 3]
    r = np.hypot(dx, dy)
    s = np.hypot(vx, vy)
    P_pos, P_vel = P[:, :2, :2], P[:, 2:4, 2:4]
    with np.errstate(invalid="ignore", divide="ignore"):
        s_safe = np.where(s > 0, s, np.nan)[:, None]
        r_safe = np.where(r > 0, r, np.nan)[:, None]
        course_std = _propagated_std(np.stack([vy, -vx], -1) / s_safe**2, P_vel)
        speed_std = _propagated_std(np.stack([vx, vy], -1) / s_safe, P_vel)
        bearing_std = _propagated_std(np.stack([dy, -dx], -1) / r_safe**2, P_pos)
        range_std = _propagated_std(np.stack([dx, dy], -1) / r_safe, P_pos)
    sd = np.sqrt(np.maximum(np.einsum("nii->ni", P), 0.0))
    return {"time_s": t, "x_m": X[:, 0], "y_m": X[:, 1], "vx_mps": vx, "vy_mps": vy,
            "course_deg": np.rad2deg(np.arctan2(vx, vy)) % 360.0, "speed_kn": s / KNOT_MPS, "range_m": r,
            "bearing_deg": np.rad2deg(np.arctan2(dx, dy)) % 360.0,
            "x_std_m": sd[:, 0], "y_std_m": sd[:, 1], "vx_std_mps": sd[:, 2], "vy_std_mps": sd[:, 3],
            "course_std_deg": np.minimum(np.rad2deg(np.nan_to_num(course_std, nan=np.pi)), 180.0),
            "speed_std_kn": speed_std / KNOT_MPS, "range_std_m": range_std, "bearing_std_deg": np.rad2deg(bearing_std),
            "range_determined": solution.range_flags(), "undetermined_reason": solution.reasons(),
            **mode_columns(solution)}


def mode_columns(solution: TmaSolution) -> dict[str, np.ndarray]:
    """The IMM columns of the table (module docstring); none when the solution has no modes.

    Parameters
    ----------
    solution : TmaSolution
        A solution, with ``modes`` set by an IMM.

    Returns
    -------
    dict of str to ndarray, each shape (n,)
        ``mode_prob_<name>`` per mode, ``manoeuvre_prob`` and ``manoeuvre`` (bool); empty without modes.
    """
    modes = solution.modes
    if modes is None:
        return {}
    prob = np.asarray(modes.prob, float)
    cols = {f"mode_prob_{name}": prob[:, j] for j, name in enumerate(modes.names)}
    man = modes.manoeuvre_prob()
    return {**cols, "manoeuvre_prob": man, "manoeuvre": np.nan_to_num(man, nan=0.0) > modes.level}
