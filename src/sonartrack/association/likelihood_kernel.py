"""Compiled chi-square pre-gate of position measurements (numba), for association/likelihood.py.

For n tracks x r modes and m measurements z (m, 2) with covariances R (m, 2, 2), in the notation of
association/likelihood.py (H = [I 0], so H x- = x_pos and H P- H^T = P_pos):

1. candidates -- the (track, measurement) pairs with nu_i^2 <= bound S_ii on both axes i for some mode,
   S_ii = P_pos_ii + R_ii, tested as ``h*h <= bound*P_ii + bound*R_ii``: exactly the test of the NumPy
   pre-gate ``_chi_square_candidates``, so both keep the same pairs, in row-major (track, measurement) order;
2. innovations -- for those pairs and every mode: nu = z - x_pos, S = P_pos + R, det S = a d - b c and
   S^-1 = [[d, -b], [-c, a]] / det S, with the same floating-point operations, in the same order, as the
   NumPy evaluation (``inv_and_logdet`` in core/gaussian.py), so the results are identical bit for bit.

The pre-gate is a loop that stops at the first failing axis and the first passing mode; NumPy has to
evaluate the whole (n, r, m) test. This module imports numba at the top: association/likelihood.py
imports it on the first large scan, so ``import sonartrack`` stays fast. Compiled functions are cached
on disk.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def _passes(x_pos, P_pos, z, R, bound, t, q, j):  # pragma: no cover - compiled
    """Pair (track t, measurement j) passes the per-axis test in mode q."""
    for i in range(z.shape[1]):
        h = z[j, i] - x_pos[t, q, i]
        if not h * h <= bound * P_pos[t, q, i, i] + bound * R[j, i, i]:
            return False
    return True


@nb.njit(cache=True)
def candidate_pairs(x_pos, P_pos, z, R, bound):  # pragma: no cover - compiled
    """(ci, cj): the pairs that pass the per-axis test in some mode, in row-major order (module doc, step 1)."""
    n, r = x_pos.shape[0], x_pos.shape[1]
    m = z.shape[0]
    ci = np.empty(n * m, np.int64)
    cj = np.empty(n * m, np.int64)
    c = 0
    for t in range(n):
        for j in range(m):
            for q in range(r):
                if _passes(x_pos, P_pos, z, R, bound, t, q, j):
                    ci[c] = t
                    cj[c] = j
                    c += 1
                    break
    return ci[:c].copy(), cj[:c].copy()


@nb.njit(cache=True)
def pair_innovations(x_pos, P_pos, z, R, ci, cj):  # pragma: no cover - compiled
    """nu (C, r, 2), S^-1 (C, r, 2, 2) and det S (C, r) of the pairs (ci, cj) in every mode (module doc, step 2)."""
    r = x_pos.shape[1]
    C = len(ci)
    nu = np.empty((C, r, 2))
    S_inv = np.empty((C, r, 2, 2))
    det = np.empty((C, r))
    for c in range(C):
        t, j = ci[c], cj[c]
        for q in range(r):
            a = P_pos[t, q, 0, 0] + R[j, 0, 0]
            b = P_pos[t, q, 0, 1] + R[j, 0, 1]
            e = P_pos[t, q, 1, 0] + R[j, 1, 0]
            d = P_pos[t, q, 1, 1] + R[j, 1, 1]
            dt = a * d - b * e
            det[c, q] = dt
            S_inv[c, q, 0, 0] = d / dt
            S_inv[c, q, 1, 1] = a / dt
            S_inv[c, q, 0, 1] = -b / dt
            S_inv[c, q, 1, 0] = -e / dt
            nu[c, q, 0] = z[j, 0] - x_pos[t, q, 0]
            nu[c, q, 1] = z[j, 1] - x_pos[t, q, 1]
    return nu, S_inv, det
