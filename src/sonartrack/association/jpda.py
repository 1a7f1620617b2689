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
sets of measurements, a step of track i from state M with option j (j = 0, or j in gate_i \\ M) leads to

    M' = (M + {j}) & rel_{i+1}                                                     (successor)
    forward   f_0({}) = 0,   f_{i+1}(M') = logsumexp over (M, j) -> M' of f_i(M) + log w_ij
    backward  g_n({}) = 0,   g_i(M) = logsumexp over j of log w_ij + g_{i+1}(M')
    marginal  log beta_ij = logsumexp over M of f_i(M) + log w_ij + g_{i+1}(M') - g_0({})

which is exactly the enumeration regrouped (each event is one path through the layers), in log
space throughout. Tracks are first split into clusters that share no gated measurement (they are
independent), and each cluster is solved on its own; a cluster may hold up to 62 distinct gated
measurements (bit masks in int64). Each equation above is one compiled function of
association/jpda_kernel.py, as are the clustering and the layout of each cluster's gates.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import InputError

_kernel = None
MAX_CLUSTER_MEASUREMENTS = 62


def _kernels():
    global _kernel
    if _kernel is None:
        from sonartrack.association import jpda_kernel

        _kernel = jpda_kernel
    return _kernel


def clusters(gated: np.ndarray) -> list[np.ndarray]:
    """Track indices grouped into clusters that share gated measurements (connected components).

    Parameters
    ----------
    gated : ndarray of bool, shape (n_tracks, n_meas)
        True where measurement j is in track t's gate.

    Returns
    -------
    list of ndarray of int
        One array of track indices per cluster.
    """
    labels = _kernels().cluster_labels(np.ascontiguousarray(gated, dtype=bool))
    return [np.nonzero(labels == lab)[0] for lab in np.unique(labels)]


def jpda_log_weights(log_lik, log_miss) -> np.ndarray:
    """Exact JPDA marginal association probabilities, in log space (recursion in the module docstring).

    Parameters
    ----------
    log_lik : array_like, shape (n_tracks, n_meas)
        log w_tj (log of P_D times the likelihood ratio against clutter); -inf where measurement j is
        outside track t's gate.
    log_miss : array_like, shape (n_tracks,)
        log w_t0 = log(1 - P_D P_G).

    Returns
    -------
    ndarray, shape (n_tracks, n_meas + 1)
        log beta; column 0 is "no measurement is the track's", column j + 1 measurement j.

    Raises
    ------
    InputError
        If the shapes disagree, or a cluster gates more than 62 measurements.
    """
    ll = np.ascontiguousarray(log_lik, dtype=float)
    lmiss = np.ascontiguousarray(log_miss, dtype=float)
    if ll.ndim != 2 or lmiss.shape != (ll.shape[0],):
        raise InputError(f"log_lik must be (tracks, measurements) and log_miss (tracks,), got {ll.shape} and "
                         f"{lmiss.shape}")
    if ll.shape[0] == 0:
        return np.full((0, ll.shape[1] + 1), -np.inf)
    k = _kernels()
    out, widest = k.all_marginals(ll, lmiss, k.cluster_labels(np.isfinite(ll)), MAX_CLUSTER_MEASUREMENTS)
    if widest > MAX_CLUSTER_MEASUREMENTS:
        raise InputError(f"a JPDA cluster gates {widest} measurements (max {MAX_CLUSTER_MEASUREMENTS}): "
                         "tighten the gate or raise the detection threshold")
    return out


def jpda_weights(log_lik, log_miss) -> np.ndarray:
    """Exact JPDA marginals beta = exp(:func:`jpda_log_weights`).

    Parameters
    ----------
    log_lik : array_like, shape (n_tracks, n_meas)
        log w_tj, -inf outside the gate.
    log_miss : array_like, shape (n_tracks,)
        log(1 - P_D P_G).

    Returns
    -------
    ndarray, shape (n_tracks, n_meas + 1)
        beta; column 0 = no measurement. Each row sums to 1.
    """
    return np.exp(jpda_log_weights(log_lik, log_miss))


def jpda_brute_force(log_lik, log_miss) -> np.ndarray:
    """Reference JPDA marginals by enumerating every joint event (tests only; exponential cost).

    Parameters
    ----------
    log_lik, log_miss : array_like, shapes (n_tracks, n_meas) and (n_tracks,)
        As :func:`jpda_weights`.

    Returns
    -------
    ndarray, shape (n_tracks, n_meas + 1)
        beta; column 0 = no measurement.
    """
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
    for w, ev in zip(p, events, strict=True):
        for t, j in enumerate(ev):
            beta[t, j] += w
    return beta
