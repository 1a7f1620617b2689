"""Batch TMA on a user's record: bearings-only ML, or EM/MAP with SNR and a propagation model (paper P3);
optionally the batch on a first window only, with a sequential EKF taking over for the rest.

For ``em-map`` the mean SNR against range is xi_bar(r) = SL - TL(r) + DI - NL, with TL from RAM
(``acoustics/``) in the given environment, source and receiver at ``depth_m``, averaged incoherently over
``EmMapSettings.tl_average_m`` (1 km by default).
The environment is an :class:`~sonartrack.acoustics.environment.Environment` (a shipped one by name,
or one read from a profile file by ``sonartrack.io.environment``); TL fields come from ``tl_store`` (any
:class:`~sonartrack.acoustics.transmission_loss.FieldStore`, e.g. the disk cache of io/environment.py)
when one is given.

Parameters the functions here share (their docstrings refer to this list):

- ``record`` (BearingRecord): bearings (rad, clockwise from north) with times (s) and SNRs (dB) when measured;
- ``ownship`` (OwnshipTrack): ownship positions (m; x east, y north) over time;
- ``sigma_bearing_rad`` (float): bearing noise standard deviation (rad);
- ``batch`` (BatchSettings, optional): propagation-model settings of em-map (environment, SL, frequency, depth,
  NL, DI, sigma_SNR); default the library defaults;
- ``em_map`` (EmMapSettings, optional): EM/MAP solver settings (range interval, kappa, TL averaging, iterations);
- ``environment`` (Environment or str, optional): overrides ``batch.env``;
- ``tl_store`` (FieldStore, optional): cache of TL fields.
"""

from __future__ import annotations

import warnings

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, check_observability, ml_bearings_only
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.tma.settings import BatchSettings, EmMapSettings


class UnobservableWarning(UserWarning):
    """Range is not observable from bearings alone (the ownship has not maneuvered)."""


def snr_model(env, sl_db: float, freq_hz: float, depth_m: float | None, r_max_m: float,
              nl_db: float | None = None, di_db: float | None = None, tl_store=None, window_m: float | None = None):
    """xi_bar(r) for an :class:`Environment` (or a shipped environment's name): (callable, environment, depth);
    TL averaged over ``window_m`` (default: ``EmMapSettings().tl_average_m``).

    Parameters
    ----------
    env : Environment or str
        The environment or a shipped environment's name.
    sl_db : float
        Source level SL (dB re 1 uPa at 1 m).
    freq_hz : float
        Frequency of the TL field (Hz).
    depth_m : float or None
        Source and receiver depth (m); None: min(50 m, half the water depth).
    r_max_m : float
        Largest range of the TL field (m).
    nl_db, di_db : float, optional
        Noise level NL and directivity index DI (dB); default acoustics/sonar_equation.py's NL_DB, DI_DB.
    tl_store : FieldStore, optional
        Cache of TL fields.
    window_m : float, optional
        Range window (m) of the incoherent TL average.

    Returns
    -------
    xi_bar : callable
        r (m) -> SL - TL(r) + DI - NL (dB), TL interpolated in range.
    environment : Environment
        The environment used.
    depth_m : float
        The depth used (m).
    """
    from sonartrack.acoustics.environment import load_environment
    from sonartrack.acoustics.sonar_equation import DI_DB, NL_DB, passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field

    env = load_environment(env) if isinstance(env, str) else env
    z = float(depth_m) if depth_m is not None else min(50.0, env.water_depth_m / 2.0)
    require(0 < z < env.water_depth_m,
            f"depth {z:g} m is outside the water column of {env.name} (0..{env.water_depth_m:g} m)")
    f = tl_field(env, freq_hz, z, rmax_m=r_max_m, store=tl_store)
    window = EmMapSettings().tl_average_m if window_m is None else window_m
    line = smooth_tl(f.ranges_m, f.at_depth(z), window)
    nl = NL_DB if nl_db is None else nl_db
    di = DI_DB if di_db is None else di_db

    def xi_bar(r):
        return passive_snr_db(sl_db, np.interp(r, f.ranges_m, line), di, nl)

    return xi_bar, env, z


def estimate_to_solution(est: BatchEstimate, time_s) -> TmaSolution:
    """A batch estimate propagated to ``time_s`` (constant velocity) as a :class:`TmaSolution`.

    Parameters
    ----------
    est : BatchEstimate
        X0 at its reference time and its covariance.
    time_s : array_like, shape (n,)
        Times (s).

    Returns
    -------
    TmaSolution
        States [x, y, vx, vy] (m, m/s) and covariances at ``time_s``, method of the estimate.
    """
    x, P = est.state_at(time_s)
    return TmaSolution(time_s=np.asarray(time_s, dtype=float), state=x, covariance=P, method=est.method)


