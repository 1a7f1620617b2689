"""Compiled Gaussian-mixture reduction of the PDA update over the gated pairs (numba), for the tracker.

The same update as ``association.pda.pda_mixture_update`` (equations there and in association/pda.py's
module doc), for n tracks x r modes and G gated (track, measurement) pairs g = (t, m):

    dx_g = K_g nu_g                                     (K_g = P-_t H^T S_g^-1)
    x_t = x-_t + sum_g beta_g dx_g
    P_t = beta_0 P-_t + sum_g beta_g (P-_t - K_g H P-_t + dx_g dx_g^T) - dx dx^T,   dx = sum_g beta_g dx_g

The gains K_g and the products K_g H P-_t stay NumPy matrix products (the wrapper computes them, as the
reference does); the compiled loops do the rest -- the per-pair terms, their sums per track, the
combination -- with the same floating-point operations in the same order as the reference (its sums
accumulate pair after pair, 0 + v_1 + v_2 + ...), so the results are identical bit for bit, without
the reference's (G, r, d, d) temporaries.

This module imports numba at the top; tracking/multi_target.py imports it on the first update, so
``import sonartrack`` stays fast. Compiled functions are cached on disk.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from sonartrack.association.likelihood import Likelihoods
from sonartrack.core.linalg import symmetrize


@nb.njit(cache=True)
def _pair_sums(P_pred, beta, ti, mi, K, KHP, nu):  # pragma: no cover - compiled
    """sum_g beta_g dx_g (n, r, d) and sum_g beta_g (P- - K H P- + dx_g dx_g^T) (n, r, d, d) per track."""
    n, r, d = P_pred.shape[0], P_pred.shape[1], P_pred.shape[2]
    k = nu.shape[2]
    acc_x = np.zeros((n, r, d))
    acc_P = np.zeros((n, r, d, d))
    dx = np.empty(d)
    for g in range(len(ti)):
        t = ti[g]
        for q in range(r):
            b = beta[t, q, mi[g]]
            for i in range(d):
                s = 0.0  # the reference's einsum sums into a zeroed output
                for j in range(k):
                    s += K[g, q, i, j] * nu[g, q, j]
                dx[i] = s
                acc_x[t, q, i] += b * s
            for i in range(d):
                for j in range(d):
                    acc_P[t, q, i, j] += ((P_pred[t, q, i, j] - KHP[g, q, i, j]) + dx[i] * dx[j]) * b
    return acc_x, acc_P


@nb.njit(cache=True)
def _combine(x_pred, P_pred, beta0, acc_x, acc_P):  # pragma: no cover - compiled
    """x = x- + acc_x;  P = sym(beta_0 P- + acc_P - acc_x acc_x^T), sym(A) = (A + A^T) / 2."""
    n, r, d = x_pred.shape
    x = np.empty((n, r, d))
    P = np.empty((n, r, d, d))
    A = np.empty((d, d))
    for t in range(n):
        for q in range(r):
            for i in range(d):
                x[t, q, i] = x_pred[t, q, i] + acc_x[t, q, i]
                for j in range(d):
                    A[i, j] = (beta0[t, q] * P_pred[t, q, i, j] + acc_P[t, q, i, j]) - acc_x[t, q, i] * acc_x[t, q, j]
            for i in range(d):
                for j in range(d):
                    P[t, q, i, j] = 0.5 * (A[i, j] + A[j, i])
    return x, P


def pda_mixture_update_fast(x_pred, P_pred, lik: Likelihoods, beta0, beta):
    """``pda_mixture_update`` (association/pda.py) with the sums compiled: same arguments, identical results."""
    k = lik.nu.shape[-1]
    ti, mi = lik.pair_track, lik.pair_meas
    if lik.gated.shape[1] == 0:
        return x_pred.copy(), P_pred.copy()
    if not len(ti):
        return x_pred.copy(), symmetrize(beta0[..., None, None] * P_pred)
    PHt = P_pred[ti][..., :, :k]  # P H^T for H = [I 0], per pair (G, r, d, k)
    K = PHt @ lik.S_inv
    KHP = K @ np.swapaxes(PHt, -1, -2)
    beta0, beta = np.ascontiguousarray(beta0, dtype=float), np.ascontiguousarray(beta, dtype=float)
    acc_x, acc_P = _pair_sums(P_pred, beta, ti, mi, K, KHP, lik.nu)
    return _combine(x_pred, P_pred, beta0, acc_x, acc_P)
