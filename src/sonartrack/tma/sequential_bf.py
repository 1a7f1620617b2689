"""Sequential bearing (+ frequency) TMA: run an EKF, MGEKF or IMM-MGEKF over a measurement record.

The filters work on the observer-relative state X = [x, y, vx, vy, f0] (models/relative_motion.py)
and the bearing + frequency measurement (models/passive.py); the observer's own motion enters as the
known input u_k = [p_o(k+1) - p_o(k) - T v_o(k), v_o(k+1) - v_o(k), 0] (Yoo & Song, paper P2,
eq. 2). The target's absolute solution is X + [p_o, v_o]; its covariance is the relative one,
since own-ship navigation is taken as exact.

Initial estimate at the first measurement time (the usual range-prior initialisation)::

    position   r0 [sin b0, cos b0],  cov = sigma_r^2 u u^T + (r0 sigma_b)^2 n n^T
               (u = [sin b0, cos b0] along the first bearing, n = [cos b0, -sin b0] across it)
    velocity   v_target_prior - v_o(t0),  cov = sigma_v^2 I
    f0         first measured frequency,  variance sigma_f0^2 (default: the Doppler spread
               f (|v_o| + 2 sigma_v) / c the unknown radial velocity can cause)

Methods: ``ekf`` / ``mgekf`` (one model, q = ``sequential.q_single``), ``imm-ekf`` / ``imm-mgekf`` (one mode
per value in ``imm.q_values``, Markov matrix with ``imm.transition_diagonal`` on its diagonal); settings in
tma/settings.py, filters in tma/imm_mgekf.py. With ``sequential.range_filters`` = N > 1 the method runs as a
range-parameterised bank of N such filters over ``sequential.bank_range_m`` (tma/range_bank.py, Peach 1995) instead
of one filter from the range guess: one filter's range collapses (NEES 20-40 times chi-square's on
tests/tma/test_imm_range_bank.py's turns), the bank's does not (its ANEES is below chi-square's interval on
straight legs, about 1 against [2.86, 5.33], and inside or just above it during turns: conservative where the
target keeps course; the trade-off is measured in tma/settings.py's ImmSettings doc).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.models.passive import SOUND_SPEED_MPS
from sonartrack.models.relative_motion import observer_inputs
from sonartrack.tma.imm_mgekf import ImmBfModel, mode_probabilities, run_imm_bf, transition_matrix
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.tma.settings import SEQUENTIAL_METHODS, ImmSettings, SequentialSettings


@dataclass(frozen=True, slots=True)
class SequentialTrack:
    """A filter's output over a record: relative state/covariance, mode probabilities."""

    time_s: np.ndarray
    rel_state: np.ndarray  # (n, 5)
    rel_cov: np.ndarray  # (n, 5, 5)
    mode_prob: np.ndarray  # (n, r)
    failed_at: int  # index of the step where the filter failed numerically, -1 if none
    method: str
    q_values: tuple[float, ...]


def filter_model(method: str, *, sigma_bearing_rad: float, sigma_freq_hz: float, imm: ImmSettings,
                 sequential: SequentialSettings) -> ImmBfModel:
    """The filter a method name stands for: ``ekf`` / ``mgekf`` one model with q = ``q_single``,
    ``imm-ekf`` / ``imm-mgekf`` one mode per ``imm.q_values``; ``*mgekf`` the MGEKF covariance update.

    Parameters
    ----------
    method : str
        One of ekf, mgekf, imm-ekf, imm-mgekf.
    sigma_bearing_rad : float
        Bearing noise standard deviation (rad).
    sigma_freq_hz : float
        Frequency noise standard deviation (Hz).
    imm : ImmSettings
        Mode intensities q (m^2/s^3), transition diagonal, f0 random walk q_f0 (Hz^2/s).
    sequential : SequentialSettings
        Single-model q (m^2/s^3) and sound speed (m/s).

    Returns
    -------
    ImmBfModel
        The mode intensities, transition matrix, noises and covariance-update choice.
    """
    if method not in SEQUENTIAL_METHODS:
        raise InputError(f"unknown sequential method '{method}': choose one of {', '.join(SEQUENTIAL_METHODS)}")
    qs = tuple(imm.q_values) if method.startswith("imm") else (sequential.q_single,)
    return ImmBfModel(qs=np.asarray(qs, float), Pi=transition_matrix(len(qs), imm.transition_diagonal),
                      sigma_bearing_rad=sigma_bearing_rad, sigma_freq_hz=sigma_freq_hz, q_f0=imm.q_f0,
                      sound_speed_mps=sequential.sound_speed_mps, modified=method.endswith("mgekf"))