def _ml_start(record: BearingRecord, t, own, sigma_bearing_rad: float):
    """The bearings-only ML X0 as an extra EM/MAP start, or None (with an UnobservableWarning) when the
    ownship has not maneuvered or ML fails."""
    msg = check_observability(t - t[0], own)
    if msg:
        warnings.warn(msg.replace("use a record with a course or speed change, or em-map with SNR",
                                  "em-map relies on the SNR for range"), UnobservableWarning, stacklevel=3)
        return None
    try:
        return ml_bearings_only(record.bearing_rad, t, own, sigma_bearing_rad).x0
    except (InputError, np.linalg.LinAlgError):
        return None


def em_map_estimate(record: BearingRecord, ownship: OwnshipTrack, *, sigma_bearing_rad: float, batch: BatchSettings,
                    em_map: EmMapSettings, environment=None, tl_store=None) -> BatchEstimate:
    """EM/MAP X0 of a record with SNRs (tma/em_map.py); ``environment`` overrides ``batch.env`` (a name).

    Parameters
    ----------
    record, ownship, sigma_bearing_rad, batch, em_map, environment, tl_store
        As in the module docstring; ``record`` must hold SNRs, ``batch`` and ``em_map`` are required here.

    Returns
    -------
    BatchEstimate
        X0 at the first bearing's time with the observed-information covariance widened by the level's
        uncertainty ``batch.sigma_level_db`` (a consider parameter: tma/em_map.py :func:`level_covariance`); the
        bearings-only ML estimate is one of the starts when it exists.
    """
    from sonartrack.tma.em_map import make_problem, solve_em_map

    if record.snr_db is None:
        raise InputError("em-map needs measured SNR: add an snr_db column to the bearings file")
    env = environment if environment is not None else batch.env
    if env is None or batch.sl_db is None:
        raise InputError("em-map needs a propagation model: give --env NAME (or a profile file) and --sl DB")
    t = np.asarray(record.time_s, dtype=float)
    own = ownship.position_at(t)
    ml_start = _ml_start(record, t, own, sigma_bearing_rad)
    xi_bar, _, _ = snr_model(env, batch.sl_db, batch.freq_hz, batch.depth_m, em_map.r_max_m * 1.05, batch.nl_db,
                             batch.di_db, tl_store=tl_store, window_m=em_map.tl_average_m)
    prob = make_problem(record.bearing_rad, record.snr_db, t, own, sigma_bearing_rad, batch.sigma_snr_db, xi_bar,
                        em_map.r_min_m, em_map.r_max_m, kappa=em_map.kappa, sigma_level_db=batch.sigma_level_db)
    est = solve_em_map(prob, t0_s=float(t[0]), extra_starts=[ml_start], max_iter=em_map.max_iter)
    if not np.all(np.isfinite(est.covariance)):
        raise InputError("em-map found no well-defined solution (flat likelihood): check the SL, environment and depth")
    return est


def solve_batch(record: BearingRecord, ownship: OwnshipTrack, method: str, *, sigma_bearing_rad: float,
                batch: BatchSettings | None = None, em_map: EmMapSettings | None = None, environment=None,
                tl_store=None) -> TmaSolution:
    """Batch TMA of a whole record: ``method`` 'ml' (bearings only) or 'em-map' (bearings + SNR + TL);
    the solution at every measurement time.

    Parameters
    ----------
    method : str
        "ml" or "em-map".
    record, ownship, sigma_bearing_rad, batch, em_map, environment, tl_store
        As in the module docstring (``batch``, ``em_map``, ``environment`` and ``tl_store`` serve em-map only).

    Returns
    -------
    TmaSolution
        States [x, y, vx, vy] (m, m/s) and covariances at the bearing times.
    """
    require(method in ("ml", "em-map"), f"unknown batch method '{method}': choose ml or em-map")
    t = np.asarray(record.time_s, dtype=float)
    if method == "ml":
        est = ml_bearings_only(record.bearing_rad, t, ownship.position_at(t), sigma_bearing_rad)
    else:
        est = em_map_estimate(record, ownship, sigma_bearing_rad=sigma_bearing_rad,
                              batch=BatchSettings() if batch is None else batch,
                              em_map=EmMapSettings() if em_map is None else em_map, environment=environment,
                              tl_store=tl_store)
    return estimate_to_solution(est, t)


