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
    """Predicted mode probabilities ``c (..., r)`` and mixing weights ``w[..., i, j] = mu_{i|j}``."""
    joint = mu[..., :, None] * Pi  # (..., i, j)
    c = joint.sum(axis=-2)
    w = joint / np.where(c > 0.0, c, 1.0)[..., None, :]
    return c, w


def imm_mix(x, P, w):
    """Mixed initial conditions ``x0 (..., r, n)``, ``P0 (..., r, n, n)`` from weights ``w[..., i, j]``."""
    x0 = np.einsum("...ij,...in->...jn", w, x)
    d = x[..., :, None, :] - x0[..., None, :, :]  # (..., i, j, n): x_i - x0_j
    P0 = np.einsum("...ij,...inm->...jnm", w, P) + np.einsum("...ij,...ijn,...ijm->...jnm", w, d, d)
    return x0, symmetrize(P0)


def imm_mode_update(c, log_lik):
    """Posterior mode probabilities from predicted ``c`` and mode log-likelihoods (log space).

    Returns ``(mu, log_total)`` where ``log_total = log sum_j c_j Lambda_j`` is the IMM
    likelihood of the measurement(s).
    """
    a = np.log(np.maximum(c, 1e-300)) + log_lik
    amax = np.max(a, axis=-1, keepdims=True)
    e = np.exp(a - amax)
    s = e.sum(axis=-1, keepdims=True)
    return e / s, np.squeeze(np.log(s) + amax, -1)


def imm_combine(mu, x, P):
    """Combined estimate ``x (..., n)``, ``P (..., n, n)`` of the mode-conditioned estimates."""
    xc = np.einsum("...j,...jn->...n", mu, x)
    d = x - xc[..., None, :]
    Pc = np.einsum("...j,...jnm->...nm", mu, P) + np.einsum("...j,...jn,...jm->...nm", mu, d, d)
    return xc, symmetrize(Pc)


def validate_transition_matrix(Pi) -> np.ndarray:
    """Check that ``Pi`` is a square row-stochastic matrix; return it as an array."""
    from sonartrack.core.errors import InputError

    Pi = np.asarray(Pi, dtype=float)
    if Pi.ndim != 2 or Pi.shape[0] != Pi.shape[1]:
        raise InputError(f"mode transition matrix must be square, got shape {Pi.shape}")
    if np.any(Pi < 0) or not np.allclose(Pi.sum(axis=1), 1.0, atol=1e-9):
        raise InputError("mode transition matrix rows must be probabilities summing to 1")
    return Pi
