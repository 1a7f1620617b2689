"""Compiled N-best pruned MFTD (Im & Kim 1996, paper P1, sec. IV, eqs. 16, 20-22), in named steps.

The same algorithm as :func:`sonartrack.detection.mftd_reference.pruned_detect` (the readable NumPy
reference, which the tests compare this against), written as loops for numba. One frame k:

1. ``_score_frame``: branch every kept track p to the cells m of its box and score it (eq. 22)

       J_pm = J_p + g y_{k,m} - d2_pm,   g = rho / (1 + rho),
       d2_pm = (v_m - w_p)^T S_k^-1 (v_m - w_p)   (w_p the track's Kalman prediction, eq. 16);

   ``_branch_box`` restricts the cells: d2 > gamma_p = g max_m y_{k,m} + d2_ref,p + margin scores at
   least ``margin`` below the parent's branch to the cell nearest its prediction, so what is left out
   weighs < exp(-margin / 2) of a kept branch (module doc of ``mftd``); the box is per parent
   (tighter than the reference's one box for all parents);
2. ``_heap_offer``: keep the best N branches in a bounded min-heap (O(branches log N), no sort of
   all N x M: the pruning of eq. 20);
3. ``_extend_tracks``: the kept branches best first, their cell histories and, before the last
   frame, their predictions for the next one (eq. 16: w' = F w + L v_m + u);
4. the decision statistic (``S / 2 - const``, see ``prior.prior_constant``): at the last frame the
   log-sum-exp of J / 2 over every branch, accumulated on the fly (``_lse_add``), or over the N kept
   (``_kept_statistic``, eq. 20 to the letter).

Arguments are grouped: ``plane = (n_range, n_doppler, dr, dv, r_min, v_min)``,
``prior = (S_inv, S_cov, F, L, u, w1)`` (arrays of :class:`~sonartrack.detection.prior.KalmanPrior`,
S_cov = inverse of S_inv where it is non-zero) and ``heap = (scores, parents, cells)``.
"""

from __future__ import annotations

import numba as nb
import numpy as np

# module-level functions (not closures): numba's disk cache finds them again in the next process; a kernel
# built inside a closure captures its helpers as dispatcher objects and is recompiled in every process
_jit = nb.njit(cache=True, nogil=True)


@_jit
def _sift_down(hj, hp, hc, size, i):
    while True:
        left = 2 * i + 1
        if left >= size:
            return
        small = left
        right = left + 1
        if right < size and hj[right] < hj[left]:
            small = right
        if hj[small] < hj[i]:
            hj[i], hj[small] = hj[small], hj[i]
            hp[i], hp[small] = hp[small], hp[i]
            hc[i], hc[small] = hc[small], hc[i]
            i = small
        else:
            return

@_jit
def _heap_offer(hj, hp, hc, size, cap, j, p, c):
    """Offer branch (J, parent, cell) to a min-heap holding the best ``cap``; return the new size."""
    if size < cap:
        i = size
        hj[i], hp[i], hc[i] = j, p, c
        while i > 0:
            parent = (i - 1) // 2
            if hj[i] < hj[parent]:
                hj[i], hj[parent] = hj[parent], hj[i]
                hp[i], hp[parent] = hp[parent], hp[i]
                hc[i], hc[parent] = hc[parent], hc[i]
                i = parent
            else:
                break
        return size + 1
    if j > hj[0]:
        hj[0], hp[0], hc[0] = j, p, c
        _sift_down(hj, hp, hc, size, 0)
    return size


@_jit
def _lse_add(lse_m, lse_s, x):
    """Running log-sum-exp: log(lse_s) + lse_m absorbs exp(x), rescaled to the largest term so far."""
    if x > lse_m:
        return x, lse_s * np.exp(lse_m - x) + 1.0
    return lse_m, lse_s + np.exp(x - lse_m)

