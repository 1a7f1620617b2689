"""OSPA and GOSPA distances between a set of true positions and a set of estimated ones, per time step and
over time (with GOSPA's switching term for track identities).

Sets X = {x_1..x_m} (truth) and Y = {y_1..y_n} (estimates) in R^d, cut-off distance d^(c)(x, y) =
min(c, ||x - y||), order 1 <= p < inf.

**OSPA** (Schuhmacher, Vo, Vo 2008, "A consistent metric for performance evaluation of multi-object
filters", IEEE Trans. Signal Process. 56(8), eq. 3), for m <= n (swap the sets otherwise)::

    d_p^(c)(X, Y) = ( (1/n) ( min_{pi in Pi_n} sum_{i=1}^m d^(c)(x_i, y_pi(i))^p + c^p (n - m) ) )^(1/p)

0 for two empty sets and c when exactly one is empty.

**GOSPA** with alpha = 2 (Rahmathullah, Garcia-Fernandez, Svensson 2017, "Generalized optimal sub-pattern
assignment metric", 20th Int. Conf. Information Fusion, Proposition 1, eq. 2): over the assignments gamma of
pairs (i, j) with ||x_i - y_j|| < c::

    d_p^(c,2)(X, Y) = ( min_gamma [ sum_{(i,j) in gamma} ||x_i - y_j||^p + (c^p / 2) (m + n - 2 |gamma|) ] )^(1/p)

split into localisation = sum_gamma ||x_i - y_j||^p, missed = (c^p / 2) (m - |gamma|) and false =
(c^p / 2) (n - |gamma|) (p-th powers: the distance is (localisation + missed + false)^(1/p)). Both are
solved by one linear assignment of the smaller set into the larger on the cost min(c, ||x - y||)^p (a pair at
the cut-off costs c^p = c^p/2 + c^p/2, a missed and a false target, so dropping it changes nothing).

**Switching** (track identities over time; the term of Stone Soup's ``GOSPAMetric.switching_penalty``, after
the trajectory metric of Garcia-Fernandez, Rahmathullah, Svensson 2020, IEEE Trans. Signal Process. 68,
sec. IV): at each time k the GOSPA assignment gives each true target present an estimate id or none. Against
the target's last recorded assignment (a target is recorded from its first assignment on) a change counts
1/2, and 1 when it goes from one estimate id to another; with s_k the sum of the counts at k::

    S_k = lambda s_k^(1/p),   D_k = (d_k^2 + S_k^2)^(1/2)      (d_k the GOSPA distance at k, alpha = 2)

DEVIATION from Stone Soup (1.9): where one of the two sets is empty at a time step, Stone Soup records no
assignment (its assignment list is empty), so a target left with no estimate at all keeps its last id; here
it loses it (1/2), exactly as a target whose estimates are all beyond the cut-off does. Stone Soup's OSPA of
order p > 1 assigns by the sum of cut-off distances, not of their p-th powers, and so can exceed the minimum
of eq. 3; ours is that minimum (the two agree for p = 1 and whenever both assignments coincide).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require


def _points(a) -> np.ndarray:
    """``a`` as an (k, d) float array; an empty input of any shape is a set of no points."""
    a = np.asarray(a, dtype=float)
    if a.size == 0:
        return np.zeros((0, a.shape[-1] if a.ndim == 2 else 0))
    require(a.ndim == 2, f"positions must be an (m, d) array, one row per point (got shape {a.shape})")
    return a


def _check(c: float, p: float) -> None:
    require(c > 0 and np.isfinite(c), f"the cut-off c must be a positive distance (got {c})")
    require(1 <= p < np.inf, f"the order p must be in [1, inf) (got {p})")


def cutoff_costs(truth, estimate, c: float, p: float) -> np.ndarray:
    """min(c, ||x_i - y_j||)^p of every pair, shape (m, n) (module doc).

    Parameters
    ----------
    truth : array_like, shape (m, d)
        True positions (m, or any one unit).
    estimate : array_like, shape (n, d)
        Estimated positions, same unit.
    c : float
        Cut-off distance, same unit.
    p : float
        Order.

    Returns
    -------
    ndarray, shape (m, n)
        Cut-off distances raised to p.
    """
    x, y = _points(truth), _points(estimate)
    if len(x) == 0 or len(y) == 0:
        return np.zeros((len(x), len(y)))
    require(x.shape[1] == y.shape[1], f"truth and estimates need the same dimension (got {x.shape[1]} and "
                                      f"{y.shape[1]})")
    dist = np.sqrt(((x[:, None, :] - y[None, :, :]) ** 2).sum(axis=-1))
    return np.minimum(dist, c) ** p


def optimal_assignment(costs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The assignment of the smaller side into the larger of least total cost (Kuhn-Munkres / Jonker-Volgenant
    as scipy's ``linear_sum_assignment``): (rows, cols) of the pairs, min(m, n) of them.

    Parameters
    ----------
    costs : ndarray, shape (m, n)
        Pair costs.

    Returns
    -------
    rows, cols : ndarray of intp, shape (min(m, n),)
        The assigned pairs (empty for an empty matrix).
    """
    from scipy.optimize import linear_sum_assignment  # scipy: loaded where a metric is computed

    if costs.size == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    if costs.shape[0] == 1:  # one target (the usual case of a single-target study): the nearest, no solver
        return np.zeros(1, dtype=np.intp), np.array([np.argmin(costs[0])], dtype=np.intp)
    if costs.shape[1] == 1:
        return np.array([np.argmin(costs[:, 0])], dtype=np.intp), np.zeros(1, dtype=np.intp)
    return linear_sum_assignment(costs)


