"""Exact JPDA marginal association probabilities by a forward-backward pass over tracks (EHM-style).

Joint association events chi assign each track t either no measurement (j = 0) or one measurement
j >= 1 that no other track takes (Bar-Shalom & Fortmann 1988, ch. 9). With per-pair weights
w_tj = P_D N(z_j; z_hat_t, S_t) / lambda  (the likelihood ratio against clutter, lambda the clutter
density) and w_t0 = 1 - P_D P_G, the event probability is P(chi) = prod_t w_{t, chi(t)} / Z and the
marginals are beta_tj = sum_{chi: chi(t) = j} P(chi). (Paper P0, appendix A.1-A.7; JPDA_A multiplies
w_tj by the amplitude likelihood ratio, see ``association/amplitude.py``.)

Enumerating all events costs prod_t (1 + |gate_t|). Instead, as in Maskell, Briers & Wright's
"Efficient Hypothesis Management" (2004), tracks are processed in order and the partial events are
merged by the only thing the remaining tracks care about: the set of used measurements that some
remaining track can still take. With rel_i = union of the gates of tracks i..n-1 and masks M as bit
sets of measurements,

    forward   f_{i+1}(M') = logsumexp over (M, j) -> M' of f_i(M) + log w_ij,
              M' = (M + {j}) & rel_{i+1},  j = 0 or j in gate_i \\ M
    backward  g_i(M) = logsumexp over j of log w_ij + g_{i+1}(M'),     g_n({}) = 0
    marginal  log beta_ij = logsumexp over M of f_i(M) + log w_ij + g_{i+1}(M') - g_0({})

which is exactly the enumeration regrouped (each event is one path through the layers), in log
space throughout. Tracks are first split into clusters that share no gated measurement (they are
independent), and each cluster is solved on its own; a cluster may hold up to 62 distinct gated
measurements (bit masks in int64).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import InputError

_kernel = None
MAX_CLUSTER_MEASUREMENTS = 62


def _build():
    import numba as nb

    @nb.njit(cache=True)
    def _lse(a, b):
        if a == -np.inf:
            return b
        if b == -np.inf:
            return a
        if a > b:
            return a + np.log1p(np.exp(b - a))
        return b + np.log1p(np.exp(a - b))

    @nb.njit(cache=True)
    def _merge(masks, lw):
        """Sort by mask and log-sum-exp equal masks."""
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
        lo, hi = 0, len(masks)
        while lo < hi:
            mid = (lo + hi) // 2
            if masks[mid] < m:
                lo = mid + 1
            else:
                hi = mid
        return lo

    @nb.njit(cache=True)
    def cluster_marginals(ll, lmiss, gate_idx, gate_len, rel):
        """ll (k, m) log weights over the cluster's m measurements (-inf outside the gate), lmiss (k,),
        gate_idx (k, m) the gated measurement indices of each track (first gate_len[t] valid), rel (k+1,)
        masks. Returns log beta (k, m+1), column 0 = no measurement, and log Z."""
        k, m = ll.shape
        f_masks = nb.typed.List()
        f_lw = nb.typed.List()
        f_masks.append(np.zeros(1, dtype=np.int64))
        f_lw.append(np.zeros(1))
        for i in range(k):
            M, W = f_masks[i], f_lw[i]
            cap = len(M) * (gate_len[i] + 1)
            cm = np.empty(cap, dtype=np.int64)
            cw = np.empty(cap)
            n = 0
            nxt = rel[i + 1]
            for s in range(len(M)):
                cm[n] = M[s] & nxt
                cw[n] = W[s] + lmiss[i]
                n += 1
                for q in range(gate_len[i]):
                    j = gate_idx[i, q]
                    bit = np.int64(1) << j
                    if M[s] & bit:
                        continue
                    cm[n] = (M[s] | bit) & nxt
                    cw[n] = W[s] + ll[i, j]
                    n += 1
            mm, ww = _merge(cm[:n], cw[:n])
            f_masks.append(mm)
            f_lw.append(ww)
        # backward over the forward-reachable states
        g = nb.typed.List()
        for i in range(k + 1):
            g.append(np.full(len(f_masks[i]), -np.inf))
        g[k][0] = 0.0
        for i in range(k - 1, -1, -1):
            M = f_masks[i]
            nxt = rel[i + 1]
            for s in range(len(M)):
                acc = -np.inf
                p = _find(f_masks[i + 1], M[s] & nxt)
                acc = _lse(acc, lmiss[i] + g[i + 1][p])
                for q in range(gate_len[i]):
                    j = gate_idx[i, q]
                    bit = np.int64(1) << j
                    if M[s] & bit:
                        continue
                    p = _find(f_masks[i + 1], (M[s] | bit) & nxt)
                    acc = _lse(acc, ll[i, j] + g[i + 1][p])
                g[i][s] = acc
        logz = g[0][0]
        out = np.full((k, m + 1), -np.inf)
        for i in range(k):
            M, W = f_masks[i], f_lw[i]
            nxt = rel[i + 1]
            for s in range(len(M)):
                p = _find(f_masks[i + 1], M[s] & nxt)
                out[i, 0] = _lse(out[i, 0], W[s] + lmiss[i] + g[i + 1][p] - logz)
                for q in range(gate_len[i]):
                    j = gate_idx[i, q]
                    bit = np.int64(1) << j
                    if M[s] & bit:
                        continue
                    p = _find(f_masks[i + 1], (M[s] | bit) & nxt)
                    out[i, j + 1] = _lse(out[i, j + 1], W[s] + ll[i, j] + g[i + 1][p] - logz)
        return out, logz

    return cluster_marginals


def _cluster_kernel():
    global _kernel
    if _kernel is None:
        _kernel = _build()
    return _kernel


def clusters(gated: np.ndarray) -> list[np.ndarray]:
    """Track indices grouped into clusters that share gated measurements (connected components)."""
    n = gated.shape[0]
    parent = list(range(n))

    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for j in range(gated.shape[1]):
        ts = np.nonzero(gated[:, j])[0]
        for t in ts[1:]:
            ra, rb = root(int(ts[0])), root(int(t))
            if ra != rb:
                parent[rb] = ra
    groups: dict[int, list[int]] = {}
    for t in range(n):
        groups.setdefault(root(t), []).append(t)
    return [np.array(g) for g in groups.values()]


def jpda_log_weights(log_lik, log_miss) -> np.ndarray:
    """log beta (n_tracks, n_meas + 1): exact JPDA marginals, column 0 = no measurement (module doc).

    ``log_lik`` (n_tracks, n_meas): log w_tj, -inf where measurement j is outside track t's gate.
    ``log_miss`` (n_tracks,): log w_t0 = log(1 - P_D P_G).
    """
    ll = np.asarray(log_lik, dtype=float)
    lmiss = np.asarray(log_miss, dtype=float)
    if ll.ndim != 2 or lmiss.shape != (ll.shape[0],):
        raise InputError(f"log_lik must be (tracks, measurements) and log_miss (tracks,), got {ll.shape} and {lmiss.shape}")
    n, m = ll.shape
    out = np.full((n, m + 1), -np.inf)
    if n == 0:
        return out
    gated = np.isfinite(ll)
    kernel = _cluster_kernel()
    for c in clusters(gated):
        cols = np.nonzero(gated[c].any(axis=0))[0]
        if len(cols) == 0:
            out[c, 0] = 0.0
            continue
        if len(cols) > MAX_CLUSTER_MEASUREMENTS:
            raise InputError(f"a JPDA cluster gates {len(cols)} measurements (max {MAX_CLUSTER_MEASUREMENTS}): "
                             "tighten the gate or raise the detection threshold")
        sub = np.ascontiguousarray(ll[np.ix_(c, cols)])
        g = np.isfinite(sub)
        k = len(c)
        gate_idx = np.zeros((k, len(cols)), dtype=np.int64)
        gate_len = g.sum(axis=1).astype(np.int64)
        masks = np.zeros(k, dtype=np.int64)
        for t in range(k):
            idx = np.nonzero(g[t])[0]
            gate_idx[t, : len(idx)] = idx
            masks[t] = int(np.sum(np.left_shift(np.int64(1), idx.astype(np.int64)))) if len(idx) else 0
        rel = np.zeros(k + 1, dtype=np.int64)
        for t in range(k - 1, -1, -1):
            rel[t] = rel[t + 1] | masks[t]
        lb, _ = kernel(sub, np.ascontiguousarray(lmiss[c]), gate_idx, gate_len, rel)
        out[c, 0] = lb[:, 0]
        out[np.ix_(c, cols + 1)] = lb[:, 1:]
    return out


def jpda_weights(log_lik, log_miss) -> np.ndarray:
    """beta (n_tracks, n_meas + 1), the exact JPDA marginals (see :func:`jpda_log_weights`)."""
    return np.exp(jpda_log_weights(log_lik, log_miss))


def jpda_brute_force(log_lik, log_miss) -> np.ndarray:
    """The reference: enumerate every joint event (tests only; exponential cost)."""
    import itertools

    ll = np.asarray(log_lik, dtype=float)
    n, m = ll.shape
    options = [[0] + [j + 1 for j in range(m) if np.isfinite(ll[t, j])] for t in range(n)]
    logs, events = [], []
    for ev in itertools.product(*options):
        used = [j for j in ev if j > 0]
        if len(used) != len(set(used)):
            continue
        logs.append(sum(log_miss[t] if j == 0 else ll[t, j - 1] for t, j in enumerate(ev)))
        events.append(ev)
    logs = np.array(logs)
    p = np.exp(logs - logs.max())
    p /= p.sum()
    beta = np.zeros((n, m + 1))
    for w, ev in zip(p, events):
        for t, j in enumerate(ev):
            beta[t, j] += w
    return beta
