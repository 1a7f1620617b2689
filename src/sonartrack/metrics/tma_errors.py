"""TMA error measures: position, velocity, course and speed errors against time, RMSE over Monte
Carlo runs, and divergence.

For a target solution x_hat = [x, y, vx, vy] (absolute or observer-relative, the same frame as the
truth x) at times t_k::

    position error   e_p(k) = |p_hat - p|                     (m; the same in either frame)
    velocity error   e_v(k) = |v_hat - v|                     (m/s; the same in either frame once the
                                                               observer's velocity is added back)
    course error     e_c(k) = wrap(course_hat - course)       (rad, course = atan2(vx, vy))
    speed error      e_s(k) = |v_hat| - |v|                   (m/s)
    RMSE(k)          sqrt(mean over runs of e(k)^2)           (NaN entries -- a run that failed -- skipped;
                                                               metrics/statistics.py rmse_over_runs)

A run *diverges* at a checkpoint when its position error exceeds ``rel_threshold`` times the true
range there, or when the filter failed numerically (NaN estimate): a solution off by more than a
quarter of the range (the default) no longer places the target usefully, which is the practical
meaning of divergence in passive TMA (the estimate has left the neighbourhood of the truth and the
filter's covariance no longer says so).
"""

from __future__ import annotations

import warnings

import numpy as np

from sonartrack.core.angles import wrap_angle


def tma_errors(est, truth) -> dict[str, np.ndarray]:
    """Position, velocity, course and speed errors of TMA estimates against the truth (module docstring).

    Both must be in the same frame and hold *absolute* velocities for the course and speed errors.

    Parameters
    ----------
    est : array_like, shape (..., >= 4)
        Estimates [x, y, vx, vy, ...] (m, m/s; x east, y north).
    truth : array_like, shape (..., >= 4)
        True states, same frame and order.

    Returns
    -------
    dict of str to ndarray, each shape (...)
        ``position_m`` |p_hat - p| (m), ``velocity_mps`` |v_hat - v| (m/s), ``course_rad``
        wrap(course_hat - course) (rad, course clockwise from north), ``speed_mps`` |v_hat| - |v| (m/s).
    """
    e = np.asarray(est, dtype=float)
    x = np.asarray(truth, dtype=float)
    dp = e[..., :2] - x[..., :2]
    dv = e[..., 2:4] - x[..., 2:4]
    course_hat = np.arctan2(e[..., 2], e[..., 3])
    course = np.arctan2(x[..., 2], x[..., 3])
    return {
        "position_m": np.hypot(dp[..., 0], dp[..., 1]),
        "velocity_mps": np.hypot(dv[..., 0], dv[..., 1]),
        "course_rad": np.asarray(wrap_angle(course_hat - course)),
        "speed_mps": np.hypot(e[..., 2], e[..., 3]) - np.hypot(x[..., 2], x[..., 3]),
    }


def time_averaged_rmse(errors, start: int = 0, stop: int | None = None) -> float:
    """RMSE over runs (axis 0) *and* the time window [start, stop) (axis 1): ``sqrt(mean of e^2)``.

    NaN entries are skipped, and a window with no value gives NaN (the NaN rule of metrics/statistics.py).

    Parameters
    ----------
    errors : array_like, shape (n_runs, n_times)
        Errors (any unit).
    start : int, default 0
        First time index of the window.
    stop : int, optional
        One past the last time index; None for the end.

    Returns
    -------
    float
        The RMSE, in the unit of ``errors``.
    """
    e = np.asarray(errors, dtype=float)[:, start:stop]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # "mean of empty slice": NaN is the answer
        return float(np.sqrt(np.nanmean(e * e)))


def diverged(position_error_m, true_range_m, rel_threshold: float = 0.25) -> np.ndarray:
    """True where the position error exceeds ``rel_threshold`` x the true range, or is NaN (module docstring).

    Parameters
    ----------
    position_error_m : array_like
        Position errors (m).
    true_range_m : array_like
        True observer-target ranges (m), broadcast with the errors.
    rel_threshold : float, default 0.25
        Error, as a fraction of the range, beyond which a run has diverged.

    Returns
    -------
    ndarray of bool
        Diverged flags.
    """
    e = np.asarray(position_error_m, dtype=float)
    r = np.asarray(true_range_m, dtype=float)
    return ~(e <= rel_threshold * r)
