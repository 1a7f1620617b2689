"""The numba functions of filters/imm_kf_kernel.py, at module level so that numba's disk cache finds them again in
the next process (a kernel built in a closure captures its helpers as dispatcher objects and is recompiled in every
process). This module imports numba: import it lazily, where the kernel is needed."""

from __future__ import annotations

import numba as nb
import numpy as np

_jit = nb.njit(cache=True)


@_jit
def mix(x, P, mu, Pi, j, c_j):  # pragma: no cover - compiled
    """x0_j = sum_i mu_{i|j} x_i, P0_j = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T),
    with mu_{i|j} = Pi_ij mu_i / c_j.

    Parameters
    ----------
    x : numpy.ndarray
        (r, n) mode-conditioned states.
    P : numpy.ndarray
        (r, n, n) their covariances.
    mu : numpy.ndarray
        (r,) mode probabilities.
    Pi : numpy.ndarray
        (r, r) transition probabilities, Pi[i, j] = P(mode j | mode i).
    j : int
        The mode mixed for.
    c_j : float
        sum_i Pi_ij mu_i; where it is 0 the weights are 0.

    Returns
    -------
    x0 : numpy.ndarray
        (n,) mixed state.
    P0 : numpy.ndarray
        (n, n) mixed covariance.
    """
    r, n = x.shape
    x0 = np.zeros(n)
    for i in range(r):
        x0 += (Pi[i, j] * mu[i] / c_j if c_j > 0 else 0.0) * x[i]
    P0 = np.zeros((n, n))
    for i in range(r):
        d = x[i] - x0
        P0 += (Pi[i, j] * mu[i] / c_j if c_j > 0 else 0.0) * (P[i] + np.outer(d, d))
    return x0, P0

@_jit
def predict_update(x0, P0, z, F, Q, H, R):  # pragma: no cover - compiled
    """KF predict (F, Q) then Joseph-form update; returns x+, P+ and the log-likelihood log N(nu; 0, S).

    Parameters
    ----------
    x0, P0 : numpy.ndarray
        (n,) state and (n, n) covariance at the previous step.
    z : numpy.ndarray
        (m,) measurement.
    F, Q : numpy.ndarray
        (n, n) transition matrix and process noise covariance over the step.
    H, R : numpy.ndarray
        (m, n) measurement matrix and (m, m) measurement noise covariance.

    Returns
    -------
    x : numpy.ndarray
        (n,) updated state.
    P : numpy.ndarray
        (n, n) updated covariance (symmetrised).
    loglik : float
        log N(nu; 0, S) of the innovation nu with covariance S = H P_pred H^T + R.
    """
    xp = F @ x0
    Pp = F @ P0 @ F.T + Q
    Pp = 0.5 * (Pp + Pp.T)
    nu = z - H @ xp
    S = H @ Pp @ H.T + R
    S = 0.5 * (S + S.T)
    Sinv = np.linalg.inv(S)
    K = Pp @ H.T @ Sinv
    A = np.eye(len(x0)) - K @ H
    Pu = A @ Pp @ A.T + K @ R @ K.T
    _, logdet = np.linalg.slogdet(S)
    return xp + K @ nu, 0.5 * (Pu + Pu.T), -0.5 * (len(z) * np.log(2.0 * np.pi) + logdet + nu @ Sinv @ nu)

@_jit
def mode_probabilities(c, loglik):  # pragma: no cover - compiled
    """mu_j = c_j Lambda_j / sum_l c_l Lambda_l, in log space.

    Parameters
    ----------
    c : numpy.ndarray
        (r,) predicted mode probabilities c_j.
    loglik : numpy.ndarray
        (r,) log-likelihoods ln Lambda_j of the modes.

    Returns
    -------
    numpy.ndarray
        (r,) updated mode probabilities, summing to 1.
    """
    a = np.log(np.maximum(c, 1e-300)) + loglik
    e = np.exp(a - a.max())
    return e / e.sum()

@_jit
def combine(mu, x, P):  # pragma: no cover - compiled
    """x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T).

    Parameters
    ----------
    mu : numpy.ndarray
        (r,) mode probabilities.
    x : numpy.ndarray
        (r, n) mode-conditioned states.
    P : numpy.ndarray
        (r, n, n) their covariances.

    Returns
    -------
    x : numpy.ndarray
        (n,) combined state.
    P : numpy.ndarray
        (n, n) combined covariance (symmetrised).
    """
    r, n = x.shape
    xc = np.zeros(n)
    for j in range(r):
        xc += mu[j] * x[j]
    Pc = np.zeros((n, n))
    for j in range(r):
        d = x[j] - xc
        Pc += mu[j] * (P[j] + np.outer(d, d))
    return xc, 0.5 * (Pc + Pc.T)

@_jit
def kernel(x, P, mu, z, F, Q, H, R, Pi):  # pragma: no cover - compiled
    """One IMM-KF cycle (mix, per-mode predict and Joseph update, mode probabilities, combine): the arguments and
    results of :func:`sonartrack.filters.imm_kf.imm_kf_step`, with ``F`` as (1 or r, n, n).

    Parameters
    ----------
    x, P, mu, z, Q, H, R, Pi : numpy.ndarray
        As :func:`sonartrack.filters.imm_kf.imm_kf_step`.
    F : numpy.ndarray
        (1, n, n) transition matrix shared by the modes, or (r, n, n) one per mode.

    Returns
    -------
    tuple of numpy.ndarray
        (x_r (r, n), P_r (r, n, n), mu (r,), x (n,), P (n, n)): updated mode-conditioned states and covariances,
        mode probabilities, combined state and covariance.
    """
    r, n = x.shape
    c = np.zeros(r)
    for j in range(r):
        for i in range(r):
            c[j] += Pi[i, j] * mu[i]
    x_out = np.empty((r, n))
    P_out = np.empty((r, n, n))
    loglik = np.empty(r)
    for j in range(r):
        x0, P0 = mix(x, P, mu, Pi, j, c[j])
        Fj = F[0] if F.shape[0] == 1 else F[j]  # one F shared by the modes, or one per mode
        x_out[j], P_out[j], loglik[j] = predict_update(x0, P0, z, Fj, Q[j], H, R)
    mu_new = mode_probabilities(c, loglik)
    xc, Pc = combine(mu_new, x_out, P_out)
    return x_out, P_out, mu_new, xc, Pc