def ospa(truth, estimate, c: float, p: float = 1.0) -> float:
    """OSPA distance of order p with cut-off c between two sets of positions (module doc; Schuhmacher et al.
    2008, eq. 3).

    Parameters
    ----------
    truth : array_like, shape (m, d)
        True positions (any unit; the same for all three distances).
    estimate : array_like, shape (n, d)
        Estimated positions.
    c : float
        Cut-off distance (> 0).
    p : float, default 1
        Order, 1 <= p < inf.

    Returns
    -------
    float
        The OSPA distance, in the unit of the positions (0 for two empty sets, c when one is empty).
    """
    _check(c, p)
    costs = cutoff_costs(truth, estimate, c, p)
    m, n = costs.shape
    if m == 0 and n == 0:
        return 0.0
    rows, cols = optimal_assignment(costs)
    total = costs[rows, cols].sum() + c**p * abs(n - m)
    return float((total / max(m, n)) ** (1.0 / p))


@dataclass(frozen=True, slots=True)
class GospaStep:
    """GOSPA (alpha = 2) of one time step: the distance, its three parts (p-th powers) and the assignment."""

    distance: float  # (localisation + missed + false)^(1/p), unit of the positions
    localisation: float  # sum over assigned pairs of ||x_i - y_j||^p
    missed: float  # (c^p / 2) x the true targets left unassigned
    false: float  # (c^p / 2) x the estimates left unassigned
    truth_to_estimate: np.ndarray  # (m,) index of the estimate assigned to each true target, -1 for none


def gospa(truth, estimate, c: float, p: float = 1.0) -> GospaStep:
    """GOSPA distance (alpha = 2) between two sets of positions, with its parts (module doc; Rahmathullah,
    Garcia-Fernandez, Svensson 2017, Proposition 1).

    Parameters
    ----------
    truth : array_like, shape (m, d)
        True positions (any unit).
    estimate : array_like, shape (n, d)
        Estimated positions, same unit.
    c : float
        Cut-off distance (> 0): pairs at c or beyond are a missed target and a false estimate.
    p : float, default 1
        Order, 1 <= p < inf.

    Returns
    -------
    GospaStep
        The distance (unit of the positions), localisation, missed and false parts (p-th powers), and the
        assignment of each true target (estimate index, -1 for none).
    """
    _check(c, p)
    costs = cutoff_costs(truth, estimate, c, p)
    m, n = costs.shape
    rows, cols = optimal_assignment(costs)
    kept = costs[rows, cols] < c**p  # a pair at the cut-off is a missed and a false target
    rows, cols = rows[kept], cols[kept]
    half = c**p / 2.0
    localisation = float(costs[rows, cols].sum())
    missed, false = half * (m - len(rows)), half * (n - len(rows))
    assigned = np.full(m, -1, dtype=np.intp)
    assigned[rows] = cols
    return GospaStep(float((localisation + missed + false) ** (1.0 / p)), localisation, missed, false, assigned)


def time_steps(truth_time, est_time) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """The distinct times of two tables and the rows of each at each time.

    Parameters
    ----------
    truth_time, est_time : array_like, shapes (M,), (N,)
        The time of each row of the two tables (s).

    Returns
    -------
    times : ndarray, shape (K,)
        The distinct times of both, in order (s).
    truth_rows, est_rows : list of ndarray
        K arrays each: the row indices of each table at each time (possibly empty).
    """
    truth_time, est_time = np.asarray(truth_time, float).ravel(), np.asarray(est_time, float).ravel()
    times = np.union1d(truth_time, est_time)
    if len(times) == 0:
        return times, [], []
    t_order, e_order = np.argsort(truth_time, kind="stable"), np.argsort(est_time, kind="stable")
    t_split = np.searchsorted(truth_time[t_order], times, side="right")[:-1]
    e_split = np.searchsorted(est_time[e_order], times, side="right")[:-1]
    return times, np.split(t_order, t_split), np.split(e_order, e_split)