def observer_kinematics(ownship: OwnshipTrack, times_s):
    """Own-ship position (linear interpolation) and velocity (central differences of the navigation
    samples, interpolated) at ``times_s``; returns ``pos (n, 2)``, ``vel (n, 2)``.

    Parameters
    ----------
    ownship : OwnshipTrack
        At least two samples.
    times_s : array_like, shape (n,)
        Times (s).

    Returns
    -------
    pos : ndarray, shape (n, 2)
        Positions (m; x east, y north).
    vel : ndarray, shape (n, 2)
        Velocities (m/s).
    """
    t = np.asarray(times_s, dtype=float)
    pos = ownship.position_at(t)
    nt = np.asarray(ownship.time_s, float)
    if len(nt) < 2:
        raise InputError("the ownship file needs at least two samples to give the ownship's velocity")
    vx = np.gradient(np.asarray(ownship.x_m, float), nt)
    vy = np.gradient(np.asarray(ownship.y_m, float), nt)
    vel = np.stack([np.interp(t, nt, vx), np.interp(t, nt, vy)], axis=-1)
    return pos, vel


def initial_estimate(bearing0_rad: float, freq0_hz: float | None, obs_vel0, *, range_m: float, sigma_range_m: float,
                     sigma_bearing_rad: float, target_velocity_mps=(0.0, 0.0), sigma_target_velocity_mps: float = 5.0,
                     sigma_f0_hz: float | None = None, c: float = SOUND_SPEED_MPS):
    """Initial relative estimate ``x0 (5,)``, ``P0 (5, 5)`` (module docstring). With no frequency,
    f0 is a placeholder (0 Hz, unit variance) that the bearings never touch.

    Parameters
    ----------
    bearing0_rad : float
        First bearing (rad, clockwise from north).
    freq0_hz : float or None
        First measured frequency (Hz); None or NaN: none.
    obs_vel0 : array_like, shape (2,)
        Ownship velocity (m/s) at the first time.
    range_m, sigma_range_m : float
        Assumed range and its standard deviation (m).
    sigma_bearing_rad : float
        Bearing noise standard deviation (rad): the cross-range spread is range_m times it.
    target_velocity_mps : array_like, shape (2,)
        Assumed target velocity (m/s).
    sigma_target_velocity_mps : float
        Its standard deviation per axis (m/s).
    sigma_f0_hz : float, optional
        Standard deviation of f0 (Hz); default f0 (|v_own| + 2 sigma_v) / c.
    c : float
        Sound speed (m/s).

    Returns
    -------
    x0 : ndarray, shape (5,)
        [x, y, vx, vy, f0] relative to the ownship (m, m/s, Hz).
    P0 : ndarray, shape (5, 5)
        Its covariance.
    """
    ur = np.array([np.sin(bearing0_rad), np.cos(bearing0_rad)])
    un = np.array([np.cos(bearing0_rad), -np.sin(bearing0_rad)])
    vo = np.asarray(obs_vel0, float)
    x0 = np.zeros(5)
    x0[:2] = range_m * ur
    x0[2:4] = np.asarray(target_velocity_mps, float) - vo
    P0 = np.zeros((5, 5))
    P0[:2, :2] = sigma_range_m**2 * np.outer(ur, ur) + (range_m * sigma_bearing_rad) ** 2 * np.outer(un, un)
    P0[2:4, 2:4] = sigma_target_velocity_mps**2 * np.eye(2)
    if freq0_hz is None or not np.isfinite(freq0_hz):
        P0[4, 4] = 1.0
    else:
        x0[4] = freq0_hz
        if sigma_f0_hz is None:
            sigma_f0_hz = freq0_hz * (np.hypot(*vo) + 2.0 * sigma_target_velocity_mps) / c
        P0[4, 4] = sigma_f0_hz**2
    return x0, P0


def _measured_frequencies(record: BearingRecord, use_frequency: bool) -> np.ndarray | None:
    """The record's frequencies (Hz, NaN where missing) if asked for, else None."""
    if not use_frequency:
        return None
    if record.frequency_hz is None or not np.isfinite(record.frequency_hz).any():
        raise InputError("--frequency needs a frequency_hz column in the bearings file")
    return np.asarray(record.frequency_hz, float)


