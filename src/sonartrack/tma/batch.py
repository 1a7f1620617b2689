"""Batch TMA on a user's record: bearings-only ML, or EM/MAP with SNR and a propagation model (paper P3).

:func:`solve_batch` is what ``sonartrack tma --method ml|em-map`` calls. For ``em-map`` the mean SNR
against range is xi_bar(r) = SL - TL(r) + DI - NL with TL from RAM (``acoustics/``) for the named
environment (or a profile file), source and receiver at ``depth_m``, averaged over 1 km.
"""

from __future__ import annotations

import warnings

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, check_observability, ml_bearings_only
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution

#: TL range average (m): a passive sonar integrates over the interference pattern
TL_AVERAGE_M = 1_000.0


class UnobservableWarning(UserWarning):
    """Range is not observable from bearings alone (the ownship has not maneuvered)."""


def snr_model(env_name: str, sl_db: float, freq_hz: float, depth_m: float | None, r_max_m: float,
              nl_db: float | None = None, di_db: float | None = None):
    """xi_bar(r) for an environment name or profile path: (callable, environment, depth used)."""
    from pathlib import Path

    from sonartrack.acoustics.environment import load_environment, read_profile
    from sonartrack.acoustics.sonar_equation import DI_DB, NL_DB, passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field

    env = read_profile(env_name) if Path(env_name).suffix.lower() in (".toml", ".csv") else load_environment(env_name)
    z = float(depth_m) if depth_m is not None else min(50.0, env.water_depth_m / 2.0)
    require(0 < z < env.water_depth_m, f"depth {z:g} m is outside the water column of {env.name} (0..{env.water_depth_m:g} m)")
    f = tl_field(env, freq_hz, z, rmax_m=r_max_m)
    line = smooth_tl(f.ranges_m, f.at_depth(z), TL_AVERAGE_M)
    nl = NL_DB if nl_db is None else nl_db
    di = DI_DB if di_db is None else di_db

    def xi_bar(r):
        return passive_snr_db(sl_db, np.interp(r, f.ranges_m, line), di, nl)

    return xi_bar, env, z


def estimate_to_solution(est: BatchEstimate, time_s) -> TmaSolution:
    x, P = est.state_at(time_s)
    return TmaSolution(np.asarray(time_s, dtype=float), x, P, est.method)


def solve_batch(record: BearingRecord, ownship: OwnshipTrack, method: str, *, sigma_bearing_rad: float,
                sigma_snr_db: float = 1.0, env: str | None = None, sl_db: float | None = None, freq_hz: float = 200.0,
                depth_m: float | None = None, r_min_m: float = 500.0, r_max_m: float = 60_000.0,
                nl_db: float | None = None, di_db: float | None = None) -> TmaSolution:
    """Batch TMA of a whole record: ``method`` 'ml' (bearings only) or 'em-map' (bearings + SNR + TL)."""
    require(method in ("ml", "em-map"), f"unknown batch method '{method}': choose ml or em-map")
    t = np.asarray(record.time_s, dtype=float)
    own = ownship.position_at(t)
    if method == "ml":
        est = ml_bearings_only(record.bearing_rad, t, own, sigma_bearing_rad)
        return estimate_to_solution(est, t)
    from sonartrack.tma.em_map import make_problem, solve_em_map

    if record.snr_db is None:
        raise InputError("em-map needs measured SNR: add an snr_db column to the bearings file")
    if env is None or sl_db is None:
        raise InputError("em-map needs a propagation model: give --env NAME (or a profile file) and --sl DB")
    msg = check_observability(t - t[0], own)
    ml_start = None
    if msg:
        warnings.warn(msg.replace("use a record with a course or speed change, or em-map with SNR",
                                  "em-map relies on the SNR for range"), UnobservableWarning, stacklevel=2)
    else:
        try:
            ml_start = ml_bearings_only(record.bearing_rad, t, own, sigma_bearing_rad).x0
        except (InputError, np.linalg.LinAlgError):
            ml_start = None
    xi_bar, _, _ = snr_model(env, sl_db, freq_hz, depth_m, r_max_m * 1.05, nl_db, di_db)
    prob = make_problem(record.bearing_rad, record.snr_db, t, own, sigma_bearing_rad, sigma_snr_db, xi_bar, r_min_m, r_max_m)
    est = solve_em_map(prob, t0_s=float(t[0]), extra_starts=[ml_start])
    if not np.all(np.isfinite(est.covariance)):
        raise InputError("em-map found no well-defined solution (flat likelihood): check the SL, environment and depth")
    return estimate_to_solution(est, t)


def ekf_from_batch(record: BearingRecord, ownship: OwnshipTrack, est: BatchEstimate, *, start_s: float,
                   sigma_bearing_rad: float, q_m2_s3: float = 1e-4) -> TmaSolution:
    """A sequential bearings-only EKF that takes over from a batch estimate (paper P3, sec. 2: the batch
    solution initialises the tracker that follows the target from then on).

    The batch estimate must come from the bearings up to ``start_s``; the EKF starts there with the
    batch state and covariance and filters only the later bearings (refiltering the batch's own data
    would count it twice and make the covariance too small). Absolute state [x, y, vx, vy] (m, m/s),
    constant velocity with white-acceleration noise of intensity ``q_m2_s3``:
    F = [[I, T I], [0, I]], Q = q [[T^3/3 I, T^2/2 I], [T^2/2 I, T I]]; bearing h = atan2(x - ox, y - oy)
    with the Jacobian of batch_ml.bearing_model; Joseph-form update. Returns the states at ``start_s``
    and at every later bearing.
    """
    from sonartrack.core.angles import wrap_angle
    from sonartrack.filters.kalman import joseph_update, kf_gain

    t_all = np.asarray(record.time_s, dtype=float)
    later = t_all > start_s
    require(bool(later.any()), f"no bearings after {start_s:g} s for the EKF to filter")
    t = np.concatenate([[start_s], t_all[later]])
    z = np.asarray(record.bearing_rad, dtype=float)[later]
    own = ownship.position_at(t)
    x0, P0 = est.state_at(t[:1])
    x, P = x0[0].copy(), P0[0].copy()
    require(bool(np.all(np.isfinite(P))), "the batch estimate has no finite covariance to start the EKF from")
    R = np.array([[sigma_bearing_rad**2]])
    xs = np.empty((len(t), 4))
    Ps = np.empty((len(t), 4, 4))
    xs[0], Ps[0] = x, P
    for k in range(1, len(t)):
        T = t[k] - t[k - 1]
        F = np.eye(4)
        F[0, 2] = F[1, 3] = T
        Q = q_m2_s3 * np.kron(np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]]), np.eye(2))
        x, P = F @ x, F @ P @ F.T + Q
        dx, dy = x[0] - own[k, 0], x[1] - own[k, 1]
        r2 = dx * dx + dy * dy
        H = np.array([[dy / r2, -dx / r2, 0.0, 0.0]])
        nu = np.array([wrap_angle(z[k - 1] - np.arctan2(dx, dy))])
        S = H @ P @ H.T + R
        x, P = joseph_update(x, P, nu, kf_gain(P, H, np.linalg.inv(S)), H, R)
        xs[k], Ps[k] = x, P
    return TmaSolution(t, xs, Ps, f"{est.method}+ekf")