def ospa_over_time(truth_time, truth_pos, est_time, est_pos, c: float, p: float = 1.0):
    """OSPA at every time of either table (module doc).

    Parameters
    ----------
    truth_time : array_like, shape (M,)
        Time of each true position (s); rows with the same time form one set.
    truth_pos : array_like, shape (M, d)
        True positions.
    est_time : array_like, shape (N,)
        Time of each estimated position (s).
    est_pos : array_like, shape (N, d)
        Estimated positions, same unit as the truth.
    c, p : float
        Cut-off distance (> 0) and order (1 <= p < inf, default 1), as in :func:`ospa`.

    Returns
    -------
    times : ndarray, shape (K,)
        The distinct times of both tables, in order (s).
    ospa : ndarray, shape (K,)
        The OSPA distance at each (unit of the positions).
    """
    times, t_rows, e_rows = time_steps(truth_time, est_time)
    x, y = _points(truth_pos), _points(est_pos)
    return times, np.array([ospa(x[i], y[j], c, p) for i, j in zip(t_rows, e_rows, strict=True)])


@dataclass(frozen=True, slots=True)
class GospaSeries:
    """GOSPA over time (alpha = 2; module doc): one entry per distinct time of the two tables."""

    time_s: np.ndarray  # (K,) the times (s)
    distance: np.ndarray  # (K,) D_k = (d_k^2 + S_k^2)^(1/2), GOSPA with the switching term
    gospa: np.ndarray  # (K,) d_k, GOSPA without it
    localisation: np.ndarray  # (K,) p-th power parts, as GospaStep
    missed: np.ndarray  # (K,)
    false: np.ndarray  # (K,)
    switching: np.ndarray  # (K,) S_k = lambda s_k^(1/p)
    switches: np.ndarray  # (K,) s_k: 1/2 per target gaining or losing an estimate, 1 per change of estimate id


def switch_count(last: dict, truth_ids, assigned_ids) -> float:
    """s_k of one time step (module doc), updating ``last`` (true target id -> its recorded estimate id or None).

    Parameters
    ----------
    last : dict
        Each true target's last recorded estimate id (None: none); updated in place.
    truth_ids : sequence
        Ids of the true targets present at this time.
    assigned_ids : sequence
        The estimate id assigned to each, or None.

    Returns
    -------
    float
        1/2 per target whose assignment appeared or went, 1 per target whose estimate id changed.
    """
    s = 0.0
    for tid, eid in zip(truth_ids, assigned_ids, strict=True):
        if tid not in last:
            if eid is not None:  # recorded from its first assignment on
                last[tid] = eid
            continue
        if last[tid] != eid:
            s += 1.0 if (eid is not None and last[tid] is not None) else 0.5
            last[tid] = eid
    return s


def gospa_over_time(truth_time, truth_id, truth_pos, est_time, est_id, est_pos, c: float, p: float = 1.0,
                    switching_penalty: float = 0.0) -> GospaSeries:
    """GOSPA (alpha = 2) at every time of either table, with the switching term of the identities (module doc).

    Parameters
    ----------
    truth_time, truth_id, truth_pos : array_like, shapes (M,), (M,), (M, d)
        True targets: time (s), target id, position; rows with the same time form one set.
    est_time, est_id, est_pos : array_like, shapes (N,), (N,), (N, d)
        Estimates (tracks): time (s), track id, position in the truth's unit.
    c : float
        Cut-off distance (> 0).
    p : float, default 1
        Order, 1 <= p < inf.
    switching_penalty : float, default 0
        lambda (unit of the positions): the switching term's weight (0: none).

    Returns
    -------
    GospaSeries
        Per time: the distance with and without the switching term, its parts, S_k and s_k.
    """
    require(switching_penalty >= 0, f"the switching penalty must be >= 0 (got {switching_penalty})")
    times, t_rows, e_rows = time_steps(truth_time, est_time)
    x, y = _points(truth_pos), _points(est_pos)
    truth_id, est_id = np.asarray(truth_id).ravel(), np.asarray(est_id).ravel()
    last: dict = {}
    out = np.zeros((5, len(times)))  # d_k, localisation, missed, false, s_k
    for k, (i, j) in enumerate(zip(t_rows, e_rows, strict=True)):
        step = gospa(x[i], y[j], c, p)
        ids = [est_id[j[a]].item() if a >= 0 else None for a in step.truth_to_estimate]
        out[:, k] = (step.distance, step.localisation, step.missed, step.false,
                     switch_count(last, truth_id[i].tolist(), ids))
    switching = switching_penalty * out[4] ** (1.0 / p)
    return GospaSeries(times, np.hypot(out[0], switching), out[0], out[1], out[2], out[3], switching, out[4])