def _run_filter(t, record: BearingRecord, freq, pos, vel, model: ImmBfModel, seq: SequentialSettings,
                sigma_bearing_rad: float):
    """The filter over the record: one from the range guess, or the range-parameterised bank of
    ``seq.range_filters`` (tma/range_bank.py). Returns (x, P, mu, failed_at)."""
    f_first = None if freq is None else float(freq[np.argmax(np.isfinite(freq))])
    b0 = float(record.bearing_rad[0])
    kw = dict(sigma_bearing_rad=sigma_bearing_rad, sigma_target_velocity_mps=seq.sigma_target_velocity_mps,
              sigma_f0_hz=seq.sigma_f0_hz, c=seq.sound_speed_mps)
    u = observer_inputs(t, pos, vel)
    if seq.range_filters == 1:
        x0, P0 = initial_estimate(b0, f_first, vel[0], range_m=seq.initial_range_m, sigma_range_m=seq.sigma_range_m,
                                  **kw)
        return run_imm_bf(t, np.asarray(record.bearing_rad, float), freq, u, x0, P0, model)
    from sonartrack.tma.range_bank import range_subintervals, run_range_bank

    ranges, sds = range_subintervals(*seq.bank_range_m, seq.range_filters)
    starts = [initial_estimate(b0, f_first, vel[0], range_m=r, sigma_range_m=s, **kw)
              for r, s in zip(ranges, sds, strict=True)]
    x0, P0 = np.array([x for x, _ in starts]), np.array([p for _, p in starts])
    z = np.c_[np.asarray(record.bearing_rad, float), np.full(len(t), np.nan) if freq is None else freq]
    x, P, mu, _, failed = run_range_bank(t, z, u, x0, P0, model)
    return x, P, mu, failed


def solve_sequential(record: BearingRecord, ownship: OwnshipTrack, method: str = "imm-mgekf", *,
                     sigma_bearing_rad: float, sigma_freq_hz: float = 0.1, use_frequency: bool = False,
                     imm: ImmSettings | None = None, sequential: SequentialSettings | None = None,
                     ) -> tuple[TmaSolution, SequentialTrack]:
    """A user's record -> the target solution over time (absolute [x, y, vx, vy] with covariance), and the
    filter's own output (relative state with f0, mode probabilities).

    The ownship track must cover the record (tma/records.py ``check_coverage``). Raises
    :class:`InputError` when frequencies are asked for but absent, or when the filter fails.

    Parameters
    ----------
    record, ownship : BearingRecord, OwnshipTrack
        At least 3 bearings (rad, clockwise from north); ownship positions (m; x east, y north).
    method : str
        ekf, mgekf, imm-ekf or imm-mgekf.
    sigma_bearing_rad, sigma_freq_hz : float
        Bearing (rad) and frequency (Hz) noise standard deviations.
    use_frequency : bool
        Use the record's frequencies too.
    imm, sequential : ImmSettings, SequentialSettings, optional
        Filter settings (default the library defaults).

    Returns
    -------
    solution : TmaSolution
        Absolute states (m, m/s) and their 4 x 4 covariances at the bearing times.
    track : SequentialTrack
        Relative states with f0, covariances, mode probabilities, method and mode intensities.
    """
    imm = ImmSettings() if imm is None else imm
    seq = SequentialSettings() if sequential is None else sequential
    model = filter_model(method, sigma_bearing_rad=sigma_bearing_rad, sigma_freq_hz=sigma_freq_hz, imm=imm,
                         sequential=seq)
    t = np.asarray(record.time_s, float)
    require(len(t) >= 3, f"the bearings file has {len(t)} measurement(s): TMA needs at least 3")
    freq = _measured_frequencies(record, use_frequency)
    pos, vel = observer_kinematics(ownship, t)
    x, P, mu, failed = _run_filter(t, record, freq, pos, vel, model, seq, sigma_bearing_rad)
    if failed >= 0:
        raise InputError(f"the {method} filter failed numerically at t = {t[failed]:g} s (the estimate "
                         "passed through the ownship): check the bearings' units and noise, or change "
                         "sequential.initial_range_m / sigma_range_m in --config")
    track = SequentialTrack(t, x, P, mu, failed, method, tuple(float(q) for q in model.qs))
    state = x[:, :4] + np.concatenate([pos, vel], axis=-1)
    modes = (mode_probabilities(model.qs, mu, manoeuvre_q_min=imm.manoeuvre_q_min, level=imm.manoeuvre_level)
             if method.startswith("imm") else None)
    return TmaSolution(time_s=t, state=state, covariance=P[:, :4, :4].copy(), method=method, modes=modes), track
