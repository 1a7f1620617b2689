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

Methods: ``ekf`` / ``mgekf`` (one model, q = ``q_single``), ``imm-ekf`` / ``imm-mgekf`` (one mode per
value in ``q_values``, Markov matrix with ``transition_diagonal`` on its diagonal).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.models.passive import SOUND_SPEED_MPS
from sonartrack.models.relative_motion import observer_inputs
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution

METHODS = ("ekf", "mgekf", "imm-ekf", "imm-mgekf")


@dataclass(frozen=True, slots=True)
class SequentialOptions:
    """Tuning of the sequential filters (the defaults are the bftma-imm study's choices)."""

    q_values: tuple[float, ...] = (1e-5, 1e-3, 1e-1)
    q_single: float = 1e-3
    transition_diagonal: float = 0.99
    q_f0: float = 1e-8
    initial_range_m: float = 10_000.0
    sigma_range_m: float = 5_000.0
    target_velocity_mps: tuple[float, float] = (0.0, 0.0)
    sigma_target_velocity_mps: float = 5.0
    sigma_f0_hz: float | None = None
    sound_speed_mps: float = SOUND_SPEED_MPS

    def __post_init__(self):
        require(len(self.q_values) >= 1 and all(q >= 0 for q in self.q_values),
                "q_values must be one or more non-negative process-noise intensities (m^2/s^3)")
        require(self.q_single >= 0, "q_single must be non-negative (m^2/s^3)")
        require(0.0 < self.transition_diagonal <= 1.0, "transition_diagonal must lie in (0, 1]")
        require(self.initial_range_m > 0 and self.sigma_range_m > 0, "initial_range_m and sigma_range_m must be positive")
        require(self.sigma_target_velocity_mps > 0, "sigma_target_velocity_mps must be positive")
        require(self.sound_speed_mps > 0, "sound_speed_mps must be positive")


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


def filter_setup(method: str, options: SequentialOptions):
    """``(qs, Pi, modified)`` for a method name."""
    from sonartrack.filters.imm_ekf import transition_matrix

    if method not in METHODS:
        raise InputError(f"unknown sequential method '{method}': choose one of {', '.join(METHODS)}")
    modified = method.endswith("mgekf")
    qs = tuple(options.q_values) if method.startswith("imm") else (options.q_single,)
    return np.asarray(qs, float), transition_matrix(len(qs), options.transition_diagonal), modified


def observer_kinematics(ownship: OwnshipTrack, times_s):
    """Own-ship position (linear interpolation) and velocity (central differences of the navigation
    samples, interpolated) at ``times_s``; returns ``pos (n, 2)``, ``vel (n, 2)``."""
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
    f0 is a placeholder (0 Hz, unit variance) that the bearings never touch."""
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


def run_sequential(times_s, bearing_rad, frequency_hz, obs_pos, obs_vel, x0, P0, method: str, *,
                   sigma_bearing_rad: float, sigma_freq_hz: float = 0.1,
                   options: SequentialOptions = SequentialOptions(), engine: str = "numba") -> SequentialTrack:
    """Filter arrays: times (n,), bearings (n,) rad, frequencies (n,) Hz or None, observer
    positions/velocities (n, 2), initial estimate at times[0]."""
    from sonartrack.filters.imm_ekf import run_imm_bf

    qs, Pi, modified = filter_setup(method, options)
    u = observer_inputs(times_s, obs_pos, obs_vel)
    x, P, mu, failed = run_imm_bf(times_s, bearing_rad, frequency_hz, u, x0, P0, qs=qs, Pi=Pi,
                                  sigma_bearing_rad=sigma_bearing_rad, sigma_freq_hz=sigma_freq_hz,
                                  modified=modified, q_f0=options.q_f0, c=options.sound_speed_mps, engine=engine)
    return SequentialTrack(np.asarray(times_s, float), x, P, mu, failed, method, tuple(float(q) for q in qs))


def solve_sequential(record: BearingRecord, ownship: OwnshipTrack, method: str = "imm-mgekf", *,
                     sigma_bearing_rad: float, sigma_freq_hz: float = 0.1, use_frequency: bool = False,
                     options: SequentialOptions = SequentialOptions()) -> tuple[TmaSolution, SequentialTrack]:
    """A user's record -> the target solution over time (absolute [x, y, vx, vy] with covariance).

    The caller has checked that the ownship file covers the record (io/tma_files.py). Raises
    :class:`InputError` when frequencies are asked for but absent, or when the filter fails.
    """
    require(sigma_bearing_rad > 0, "the bearing standard deviation must be positive")
    t = np.asarray(record.time_s, float)
    require(len(t) >= 3, f"the bearings file has {len(t)} measurement(s): TMA needs at least 3")
    freq = None
    if use_frequency:
        if record.frequency_hz is None or not np.isfinite(record.frequency_hz).any():
            raise InputError("--frequency needs a frequency_hz column in the bearings file")
        require(sigma_freq_hz > 0, "the frequency standard deviation must be positive")
        freq = np.asarray(record.frequency_hz, float)
    pos, vel = observer_kinematics(ownship, t)
    f_first = None
    if freq is not None:
        f_first = float(freq[np.argmax(np.isfinite(freq))])
    x0, P0 = initial_estimate(float(record.bearing_rad[0]), f_first, vel[0], range_m=options.initial_range_m,
                              sigma_range_m=options.sigma_range_m, sigma_bearing_rad=sigma_bearing_rad,
                              target_velocity_mps=options.target_velocity_mps,
                              sigma_target_velocity_mps=options.sigma_target_velocity_mps,
                              sigma_f0_hz=options.sigma_f0_hz, c=options.sound_speed_mps)
    track = run_sequential(t, np.asarray(record.bearing_rad, float), freq, pos, vel, x0, P0, method,
                           sigma_bearing_rad=sigma_bearing_rad, sigma_freq_hz=sigma_freq_hz, options=options)
    if track.failed_at >= 0:
        raise InputError(f"the {method} filter failed numerically at t = {t[track.failed_at]:g} s (the estimate "
                         "passed through the ownship): check the bearings' units and noise, or change "
                         "initial_range_m / sigma_range_m in --config")
    state = track.rel_state[:, :4] + np.concatenate([pos, vel], axis=-1)
    return TmaSolution(t, state, track.rel_cov[:, :4, :4].copy(), method), track