@_jit
def _branch_box(wr, wv, plane, a00, a01, a11, s_cov, gy_max, margin):
    """Cells [i0, i1) x [j0, j1) covering the ellipse d2 <= gamma_p around prediction (wr, wv).

    gamma_p = g max_m y_{k,m} + d2_ref,p + margin, d2_ref,p the distance to the nearest cell;
    the half-widths are ceil(sqrt(gamma_p S_aa) / cell) + 1 cells, S = S_inv^-1."""
    n_range, n_doppler, dr, dv, r_min, v_min = plane
    ic = min(max(int(np.floor((wr - r_min) / dr)), 0), n_range - 1)
    jc = min(max(int(np.floor((wv - v_min) / dv)), 0), n_doppler - 1)
    er = r_min + (ic + 0.5) * dr - wr
    ev = v_min + (jc + 0.5) * dv - wv
    gamma = gy_max + (a00 * er * er + 2.0 * a01 * er * ev + a11 * ev * ev) + margin
    hr = int(np.ceil(np.sqrt(gamma * s_cov[0, 0]) / dr)) + 1
    hd = int(np.ceil(np.sqrt(gamma * s_cov[1, 1]) / dv)) + 1
    return max(ic - hr, 0), min(ic + hr + 1, n_range), max(jc - hd, 0), min(jc + hd + 1, n_doppler)

@_jit
def _score_frame(yk, J, what, plane, s_inv, s_cov, g, margin, restrict, heap, cap, sum_all):
    """Eq. 22 for every branch p -> m (m in p's box if ``restrict``), each offered to the heap; with
    ``sum_all`` the running log-sum-exp of J / 2 too. Returns (heap size, branches, lse_m, lse_s)."""
    n_range, n_doppler, dr, dv, r_min, v_min = plane
    hj, hp, hc = heap
    a00, a01, a11 = s_inv[0, 0], s_inv[0, 1], s_inv[1, 1]
    boxed = restrict and not (a00 == 0.0 and a01 == 0.0 and a11 == 0.0)  # frame 1's prior is flat
    ymax = 0.0
    for m in range(yk.shape[0]):
        ymax = max(ymax, yk[m])
    gy_max = g * ymax
    size, n_branches, lse_m, lse_s = 0, 0, -np.inf, 0.0
    for p in range(J.shape[0]):
        wr, wv, Jp = what[p, 0], what[p, 1], J[p]
        i0, i1, j0, j1 = 0, n_range, 0, n_doppler
        if boxed:
            i0, i1, j0, j1 = _branch_box(wr, wv, plane, a00, a01, a11, s_cov, gy_max, margin)
        n_branches += (i1 - i0) * (j1 - j0)
        for i in range(i0, i1):
            er = r_min + (i + 0.5) * dr - wr
            for j in range(j0, j1):
                m = i * n_doppler + j
                ev = v_min + (j + 0.5) * dv - wv
                jb = Jp + g * yk[m] - (a00 * er * er + 2.0 * a01 * er * ev + a11 * ev * ev)
                if sum_all:
                    lse_m, lse_s = _lse_add(lse_m, lse_s, 0.5 * jb)
                if size < cap or jb > hj[0]:  # most branches lose to the heap's worst: skip the call
                    size = _heap_offer(hj, hp, hc, size, cap, jb, p, m)
    return size, n_branches, lse_m, lse_s


