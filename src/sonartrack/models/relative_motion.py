"""Relative constant-velocity motion with the observer's own motion as a known input.

State order (used by models/passive.py, filters/{ekf,mgekf}.py, tma/imm_mgekf.py, tma/sequential_bf.py):
X = [x, y, vx, vy, f0] -- target minus observer position (m) and velocity (m/s), x east, y north,
and the emitted frequency f0 (Hz).

Yoo & Song (paper P2), eq. 2: dX/dt = A X - B a_o, with A the constant-velocity matrix, B = [0; I; 0]
and a_o the observer's acceleration; the target's acceleration is process noise. Over a step of
T seconds, for a constant-velocity target and *any* observer motion, the exact discrete form is::

    X_k+1 = F X_k - u_k + w_k
    F = [[I, T I, 0], [0, I, 0], [0, 0, 1]]
    u_k = [ p_o(k+1) - p_o(k) - T v_o(k),  v_o(k+1) - v_o(k),  0 ]      (observer input)

which for a constant observer acceleration a over the step is u_k = [T^2/2 a, T a, 0] (the
discretised eq. 2). The process noise w_k is the continuous white-noise acceleration model of
intensity q (m^2/s^3) on the kinematic block (Bar-Shalom, Li, Kirubarajan 2001, sec. 6.2.2) and a
random walk of intensity q_f0 (Hz^2/s) on f0::

    Q = [[q T^3/3 I, q T^2/2 I, 0], [q T^2/2 I, q T I, 0], [0, 0, q_f0 T]]
"""

from __future__ import annotations

import numpy as np

from sonartrack.models.motion import cv_process_noise

STATE_DIM = 5


def relative_transition(dt_s: float) -> np.ndarray:
    """Transition matrix ``F = [[I, T I, 0], [0, I, 0], [0, 0, 1]]`` of the relative CV model (paper P2, eq. 2).

    Parameters
    ----------
    dt_s : float
        Step T (s).

    Returns
    -------
    ndarray, shape (5, 5)
        F for the state [x, y, vx, vy, f0].
    """
    F = np.eye(STATE_DIM)
    F[0, 2] = F[1, 3] = dt_s
    return F


def relative_process_noise(dt_s: float, q: float, q_f0: float = 0.0) -> np.ndarray:
    """Process noise Q of the relative model (module docstring; Bar-Shalom et al. 2001, sec. 6.2.2).

    ``Q = [[q T^3/3 I, q T^2/2 I, 0], [q T^2/2 I, q T I, 0], [0, 0, q_f0 T]]``.

    Parameters
    ----------
    dt_s : float
        Step T (s).
    q : float
        Target acceleration noise power spectral density per axis (m^2/s^3).
    q_f0 : float, default 0.0
        Random-walk intensity of the emitted frequency f0 (Hz^2/s).

    Returns
    -------
    ndarray, shape (5, 5)
        Q.
    """
    Q = np.zeros((STATE_DIM, STATE_DIM))
    Q[:4, :4] = cv_process_noise(dt_s, q)
    Q[4, 4] = q_f0 * dt_s
    return Q


def relative_process_noise_stack(dt_s: float, qs, q_f0: float = 0.0) -> np.ndarray:
    """Relative-model process noise for several intensities at once (one per IMM mode).

    Parameters
    ----------
    dt_s, qs : float, float or array_like (r,)
        Step T (s) and acceleration noise power spectral densities (m^2/s^3), as in
        :func:`~sonartrack.models.motion.cv_process_noise_stack`.
    q_f0 : float, default 0.0
        f0 random-walk intensity (Hz^2/s), shared by the modes.

    Returns
    -------
    ndarray, shape (r, 5, 5)
        Q per mode.
    """
    return np.stack([relative_process_noise(dt_s, q, q_f0) for q in np.atleast_1d(qs)])


def input_from_acceleration(accel_mps2, dt_s: float) -> np.ndarray:
    """Observer input ``u = [T^2/2 a, T a, 0]`` for a constant observer acceleration over the step.

    Parameters
    ----------
    accel_mps2 : array_like, shape (..., 2)
        Observer acceleration [east, north] (m/s^2).
    dt_s : float
        Step T (s).

    Returns
    -------
    ndarray, shape (..., 5)
        u, subtracted from F X in the prediction (m, m/s, Hz).
    """
    a = np.asarray(accel_mps2, dtype=float)
    u = np.zeros(a.shape[:-1] + (STATE_DIM,))
    u[..., :2] = 0.5 * dt_s**2 * a
    u[..., 2:4] = dt_s * a
    return u


def observer_inputs(times_s, obs_pos, obs_vel) -> np.ndarray:
    """Exact observer inputs u_k between consecutive times, whatever the observer did in between.

    ``u_k = [p(k+1) - p(k) - T_k v(k), v(k+1) - v(k), 0]`` with T_k = t(k+1) - t(k). The target is
    then propagated exactly (up to its own acceleration).

    Parameters
    ----------
    times_s : array_like, shape (n,)
        Times (s), increasing.
    obs_pos : array_like, shape (n, 2)
        Observer positions [x east, y north] (m).
    obs_vel : array_like, shape (n, 2)
        Observer velocities (m/s).

    Returns
    -------
    ndarray, shape (n - 1, 5)
        u_k (m, m/s, 0 for f0).
    """
    t = np.asarray(times_s, dtype=float)
    p = np.asarray(obs_pos, dtype=float)
    v = np.asarray(obs_vel, dtype=float)
    dt = np.diff(t)[:, None]
    u = np.zeros((len(t) - 1, STATE_DIM))
    u[:, :2] = p[1:] - p[:-1] - dt * v[:-1]
    u[:, 2:4] = v[1:] - v[:-1]
    return u


def relative_predict_mean(X, dt_s: float, u=None):
    """Predicted relative state ``x- = F X - u``.

    Parameters
    ----------
    X : array_like, shape (..., 5)
        Relative states [x, y, vx, vy, f0] (m, m/s, Hz).
    dt_s : float
        Step T (s).
    u : array_like, shape (..., 5), optional
        Observer input (:func:`observer_inputs`); None for a non-manoeuvring observer.

    Returns
    -------
    ndarray, shape (..., 5)
        Predicted states.
    """
    X = np.asarray(X, dtype=float)
    out = np.array(X, copy=True)
    out[..., 0] += dt_s * X[..., 2]
    out[..., 1] += dt_s * X[..., 3]
    if u is not None:
        out = out - u
    return out
