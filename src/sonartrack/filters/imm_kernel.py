"""Compiled IMM mixing and combination for a batch of tracks (numba): filters/imm.py's ``imm_mix`` and
``imm_combine`` as loops, for the multi-target tracker.

For track t and modes i, j (equations in filters/imm.py):

    mix        x0_j = sum_i w_ij x_i,   P0_j = sym(sum_i w_ij P_i + sum_i (w_ij d_ij) d_ij^T),  d_ij = x_i - x0_j
    combine    x = sum_j mu_j x_j,      P = sym(sum_j mu_j P_j + sum_j (mu_j d_j) d_j^T),       d_j = x_j - x

with sym(A) = (A + A^T) / 2. Each sum runs over the modes in order, with the same floating-point
operations as the NumPy reference (its einsum sums the few modes one after the other), so the results
are identical bit for bit; the loops avoid the reference's (n, r, r, d, d) temporaries. This module
imports numba at the top; its callers import it on first use, so ``import sonartrack`` stays fast.
Compiled functions are cached on disk.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def _moments(wt, x, P, out_x, out_P, A, B, dv):  # pragma: no cover - compiled
    """out_x = sum_i wt_i x_i;  out_P = sym(sum_i wt_i P_i + sum_i (wt_i d_i) d_i^T), d_i = x_i - out_x
    (A, B, dv: scratch (d, d), (d, d), (d,))."""
    r, d = x.shape
    for a in range(d):
        s = 0.0  # the reference's sums start from a zeroed output
        for i in range(r):
            s += wt[i] * x[i, a]
        out_x[a] = s
    A[:] = 0.0
    B[:] = 0.0
    for i in range(r):
        for a in range(d):
            dv[a] = x[i, a] - out_x[a]
        for a in range(d):
            for b in range(d):
                A[a, b] += wt[i] * P[i, a, b]
                B[a, b] += (wt[i] * dv[a]) * dv[b]
    for a in range(d):
        for b in range(d):
            out_P[a, b] = 0.5 * ((A[a, b] + B[a, b]) + (A[b, a] + B[b, a]))


@nb.njit(cache=True)
def mix(x, P, w):  # pragma: no cover - compiled
    """Mixed initial conditions for a batch of tracks (compiled ``filters.imm.imm_mix``).

    Parameters
    ----------
    x : ndarray, shape (n, r, d)
        Mode-conditioned states of n tracks, r modes.
    P : ndarray, shape (n, r, d, d)
        Their covariances.
    w : ndarray, shape (n, r, r)
        Mixing weights w[t, i, j] = mu_{i|j}.

    Returns
    -------
    x0 : ndarray, shape (n, r, d)
        Mixed states.
    P0 : ndarray, shape (n, r, d, d)
        Mixed covariances, symmetrized.
    """
    n, r, d = x.shape
    x0 = np.empty((n, r, d))
    P0 = np.empty((n, r, d, d))
    A, B, dv = np.empty((d, d)), np.empty((d, d)), np.empty(d)
    for t in range(n):
        for j in range(r):
            _moments(w[t, :, j], x[t], P[t], x0[t, j], P0[t, j], A, B, dv)
    return x0, P0


@nb.njit(cache=True)
def combine(mu, x, P):  # pragma: no cover - compiled
    """Combined estimates for a batch of tracks (compiled ``filters.imm.imm_combine``).

    Parameters
    ----------
    mu : ndarray, shape (n, r)
        Mode probabilities.
    x : ndarray, shape (n, r, d)
        Mode-conditioned states.
    P : ndarray, shape (n, r, d, d)
        Their covariances.

    Returns
    -------
    x : ndarray, shape (n, d)
        Combined states.
    P : ndarray, shape (n, d, d)
        Combined covariances, symmetrized.
    """
    n, r, d = x.shape
    xc = np.empty((n, d))
    Pc = np.empty((n, d, d))
    A, B, dv = np.empty((d, d)), np.empty((d, d)), np.empty(d)
    for t in range(n):
        _moments(mu[t], x[t], P[t], xc[t], Pc[t], A, B, dv)
    return xc, Pc