def solve_batch_then_ekf(record: BearingRecord, ownship: OwnshipTrack, method: str, *, window_s: float,
                         sigma_bearing_rad: float, batch: BatchSettings | None = None,
                         em_map: EmMapSettings | None = None, environment=None, tl_store=None) -> TmaSolution:
    """Batch TMA on the bearings of the first ``window_s`` seconds, then a sequential EKF from the batch's
    last state and covariance over the rest (paper P3, sec. 2: the batch solution initialises the tracker);
    one solution over the whole record (method '<batch>+ekf').

    Parameters
    ----------
    method : str
        Batch method, "ml" or "em-map".
    window_s : float
        Length (s) of the batch window from the first bearing; bearings must remain after it.
    record, ownship, sigma_bearing_rad, batch, em_map, environment, tl_store
        As in the module docstring; ``batch.ekf_q_m2_s3`` also sets the EKF's acceleration noise (m^2/s^3).

    Returns
    -------
    TmaSolution
        The batch solution over the window followed by the EKF's over the rest.
    """
    batch = BatchSettings() if batch is None else batch
    head = record.until(float(record.time_s[0]) + window_s)
    require(0 < len(head.time_s) < len(record.time_s),
            f"batch window {window_s:g} s must leave bearings for both the batch and the EKF")
    first = solve_batch(head, ownship, method, sigma_bearing_rad=sigma_bearing_rad, batch=batch, em_map=em_map,
                        environment=environment, tl_store=tl_store)
    start_s = float(first.time_s[-1])
    later = ekf_from_state(record, ownship, first.state[-1], first.covariance[-1], start_s=start_s,
                           sigma_bearing_rad=sigma_bearing_rad, q_m2_s3=batch.ekf_q_m2_s3,
                           method=f"{first.method}+ekf")
    return first.followed_by(later)


def ekf_from_batch(record: BearingRecord, ownship: OwnshipTrack, est: BatchEstimate, *, start_s: float,
                   sigma_bearing_rad: float, q_m2_s3: float = 1e-4) -> TmaSolution:
    """:func:`ekf_from_state` started from a batch estimate propagated to ``start_s``.

    Parameters
    ----------
    est : BatchEstimate
        The batch estimate.
    start_s : float
        Time (s) the EKF starts from; only later bearings are filtered.
    record, ownship, sigma_bearing_rad, q_m2_s3
        As in :func:`ekf_from_state`.

    Returns
    -------
    TmaSolution
        As :func:`ekf_from_state`, method "<batch method>+ekf".
    """
    x0, P0 = est.state_at(np.array([start_s]))
    return ekf_from_state(record, ownship, x0[0], P0[0], start_s=start_s, sigma_bearing_rad=sigma_bearing_rad,
                          q_m2_s3=q_m2_s3, method=f"{est.method}+ekf")


def ekf_from_state(record: BearingRecord, ownship: OwnshipTrack, state, covariance, *, start_s: float,
                   sigma_bearing_rad: float, q_m2_s3: float = 1e-4, method: str = "ekf") -> TmaSolution:
    """A sequential bearings-only EKF from ``state``, ``covariance`` at ``start_s`` (e.g. a batch estimate).

    The start must come from the bearings up to ``start_s``; the EKF filters only the later bearings
    (refiltering the batch's own data would count it twice and make the covariance too small). Absolute
    state [x, y, vx, vy] (m, m/s), constant velocity with white-acceleration noise of intensity ``q_m2_s3``:
    F = [[I, T I], [0, I]], Q = q [[T^3/3 I, T^2/2 I], [T^2/2 I, T I]]; bearing h = atan2(x - ox, y - oy)
    with the Jacobian of batch_ml.bearing_model; Joseph-form update. Returns the states at ``start_s``
    and at every later bearing.

    Parameters
    ----------
    record, ownship : BearingRecord, OwnshipTrack
        Bearings (rad, clockwise from north) and ownship positions (m; x east, y north).
    state, covariance : array_like, shapes (4,), (4, 4)
        Start [x, y, vx, vy] (m, m/s) at ``start_s`` and its covariance (finite).
    start_s, sigma_bearing_rad, q_m2_s3, method : float, float, float, str
        Start time (s), bearing noise sd (rad), acceleration noise (m^2/s^3), method label.

    Returns
    -------
    TmaSolution
        States and covariances at ``start_s`` and at every later bearing time.
    """
    from sonartrack.core.angles import wrap_angle
    from sonartrack.filters.kalman import joseph_update, kf_gain

    t_all = np.asarray(record.time_s, dtype=float)
    later = t_all > start_s
    require(bool(later.any()), f"no bearings after {start_s:g} s for the EKF to filter")
    t = np.concatenate([[start_s], t_all[later]])
    z = np.asarray(record.bearing_rad, dtype=float)[later]
    own = ownship.position_at(t)
    x, P = np.array(state, dtype=float), np.array(covariance, dtype=float)
    require(bool(np.all(np.isfinite(P))), "the batch estimate has no finite covariance to start the EKF from")
    R = np.array([[sigma_bearing_rad**2]])
    xs, Ps = np.empty((len(t), 4)), np.empty((len(t), 4, 4))
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
    return TmaSolution(time_s=t, state=xs, covariance=Ps, method=method)