def _injections(m: int, n: int) -> np.ndarray:
    """Every one-to-one map of range(m) into range(n) (m <= n), shape (n! / (n - m)!, m)."""
    from itertools import permutations

    return np.array(list(permutations(range(n), m)), dtype=np.intp).reshape(-1, m)


def _switches(assigned: np.ndarray) -> np.ndarray:
    """s_k of every step (module doc, :func:`switch_count`) from the assignments (K, m), -1 for none."""
    K, m = assigned.shape
    s = np.zeros(K)
    for i in range(m):
        a = assigned[:, i]
        seen = np.cumsum(a >= 0) > 0  # recorded from its first assignment on
        prev = np.concatenate([[-1], a[:-1]])
        change = seen & (np.arange(K) > np.argmax(a >= 0)) & (a != prev)
        s += np.where(change, np.where((a >= 0) & (prev >= 0), 1.0, 0.5), 0.0)
    return s


def gospa_fixed_sets(truth, estimate, c: float, p: float = 1.0, switching_penalty: float = 0.0) -> GospaSeries:
    """GOSPA over time (alpha = 2, with switching; module doc) where the same m targets and n estimates are
    present at every step, vectorised over the steps: what :func:`gospa_over_time` gives for such tables, at array
    speed for the small sets of a tracker study (the assignment by enumerating the n! / (n - m)! one-to-one maps
    at every step at once, so meant for m, n <= 4). Where two assignments cost exactly the same (a tie: only
    likely in one dimension with p = 1) the first map in lexicographic order wins, which keeps the ids in order;
    scipy's solver may pick the other, so the switching terms of the two functions can differ at ties.

    Parameters
    ----------
    truth : array_like, shape (K, m, d)
        True positions at K steps; target i is the same target at every step (its id is i).
    estimate : array_like, shape (K, n, d)
        Estimates at the same steps; estimate j keeps its id j at every step.
    c : float
        Cut-off distance (> 0), unit of the positions.
    p : float, default 1
        Order, 1 <= p < inf.
    switching_penalty : float, default 0
        lambda (unit of the positions).

    Returns
    -------
    GospaSeries
        As :func:`gospa_over_time`, with ``time_s`` the step index 0..K-1.
    """
    _check(c, p)
    require(switching_penalty >= 0, f"the switching penalty must be >= 0 (got {switching_penalty})")
    x, y = np.asarray(truth, float), np.asarray(estimate, float)
    require(x.ndim == 3 and y.ndim == 3 and x.shape[0] == y.shape[0] and x.shape[2] == y.shape[2],
            f"truth (K, m, d) and estimates (K, n, d) must agree in K and d (got {x.shape} and {y.shape})")
    K, m, n = x.shape[0], x.shape[1], y.shape[1]
    swap = m > n  # assign the smaller set into the larger, as optimal_assignment does
    cost = np.minimum(np.sqrt(((x[:, :, None, :] - y[:, None, :, :]) ** 2).sum(axis=-1)), c) ** p  # (K, m, n)
    small, maps = (cost.transpose(0, 2, 1), _injections(n, m)) if swap else (cost, _injections(m, n))
    rows = np.arange(small.shape[1])
    totals = small[:, rows[None, :], maps].sum(axis=-1)  # (K, n_maps)
    best = maps[np.argmin(totals, axis=1)]  # (K, min(m, n))
    pair = small[np.arange(K)[:, None], rows[None, :], best]  # (K, min(m, n))
    kept = pair < c**p
    loc = np.where(kept, pair, 0.0).sum(axis=1)
    n_kept = kept.sum(axis=1)
    missed, false = c**p / 2 * (m - n_kept), c**p / 2 * (n - n_kept)
    d = (loc + missed + false) ** (1.0 / p)
    if swap:  # best maps estimates to targets: invert it for each target's estimate
        assigned = np.full((K, m), -1, dtype=np.intp)
        kk, jj = np.nonzero(kept)
        assigned[kk, best[kk, jj]] = jj
    else:
        assigned = np.where(kept, best, -1)
    s = _switches(assigned)
    switching = switching_penalty * s ** (1.0 / p)
    return GospaSeries(np.arange(K, dtype=float), np.hypot(d, switching), d, loc, missed, false, switching, s)
