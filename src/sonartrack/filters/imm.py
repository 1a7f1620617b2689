"""Interacting Multiple Model (IMM) steps that any mode-matched filter plugs into.

The mode filters are not called from here: the IMM cycle is split into the pieces that are the
same for every filter, and a caller (an IMM-KF, IMM-EKF, IMM-MGEKF, IMM-IPDA) runs its own
mode-matched predict/update between them. Mode index r is the *second-to-last* batch axis of the
state arrays: x (..., r, n), P (..., r, n, n), so a batch of tracks is handled at once.

Equations (Blom & Bar-Shalom 1988; Bar-Shalom, Li, Kirubarajan 2001, sec. 11.6.6), with
Markov transition matrix Pi[i, j] = P(mode j at k | mode i at k-1):

    predicted mode probability   c_j = sum_i Pi[i, j] mu_i                         (interaction)
    mixing probability           mu_{i|j} = Pi[i, j] mu_i / c_j
    mixed initial condition      x0_j = sum_i mu_{i|j} x_i
                                 P0_j = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T)
    mode probability update      mu_j = c_j Lambda_j / sum_l c_l Lambda_l   (Lambda_j: mode likelihood)
    combination                  x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.linalg import symmetrize


def imm_mixing(mu, Pi):
    """IMM interaction: predicted mode probabilities and mixing weights (Bar-Shalom et al. 2001, sec. 11.6.6).

    ``c_j = sum_i Pi[i, j] mu_i``, ``mu_{i|j} = Pi[i, j] mu_i / c_j`` (a mode with c_j = 0 gets weights 0).

    Parameters
    ----------
    mu : ndarray, shape (..., r)
        Mode probabilities at k-1.
    Pi : ndarray, shape (r, r)
        Markov transition matrix, Pi[i, j] = P(mode j at k | mode i at k-1).

    Returns
    -------
    c : ndarray, shape (..., r)
        Predicted mode probabilities.
    w : ndarray, shape (..., r, r)
        Mixing weights, w[..., i, j] = mu_{i|j}.
    """
    joint = mu[..., :, None] * Pi  # (..., i, j)
    c = joint.sum(axis=-2)
    w = joint / np.where(c > 0.0, c, 1.0)[..., None, :]
    return c, w


def imm_mix(x, P, w):
    """Mixed initial conditions of the mode filters.

    ``x0_j = sum_i mu_{i|j} x_i``, ``P0_j = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T)``.

    Parameters
    ----------
    x : ndarray, shape (..., r, n)
        Mode-conditioned states at k-1.
    P : ndarray, shape (..., r, n, n)
        Their covariances.
    w : ndarray, shape (..., r, r)
        Mixing weights w[..., i, j] = mu_{i|j} from :func:`imm_mixing`.

    Returns
    -------
    x0 : ndarray, shape (..., r, n)
        Mixed states, one per mode j.
    P0 : ndarray, shape (..., r, n, n)
        Mixed covariances, symmetrized.
    """
    x0 = np.einsum("...ij,...in->...jn", w, x)
    d = x[..., :, None, :] - x0[..., None, :, :]  # (..., i, j, n): x_i - x0_j
    P0 = np.einsum("...ij,...inm->...jnm", w, P) + np.einsum("...ij,...ijn,...ijm->...jnm", w, d, d)
    return x0, symmetrize(P0)


def imm_mode_update(c, log_lik):
    """Posterior mode probabilities ``mu_j = c_j Lambda_j / sum_l c_l Lambda_l``, computed in log space.

    Parameters
    ----------
    c : ndarray, shape (..., r)
        Predicted mode probabilities.
    log_lik : ndarray, shape (..., r)
        Mode log-likelihoods log Lambda_j of the measurement(s).

    Returns
    -------
    mu : ndarray, shape (..., r)
        Posterior mode probabilities (sum to 1).
    log_total : ndarray, shape (...)
        ``log sum_j c_j Lambda_j``, the IMM likelihood of the measurement(s).
    """
    a = np.log(np.maximum(c, 1e-300)) + log_lik
    amax = np.max(a, axis=-1, keepdims=True)
    e = np.exp(a - amax)
    s = e.sum(axis=-1, keepdims=True)
    return e / s, np.squeeze(np.log(s) + amax, -1)


def imm_combine(mu, x, P):
    """Combined estimate of the mode-conditioned estimates (output only; not fed back).

    ``x = sum_j mu_j x_j``, ``P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)``.

    Parameters
    ----------
    mu : ndarray, shape (..., r)
        Mode probabilities.
    x : ndarray, shape (..., r, n)
        Mode-conditioned states.
    P : ndarray, shape (..., r, n, n)
        Their covariances.

    Returns
    -------
    x : ndarray, shape (..., n)
        Combined state.
    P : ndarray, shape (..., n, n)
        Combined covariance, symmetrized.
    """
    xc = np.einsum("...j,...jn->...n", mu, x)
    d = x - xc[..., None, :]
    Pc = np.einsum("...j,...jnm->...nm", mu, P) + np.einsum("...j,...jn,...jm->...nm", mu, d, d)
    return xc, symmetrize(Pc)


def validate_transition_matrix(Pi) -> np.ndarray:
    """Check that ``Pi`` is a square row-stochastic matrix and return it as a float array.

    Parameters
    ----------
    Pi : array_like, shape (r, r)
        Mode transition matrix, Pi[i, j] = P(mode j at k | mode i at k-1).

    Returns
    -------
    ndarray, shape (r, r)
        The same matrix as float.

    Raises
    ------
    InputError
        If it is not square, has a negative entry, or a row does not sum to 1 (within 1e-9).
    """
    from sonartrack.core.errors import InputError

    Pi = np.asarray(Pi, dtype=float)
    if Pi.ndim != 2 or Pi.shape[0] != Pi.shape[1]:
        raise InputError(f"mode transition matrix must be square, got shape {Pi.shape}")
    if np.any(Pi < 0) or not np.allclose(Pi.sum(axis=1), 1.0, atol=1e-9):
        raise InputError("mode transition matrix rows must be probabilities summing to 1")
    return Pi
