"""Compiled chi-square pre-gate of position measurements (numba), for association/likelihood.py.

For n tracks x r modes and m measurements z (m, 2) with covariances R (m, 2, 2), in the notation of
association/likelihood.py (H = [I 0], so H x- = x_pos and H P- H^T = P_pos):

1. candidates -- the (track, measurement) pairs with nu_i^2 <= bound S_ii on both axes i for some mode,
   S_ii = P_pos_ii + R_ii, tested as ``h*h <= bound*P_ii + bound*R_ii``: exactly the test of the NumPy
   pre-gate ``_chi_square_candidates``, so both keep the same pairs, in row-major (track, measurement) order;
2. innovations and gate -- for those pairs and every mode: nu = z - x_pos, S = P_pos + R, det S = a d - b c,
   S^-1 = [[d, -b], [-c, a]] / det S and d2 = nu^T S^-1 nu, with the same floating-point operations, in
   the same order, as the NumPy evaluation (``inv_and_logdet`` in core/gaussian.py, ``mahalanobis2``), so
   the results are identical bit for bit; only the pairs with d2 < gamma in some mode are returned.

The pre-gate is a loop that stops at the first failing axis and the first passing mode, and it only
visits, per track, the measurements whose x lies in a window that contains every one that can pass
(a binary search in the measurements sorted by x): its cost grows with n log m plus the pairs in the
windows, not with n x m; NumPy has to evaluate the whole (n, r, m) test. This module imports numba at
the top: association/likelihood.py imports it on the first large scan, so ``import sonartrack`` stays
fast. Compiled functions are cached on disk.
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
def _passes_some_mode(x_pos, P_pos, z, R, bound, t, j):  # pragma: no cover - compiled
    """Pair (track t, measurement j) passes the per-axis test in some mode (the modes in order)."""
    for q in range(x_pos.shape[1]):  # noqa: SIM110 - a loop, not any() over a generator, for numba
        if _passes(x_pos, P_pos, z, R, bound, t, q, j):
            return True
    return False


@nb.njit(cache=True)
def _axis_windows(x_pos, P_pos, R, bound, axis):  # pragma: no cover - compiled
    """Per track, the interval [low, high] of measurement coordinates on ``axis`` that can pass that axis's
    test in some mode (module doc, step 1): h^2 <= bound P_ii + bound R_ii <= bound P_ii + bound max(R_ii) =: w2
    (rounding is monotone), so |z_i - x_i| <= sqrt(w2) up to round-off, which the margins cover. A track
    that no pair can pass (w2 < 0, or NaN) gets an empty interval."""
    n, r = x_pos.shape[0], x_pos.shape[1]
    r_max = R[:, axis, axis].max()
    low, high = np.full(n, np.inf), np.full(n, -np.inf)
    for t in range(n):
        w2, x_min, x_max = -1.0, np.inf, -np.inf
        for q in range(r):
            v = bound * P_pos[t, q, axis, axis] + bound * r_max
            if v > w2:  # a NaN mode passes nothing and is skipped
                w2 = v
            x_min, x_max = min(x_min, x_pos[t, q, axis]), max(x_max, x_pos[t, q, axis])
        if w2 >= 0.0:
            half = np.sqrt(w2) * (1.0 + 1e-9) + 1e-12 * (abs(x_min) + abs(x_max)) + 1e-300
            low[t], high[t] = x_min - half, x_max + half
    return low, high


@nb.njit(cache=True)
def _windows(x_pos, P_pos, z, R, bound):  # pragma: no cover - compiled
    """The measurements sorted by x (``order``, their y ``zy``) and per track its slice [lo, hi) of them that lies
    in its x interval and its y interval [y_low, y_high] (:func:`_axis_windows`)."""
    order = np.argsort(z[:, 0])
    zx, zy = z[order, 0], z[order, 1]
    x_low, x_high = _axis_windows(x_pos, P_pos, R, bound, 0)
    y_low, y_high = _axis_windows(x_pos, P_pos, R, bound, 1)
    return order, zy, np.searchsorted(zx, x_low, side="left"), np.searchsorted(zx, x_high, side="right"), y_low, y_high


#: 64-bit de Bruijn sequence and its table: the index of the lowest set bit b of a word is
#: _BIT_INDEX[(b * _DE_BRUIJN) >> 58] (mod 2^64), so the set bits of a bit map come out in increasing order.
_DE_BRUIJN = np.uint64(0x03F79D71B4CB0A89)
_BIT_INDEX = np.zeros(64, np.int64)
for _i in range(64):
    _BIT_INDEX[((1 << _i) * 0x03F79D71B4CB0A89 % 2**64) >> 58] = _i


@nb.njit(cache=True)
def _near(t, order, zy, lo, hi, y_low, y_high, near, bits):  # pragma: no cover - compiled
    """Writes the measurements inside track t's x and y intervals to ``near`` in increasing index order (set in
    the all-zero bit map ``bits`` of the m measurements, read back word by word, which leaves it zero);
    returns how many."""
    first, last = len(bits), -1
    for p in range(lo[t], hi[t]):
        if y_low[t] <= zy[p] <= y_high[t]:
            j = order[p]
            w = j >> 6
            bits[w] |= np.uint64(1) << np.uint64(j & 63)
            first, last = min(first, w), max(last, w)
    k = 0
    for w in range(first, last + 1):
        v = bits[w]
        bits[w] = np.uint64(0)
        while v:
            low = v & (~v + np.uint64(1))  # the lowest set bit
            near[k] = w * 64 + _BIT_INDEX[(low * _DE_BRUIJN) >> np.uint64(58)]
            k += 1
            v ^= low
    return k


@nb.njit(cache=True)
def candidate_pairs(x_pos, P_pos, z, R, bound):  # pragma: no cover - compiled
    """The pairs that pass the per-axis pre-gate ``nu_i^2 <= bound S_ii`` in some mode (module docstring, step 1).

    Only the measurements inside each track's x and y windows (a binary search in the measurements sorted
    by x) are tested, in increasing index order; the others cannot pass, so the pairs are exactly those of
    testing every (track, measurement).

    Parameters
    ----------
    x_pos : ndarray, shape (n, r, 2)
        Predicted positions H x- (m).
    P_pos : ndarray, shape (n, r, 2, 2)
        Their covariances H P- H^T (m^2).
    z : ndarray, shape (m, 2)
        Measured positions (m).
    R : ndarray, shape (m, 2, 2)
        Measurement covariances (m^2).
    bound : float
        Gate size gamma with its round-off margin.

    Returns
    -------
    ci, cj : ndarray of int64, shape (C,)
        Track and measurement of each candidate pair, row-major.
    """
    n, m = x_pos.shape[0], z.shape[0]
    if n == 0 or m == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    order, zy, lo, hi, y_low, y_high = _windows(x_pos, P_pos, z, R, bound)
    size = max(1, np.maximum(hi - lo, 0).sum())
    ci, cj = np.empty(size, np.int64), np.empty(size, np.int64)
    near, bits = np.empty(m, np.int64), np.zeros((m + 63) // 64, np.uint64)
    c = 0
    for t in range(n):
        for j in near[:_near(t, order, zy, lo, hi, y_low, y_high, near, bits)]:
            if _passes_some_mode(x_pos, P_pos, z, R, bound, t, j):
                ci[c], cj[c] = t, j
                c += 1
    return ci[:c].copy(), cj[:c].copy()


@nb.njit(cache=True)
def _gate(x_pos, P_pos, z, R, t, j, gamma, slot, nu, S_inv, det, d2):  # pragma: no cover - compiled
    """nu, S^-1, det S and d2 of pair (t, j) in every mode, written at ``slot`` (module doc, step 2); returns
    (d2 < gamma in some mode, det S > 0 in every mode). d2 is association/likelihood.py's ``mahalanobis2``,
    n0 S00 n0 + n0 S01 n1 + n1 S10 n0 + n1 S11 n1 in that order (as einsum sums)."""
    inside, positive = False, True
    for q in range(x_pos.shape[1]):
        a = P_pos[t, q, 0, 0] + R[j, 0, 0]
        b = P_pos[t, q, 0, 1] + R[j, 0, 1]
        e = P_pos[t, q, 1, 0] + R[j, 1, 0]
        d = P_pos[t, q, 1, 1] + R[j, 1, 1]
        dt = a * d - b * e
        positive &= dt > 0.0
        s00, s11, s01, s10 = d / dt, a / dt, -b / dt, -e / dt
        n0, n1 = z[j, 0] - x_pos[t, q, 0], z[j, 1] - x_pos[t, q, 1]
        dd = n0 * s00 * n0 + n0 * s01 * n1 + n1 * s10 * n0 + n1 * s11 * n1
        det[slot, q], d2[slot, q] = dt, dd
        S_inv[slot, q, 0, 0], S_inv[slot, q, 1, 1], S_inv[slot, q, 0, 1], S_inv[slot, q, 1, 0] = s00, s11, s01, s10
        nu[slot, q, 0], nu[slot, q, 1] = n0, n1
        inside |= dd < gamma
    return inside, positive


@nb.njit(cache=True)
def gated_pairs(x_pos, P_pos, z, R, bound, gamma):  # pragma: no cover - compiled
    """The pairs that pass the pre-gate and then the chi-square gate d2 < gamma in some mode (module docstring).

    Outputs are views of buffers sized for every pair in the x windows (np.empty: only the pages written
    are touched).

    Parameters
    ----------
    x_pos, P_pos, z, R, bound
        As :func:`candidate_pairs`: predicted positions (m) and covariances (m^2), measurements (m) and their
        covariances (m^2), the pre-gate size (gamma with its round-off margin).
    gamma : float
        Chi-square gate size.

    Returns
    -------
    ti, mi : ndarray of int64, shape (G,)
        The gated pairs, row-major.
    nu : ndarray, shape (G, r, 2)
        Innovations (m).
    S_inv : ndarray, shape (G, r, 2, 2)
        Inverse innovation covariances (1/m^2).
    det : ndarray, shape (G, r)
        det S (m^4).
    d2 : ndarray, shape (G, r)
        Squared Mahalanobis distances.
    all_positive : bool
        Whether det S > 0 for every pre-gated pair (NumPy's ``inv_and_logdet`` raises otherwise).
    """
    n, r, m = x_pos.shape[0], x_pos.shape[1], z.shape[0]
    if n == 0 or m == 0:
        order, zy = np.zeros(0, np.int64), np.zeros(0)
        lo, hi, y_low, y_high = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n), np.zeros(n)
    else:
        order, zy, lo, hi, y_low, y_high = _windows(x_pos, P_pos, z, R, bound)
    size = max(1, np.maximum(hi - lo, 0).sum())
    ti, mi = np.empty(size, np.int64), np.empty(size, np.int64)
    nu, S_inv, det, d2 = np.empty((size, r, 2)), np.empty((size, r, 2, 2)), np.empty((size, r)), np.empty((size, r))
    G, all_positive = 0, True
    near, bits = np.empty(m, np.int64), np.zeros((m + 63) // 64, np.uint64)
    for t in range(n):
        for j in near[:_near(t, order, zy, lo, hi, y_low, y_high, near, bits)]:
            if not _passes_some_mode(x_pos, P_pos, z, R, bound, t, j):
                continue
            inside, positive = _gate(x_pos, P_pos, z, R, t, j, gamma, G, nu, S_inv, det, d2)
            all_positive &= positive
            if inside:  # keep slot G: the pair is validated
                ti[G], mi[G] = t, j
                G += 1
    return ti[:G], mi[:G], nu[:G], S_inv[:G], det[:G], d2[:G], all_positive
