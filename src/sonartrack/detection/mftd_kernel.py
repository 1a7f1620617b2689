"""Compiled N-best pruned MFTD (Im & Kim 1996, paper P1, sec. IV, eqs. 20-22).

The same algorithm as :func:`sonartrack.detection.mftd.pruned_detect` (the readable NumPy
reference, which the tests compare this against), written as loops for numba:

* branch every kept track p to the cells m of frame k and score J = J_p + g y_{k,m} - d2_pm
  (eq. 22, g = rho / (1 + rho), d2 the Mahalanobis distance of the cell centre to the track's
  Kalman prediction, eq. 16);
* keep the best N branches in a bounded min-heap (O(branches log N), no sort of all N x M);
* at the last frame accumulate log-sum-exp of J / 2 over every branch on the fly.

Restricted branching uses a box per parent (tighter than the reference's one box for all parents):
cells with d2 > gamma_p = g max_m y_{k,m} + d2_ref,p + margin score at least ``margin`` below the
parent's branch to the cell nearest its prediction, so what is left out weighs < exp(-margin / 2)
of a kept branch (module doc of ``mftd``).
"""

from __future__ import annotations

import numpy as np

_kernel = None


def _build():
    import numba as nb

    @nb.njit(cache=True, nogil=True)
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

    @nb.njit(cache=True, nogil=True)
    def _push(hj, hp, hc, size, cap, j, p, c):
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

    @nb.njit(cache=True, nogil=True)
    def pruned(yf, n_range, n_doppler, dr, dv, r_min, v_min, S_inv, S_cov, F, L, u, w1, g, n_keep, n_best,
               restrict, margin, final_kept):
        K = yf.shape[0]
        M = n_range * n_doppler
        # parents
        J = np.zeros(1)
        what = np.empty((1, 2))
        what[0, 0] = w1[0]
        what[0, 1] = w1[1]
        hist = np.zeros((1, K), dtype=np.int64)
        n_branches = 0
        stat_half = -np.inf
        for k in range(K):
            last = k == K - 1
            cap = n_best if last else n_keep
            if last and final_kept:
                cap = max(n_best, n_keep)
            hj = np.empty(cap)
            hp = np.empty(cap, dtype=np.int64)
            hc = np.empty(cap, dtype=np.int64)
            size = 0
            a00, a01, a11 = S_inv[k, 0, 0], S_inv[k, 0, 1], S_inv[k, 1, 1]
            flat_prior = a00 == 0.0 and a01 == 0.0 and a11 == 0.0
            ymax = 0.0
            for m in range(M):
                if yf[k, m] > ymax:
                    ymax = yf[k, m]
            lse_m = -np.inf
            lse_s = 0.0
            P = J.shape[0]
            for p in range(P):
                wr, wv = what[p, 0], what[p, 1]
                i0, i1, j0, j1 = 0, n_range, 0, n_doppler
                if restrict and not flat_prior:
                    ic = int(np.floor((wr - r_min) / dr))
                    jc = int(np.floor((wv - v_min) / dv))
                    ic = min(max(ic, 0), n_range - 1)
                    jc = min(max(jc, 0), n_doppler - 1)
                    er = r_min + (ic + 0.5) * dr - wr
                    ev = v_min + (jc + 0.5) * dv - wv
                    d2ref = a00 * er * er + 2.0 * a01 * er * ev + a11 * ev * ev
                    gamma = g * ymax + d2ref + margin
                    hr = int(np.ceil(np.sqrt(gamma * S_cov[k, 0, 0]) / dr)) + 1
                    hd = int(np.ceil(np.sqrt(gamma * S_cov[k, 1, 1]) / dv)) + 1
                    i0, i1 = max(ic - hr, 0), min(ic + hr + 1, n_range)
                    j0, j1 = max(jc - hd, 0), min(jc + hd + 1, n_doppler)
                Jp = J[p]
                for i in range(i0, i1):
                    er = r_min + (i + 0.5) * dr - wr
                    for j in range(j0, j1):
                        m = i * n_doppler + j
                        ev = v_min + (j + 0.5) * dv - wv
                        jb = Jp + g * yf[k, m] - (a00 * er * er + 2.0 * a01 * er * ev + a11 * ev * ev)
                        n_branches += 1
                        if last and not final_kept:
                            x = 0.5 * jb
                            if x > lse_m:
                                lse_s = lse_s * np.exp(lse_m - x) + 1.0
                                lse_m = x
                            else:
                                lse_s += np.exp(x - lse_m)
                        size = _push(hj, hp, hc, size, cap, jb, p, m)
            order = np.argsort(-hj[:size], kind="mergesort")
            newJ = np.empty(size)
            new_hist = np.empty((size, K), dtype=np.int64)
            new_what = np.empty((size, 2))
            for r in range(size):
                q = order[r]
                p = hp[q]
                m = hc[q]
                newJ[r] = hj[q]
                new_hist[r, :] = hist[p, :]
                new_hist[r, k] = m
                if not last:
                    vr = r_min + (m // n_doppler + 0.5) * dr
                    vv = v_min + (m % n_doppler + 0.5) * dv
                    for a in range(2):
                        new_what[r, a] = (F[k, a, 0] * what[p, 0] + F[k, a, 1] * what[p, 1]
                                          + L[k, a, 0] * vr + L[k, a, 1] * vv + u[k, a])
            if last:
                if final_kept:
                    nk = min(n_keep, size)
                    mx = newJ[0] * 0.5
                    s = 0.0
                    for r in range(nk):
                        s += np.exp(0.5 * newJ[r] - mx)
                    stat_half = mx + np.log(s)
                    newJ = newJ[:n_best]
                    new_hist = new_hist[:n_best]
                else:
                    stat_half = lse_m + np.log(lse_s)
                return stat_half, new_hist, newJ, n_branches
            J = newJ
            hist = new_hist
            what = new_what
        return stat_half, hist, J, n_branches

    return pruned


def pruned_kernel():
    """The compiled kernel (built on first use; numba caches it on disk)."""
    global _kernel
    if _kernel is None:
        _kernel = _build()
    return _kernel
