"""Compiled steps of the exact JPDA marginals (numba): forward, backward, marginals (association/jpda.py).

Each function is one equation of association/jpda.py's module doc, over the bit-mask states of one
cluster of tracks. This module imports numba at the top: association/jpda.py imports it lazily, on the
first JPDA call, so that ``import sonartrack`` stays fast. Compiled functions are cached on disk.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def _lse(a, b):
    """log(exp(a) + exp(b)), exact at -inf."""
    if a == -np.inf:
        return b
    if b == -np.inf:
        return a
    if a > b:
        return a + np.log1p(np.exp(b - a))
    return b + np.log1p(np.exp(a - b))


@nb.njit(cache=True)
def _merge(masks, lw):
    """Sort by mask and log-sum-exp equal masks: the states of one layer."""
    order = np.argsort(masks, kind="mergesort")
    out_m = np.empty(len(masks), dtype=np.int64)
    out_w = np.empty(len(masks))
    n = 0
    for q in range(len(order)):
        i = order[q]
        if n > 0 and out_m[n - 1] == masks[i]:
            out_w[n - 1] = _lse(out_w[n - 1], lw[i])
        else:
            out_m[n] = masks[i]
            out_w[n] = lw[i]
            n += 1
    return out_m[:n].copy(), out_w[:n].copy()


@nb.njit(cache=True)
def _find(masks, m):
    """Index of mask ``m`` in the sorted ``masks`` (binary search)."""
    lo, hi = 0, len(masks)
    while lo < hi:
        mid = (lo + hi) // 2
        if masks[mid] < m:
            lo = mid + 1
        else:
            hi = mid
    return lo


@nb.njit(cache=True)
def _successors(M, i, ll, lmiss, gate_idx, gate_len, nxt, out_m, out_w, out_j):
    """The options of track i from state M, written to the buffers: successor masks M', log w_ij and the
    column j + 1 of beta (0 = miss). Returns how many."""
    out_m[0], out_w[0], out_j[0] = M & nxt, lmiss[i], 0
    n = 1
    for q in range(gate_len[i]):
        j = gate_idx[i, q]
        bit = np.int64(1) << j
        if M & bit:
            continue  # measurement j is already taken in this partial event
        out_m[n], out_w[n], out_j[n] = (M | bit) & nxt, ll[i, j], j + 1
        n += 1
    return n


@nb.njit(cache=True)
def _buffers(size):
    return np.empty(size, dtype=np.int64), np.empty(size), np.empty(size, dtype=np.int64)


@nb.njit(cache=True)
def forward(ll, lmiss, gate_idx, gate_len, rel):
    """Forward pass ``f_{i+1}(M') = logsumexp over (M, j) -> M' of f_i(M) + log w_ij`` (association/jpda.py).

    Parameters
    ----------
    ll : ndarray, shape (k, m)
        log w_tj of the cluster's tracks over its measurements (-inf outside the gate).
    lmiss : ndarray, shape (k,)
        log w_t0 = log(1 - P_D P_G).
    gate_idx, gate_len, rel
        Gate layout of the cluster (:func:`gate_layout`).

    Returns
    -------
    f_masks, f_lw : numba typed lists of k + 1 arrays
        Per layer i, the reachable bit-mask states M (sorted) and log f_i(M).
    """
    k = ll.shape[0]
    f_masks = nb.typed.List()
    f_lw = nb.typed.List()
    f_masks.append(np.zeros(1, dtype=np.int64))
    f_lw.append(np.zeros(1))
    for i in range(k):
        M, W = f_masks[i], f_lw[i]
        cm = np.empty(len(M) * (gate_len[i] + 1), dtype=np.int64)
        cw = np.empty(len(cm))
        cj = np.empty(len(cm), dtype=np.int64)
        n = 0
        for s in range(len(M)):
            c = _successors(M[s], i, ll, lmiss, gate_idx, gate_len, rel[i + 1], cm[n:], cw[n:], cj[n:])
            cw[n:n + c] += W[s]
            n += c
        mm, ww = _merge(cm[:n], cw[:n])
        f_masks.append(mm)
        f_lw.append(ww)
    return f_masks, f_lw


@nb.njit(cache=True)
def backward(f_masks, ll, lmiss, gate_idx, gate_len, rel):
    """Backward pass ``g_i(M) = logsumexp over j of log w_ij + g_{i+1}(M')``, ``g_k({}) = 0`` (association/jpda.py).

    Evaluated over the forward-reachable states only.

    Parameters
    ----------
    f_masks : numba typed list of arrays
        States of each layer (:func:`forward`).
    ll, lmiss, gate_idx, gate_len, rel
        As :func:`forward`.

    Returns
    -------
    numba typed list of k + 1 arrays
        log g_i(M) for each state of each layer.
    """
    k = ll.shape[0]
    g = nb.typed.List()
    for i in range(k + 1):
        g.append(np.full(len(f_masks[i]), -np.inf))
    g[k][0] = 0.0
    for i in range(k - 1, -1, -1):
        M = f_masks[i]
        sm, sw, sj = _buffers(gate_len[i] + 1)
        for s in range(len(M)):
            c = _successors(M[s], i, ll, lmiss, gate_idx, gate_len, rel[i + 1], sm, sw, sj)
            acc = -np.inf
            for q in range(c):
                acc = _lse(acc, sw[q] + g[i + 1][_find(f_masks[i + 1], sm[q])])
            g[i][s] = acc
    return g


@nb.njit(cache=True)
def marginals(f_masks, f_lw, g, ll, lmiss, gate_idx, gate_len, rel):
    """``log beta_ij = logsumexp over M of f_i(M) + log w_ij + g_{i+1}(M') - log Z``, ``log Z = g_0({})``.

    Parameters
    ----------
    f_masks, f_lw
        Forward layers (:func:`forward`).
    g
        Backward layers (:func:`backward`).
    ll, lmiss, gate_idx, gate_len, rel
        As :func:`forward`.

    Returns
    -------
    log_beta : ndarray, shape (k, m + 1)
        Marginals, column 0 = no measurement.
    log_z : float
        Log normaliser over all joint events.
    """
    k, m = ll.shape
    logz = g[0][0]
    out = np.full((k, m + 1), -np.inf)
    for i in range(k):
        M, W = f_masks[i], f_lw[i]
        sm, sw, sj = _buffers(gate_len[i] + 1)
        for s in range(len(M)):
            c = _successors(M[s], i, ll, lmiss, gate_idx, gate_len, rel[i + 1], sm, sw, sj)
            for q in range(c):
                p = _find(f_masks[i + 1], sm[q])
                out[i, sj[q]] = _lse(out[i, sj[q]], W[s] + sw[q] + g[i + 1][p] - logz)
    return out, logz


@nb.njit(cache=True)
def cluster_marginals(ll, lmiss, gate_idx, gate_len, rel):
    """Exact JPDA marginals of one cluster: forward, backward, marginals.

    Parameters
    ----------
    ll : ndarray, shape (k, m)
        log weights over the cluster's m measurements (-inf outside the gate).
    lmiss : ndarray, shape (k,)
        log miss weights.
    gate_idx : ndarray of int64, shape (k, m)
        Gated measurement indices of each track (first ``gate_len[t]`` valid).
    gate_len : ndarray of int64, shape (k,)
        Gate sizes.
    rel : ndarray of int64, shape (k + 1,)
        Bit masks of the measurements tracks i..k-1 can take.

    Returns
    -------
    log_beta : ndarray, shape (k, m + 1)
        Marginals, column 0 = no measurement.
    log_z : float
        Log normaliser.
    """
    f_masks, f_lw = forward(ll, lmiss, gate_idx, gate_len, rel)
    g = backward(f_masks, ll, lmiss, gate_idx, gate_len, rel)
    return marginals(f_masks, f_lw, g, ll, lmiss, gate_idx, gate_len, rel)


@nb.njit(cache=True)
def _root(parent, a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@nb.njit(cache=True)
def cluster_labels(gated):
    """Cluster label of each track: tracks that share a gated measurement, transitively (union-find); from the
    gates ``gated`` (bool, (n, m)) the cluster's smallest track index per track (int64, (n,))."""
    n, m = gated.shape
    parent = np.arange(n)
    for j in range(m):
        first = -1
        for t in range(n):
            if gated[t, j]:
                if first < 0:
                    first = t
                else:
                    ra, rb = _root(parent, first), _root(parent, t)
                    parent[max(ra, rb)] = min(ra, rb)
    labels = np.empty(n, dtype=np.int64)
    for t in range(n):
        labels[t] = _root(parent, t)
    return labels


@nb.njit(cache=True)
def gate_layout(gated):
    """Gate layout of a cluster for the bit-mask recursion.

    Parameters
    ----------
    gated : ndarray of bool, shape (k, m)
        Gates of the cluster's tracks over its measurements (m <= 62).

    Returns
    -------
    gate_idx : ndarray of int64, shape (k, m)
        Gated measurement indices of each track (first ``gate_len[t]`` valid).
    gate_len : ndarray of int64, shape (k,)
        Gate sizes.
    rel : ndarray of int64, shape (k + 1,)
        ``rel[i]``: bit mask of the measurements tracks i..k-1 can take (``rel[k] = 0``).
    """
    k, m = gated.shape
    gate_idx = np.zeros((k, m), dtype=np.int64)
    gate_len = np.zeros(k, dtype=np.int64)
    rel = np.zeros(k + 1, dtype=np.int64)
    for t in range(k - 1, -1, -1):
        mask = np.int64(0)
        for j in range(m):
            if gated[t, j]:
                gate_idx[t, gate_len[t]] = j
                gate_len[t] += 1
                mask |= np.int64(1) << j
        rel[t] = rel[t + 1] | mask
    return gate_idx, gate_len, rel


@nb.njit(cache=True)
def all_marginals(ll, lmiss, labels, max_cols):
    """log beta of every cluster, each solved on its own over its own gated measurements (in increasing order).

    Parameters
    ----------
    ll : ndarray, shape (n, m)
        log w_tj (-inf outside the gate).
    lmiss : ndarray, shape (n,)
        log miss weights.
    labels : ndarray of int64, shape (n,)
        Cluster labels (:func:`cluster_labels`).
    max_cols : int
        Widest cluster solved (measurements); wider ones are skipped (left at -inf).

    Returns
    -------
    log_beta : ndarray, shape (n, m + 1)
        Marginals, column 0 = no measurement.
    widest : int
        Measurements of the widest cluster.
    """
    n, m = ll.shape
    out = np.full((n, m + 1), -np.inf)
    widest = 0
    for lab in range(n):
        tracks = np.nonzero(labels == lab)[0]
        if len(tracks) == 0:
            continue
        used = np.zeros(m, dtype=np.bool_)
        for t in tracks:
            used |= np.isfinite(ll[t])
        cols = np.nonzero(used)[0]
        widest = max(widest, len(cols))
        if len(cols) == 0:
            out[tracks, 0] = 0.0
            continue
        if len(cols) > max_cols:
            continue
        sub = np.empty((len(tracks), len(cols)))
        for a in range(len(tracks)):
            sub[a] = ll[tracks[a]][cols]
        gate_idx, gate_len, rel = gate_layout(np.isfinite(sub))
        lb, _ = cluster_marginals(sub, lmiss[tracks], gate_idx, gate_len, rel)
        for a in range(len(tracks)):
            out[tracks[a], 0] = lb[a, 0]
            out[tracks[a]][cols + 1] = lb[a, 1:]
    return out, widest