@_jit
def _extend_tracks(heap, size, hist, what, k, plane, F, L, u, predict):
    """The ``size`` kept branches best first: scores, cell histories (cell m at frame k) and, if
    ``predict``, the predictions for frame k + 1 (eq. 16: w' = F_k w_p + L_k v_m + u_k)."""
    n_range, n_doppler, dr, dv, r_min, v_min = plane
    hj, hp, hc = heap
    order = np.argsort(-hj[:size], kind="mergesort")
    new_J = np.empty(size)
    new_hist = np.empty((size, hist.shape[1]), dtype=np.int64)
    new_what = np.empty((size, 2))
    for r in range(size):
        q = order[r]
        p, m = hp[q], hc[q]
        new_J[r] = hj[q]
        new_hist[r, :] = hist[p, :]
        new_hist[r, k] = m
        if predict:
            vr = r_min + (m // n_doppler + 0.5) * dr
            vv = v_min + (m % n_doppler + 0.5) * dv
            for a in range(2):
                new_what[r, a] = (F[k, a, 0] * what[p, 0] + F[k, a, 1] * what[p, 1]
                                  + L[k, a, 0] * vr + L[k, a, 1] * vv + u[k, a])
    return new_J, new_hist, new_what

@_jit
def _kept_statistic(J, n_keep):
    """log sum_{r < N} exp(J_r / 2) over the N best (sorted) tracks: eq. 20 to the letter."""
    mx = J[0] * 0.5
    s = 0.0
    for r in range(min(n_keep, J.shape[0])):
        s += np.exp(0.5 * J[r] - mx)
    return mx + np.log(s)


@_jit
def pruned(yf, plane, prior, g, margin, n_keep, n_best, restrict, final_kept):
    """Frames (K, M) -> (S / 2 - const, histories (n, K), scores J (n,), branches scored), best first.

    Parameters
    ----------
    yf : numpy.ndarray
        (K, M) frames of the statistic on P1's noise scale, the M = n_range x n_doppler cells of each frame
        flattened.
    plane : tuple
        (n_range, n_doppler, dr, dv, r_min, v_min): the cell counts, cell steps (m, m/s) and first cell edges.
    prior : tuple
        (S_inv, S_cov, F, L, u, w1) of the Kalman prior (module doc).
    g : float
        rho / (1 + rho), rho the design SNR (linear).
    margin : float
        Restriction margin on J (module doc, step 1).
    n_keep : int
        N, the branches kept per frame (eq. 20).
    n_best : int
        Number of best tracks returned.
    restrict : bool
        Whether to restrict each parent's branches to its box (step 1).
    final_kept : bool
        Statistic over the N kept branches (eq. 20) instead of over every branch of the last frame.

    Returns
    -------
    tuple
        (S / 2 - const as a float, histories (n, K) of flat cell numbers, scores J (n,), number of branches
        scored), n <= n_best tracks, best first.
    """
    S_inv, S_cov, F, L, u, w1 = prior
    K = yf.shape[0]
    J = np.zeros(1)
    what = np.empty((1, 2))
    what[0, 0], what[0, 1] = w1[0], w1[1]
    hist = np.zeros((1, K), dtype=np.int64)
    n_branches, lse_m, lse_s = 0, -np.inf, 0.0
    for k in range(K):
        last = k == K - 1
        cap = (max(n_best, n_keep) if final_kept else n_best) if last else n_keep
        heap = (np.empty(cap), np.empty(cap, dtype=np.int64), np.empty(cap, dtype=np.int64))
        size, n, lse_m, lse_s = _score_frame(yf[k], J, what, plane, S_inv[k], S_cov[k], g, margin, restrict,
                                             heap, cap, last and not final_kept)
        n_branches += n
        J, hist, what = _extend_tracks(heap, size, hist, what, k, plane, F, L, u, not last)
    if final_kept:
        return _kept_statistic(J, n_keep), hist[:n_best], J[:n_best], n_branches
    return lse_m + np.log(lse_s), hist, J, n_branches


def pruned_kernel():
    """The compiled pruned-MFTD kernel (compiled on first call; numba caches it on disk). This module imports
    numba: import it lazily, where the kernel is needed.

    Returns
    -------
    callable
        ``pruned(y, plane, arrays, g, margin, N, n_best, restrict, final_kept)`` returning
        (S / 2 - const, flat cell numbers of the best tracks, their scores J, n_branches);
        :func:`detection.mftd.pruned_detect_fast` wraps it.
    """
    return pruned
