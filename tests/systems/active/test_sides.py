"""Side decision of the active chain's tracks: the CV fit against an independent least squares, a straight array
that decides nothing, and a turning array that decides the true side (and calls the mirror track a ghost)."""

import numpy as np

from sonartrack.systems.active.contacts import Contacts
from sonartrack.systems.active.sides import MIN_LOG_LR, SideTracker, _CvFit


def test_cv_fit_matches_whitened_least_squares():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 900, 12))
    z = np.stack([100 + 2 * t, -50 + 0.5 * t], -1) + rng.normal(0, 40, (12, 2))
    L = rng.normal(0, 1, (12, 2, 2))
    R = L @ np.swapaxes(L, 1, 2) * 900 + np.eye(2) * 400
    sums = _CvFit()
    for k in range(12):
        sums.add(t[k], z[k], R[k])
    # independent: stack the whitened system C^-1 A x = C^-1 z (R = C C^T) and solve it with lstsq
    rows, rhs = [], []
    for k in range(12):
        Ci = np.linalg.inv(np.linalg.cholesky(R[k]))
        A = np.hstack([np.eye(2), t[k] * np.eye(2)])
        rows.append(Ci @ A)
        rhs.append(Ci @ z[k])
    A, b = np.vstack(rows), np.concatenate(rhs)
    x = np.linalg.lstsq(A, b, rcond=None)[0]
    chi2 = float(np.sum((A @ x - b) ** 2))
    logdet = sum(np.log(np.linalg.det(2 * np.pi * R[k])) for k in range(12))
    assert abs(sums.log_likelihood() - (-0.5 * (chi2 + logdet))) < 1e-6 * abs(logdet)


def _mirror(xy, heading):
    a = np.array([np.sin(heading), np.cos(heading)])
    return 2.0 * (xy @ a) * a - xy


def _run(headings, sd=30.0, seed=0):
    """A CV target at 5-6 km seen from a receiver at the origin whose axis heading follows ``headings``; a track
    sits on the target (id 1) and one on its mirror (id 2). Returns the decisions."""
    rng = np.random.default_rng(seed)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=0)
    R = np.eye(2) * sd**2
    P = np.diag([sd**2, sd**2, 1.0, 1.0])
    for k, h in enumerate(headings):
        t = 30.0 * k
        true = np.array([4000.0 + 3.0 * t, 3000.0 - 2.0 * t])
        z = true + rng.normal(0, sd, 2)
        xy = np.stack([z, _mirror(z, h)])
        c = Contacts(np.array([k, k]), np.array([t, t]), np.array([k, k]), np.array([1, -1], np.int8), xy,
                     np.stack([R, R]), np.full(2, np.nan), np.full(2, 5000.0), np.ones(2))
        x = np.array([[*true, 3.0, -2.0], [*_mirror(true, h), 0.0, 0.0]])
        st.update(t, h, c, np.array([1, 2]), x, np.stack([P, P]),
                  lambda _t, p, h=h: np.where(np.sin(np.arctan2(p[:, 0], p[:, 1]) - h) >= 0, 1, -1))
    return st.result()


def test_straight_array_decides_nothing():
    d = _run(np.zeros(40))
    # the mirror of a CV target about a fixed axis is a CV target, isotropic errors: equal fits, ln LR = 0
    np.testing.assert_allclose(d.log_lr, 0.0, atol=1e-6)
    assert list(d.decision) == ["undecided", "undecided"]


def test_turning_array_decides_the_true_side_and_the_ghost():
    h = np.deg2rad(np.concatenate([np.zeros(15), np.linspace(0, -60, 10), np.full(15, -60.0)]))
    d = _run(h)
    k1, k2 = d.of(1), d.of(2)
    assert d.decision[k1] == "track" and d.log_lr[k1] >= MIN_LOG_LR
    assert d.decision[k2] == "mirror" and d.log_lr[k2] <= -MIN_LOG_LR
    # the target (east of a receiver heading north, then north-west) is on the starboard side
    assert d.side[k1] == "starboard" and d.side[k2] == "starboard"
    assert np.isfinite(d.resolved_s[k1]) and 15 * 30.0 <= d.resolved_s[k1] <= 39 * 30.0


def _brute_capped_chi2(t, z, sd, cap):
    """Global minimum over the CV motion of sum_k min(r_k, cap): at it the contacts under the cap are a subset
    whose least-squares fit scores no worse, and every subset's fit is a candidate, so the best subset is it."""
    n = len(t)
    A = np.stack([np.hstack([np.eye(2), tk * np.eye(2)]) for tk in t])
    best = np.inf
    for mask in range(1, 2**n):
        keep = np.array([(mask >> k) & 1 for k in range(n)], bool)
        if keep.sum() >= 2:
            p = np.linalg.lstsq(A[keep].reshape(-1, 4), z[keep].reshape(-1), rcond=None)[0]
            best = min(best, float(np.minimum(np.sum((z - A @ p) ** 2, axis=1) / sd**2, cap).sum()))
    return best


def test_capped_fit_is_near_the_best_subset_fit():
    # ln L with each chi-square capped at gamma, minimised over the CV motion (a local search, taken within 1 of
    # the global minimum) against the brute-force global minimum, on 9 contacts with 0-3 strays and some contacts
    # the track's own (live)
    cap, sd = 9.21, 30.0
    R = np.eye(2) * sd**2
    logdet = np.log(np.linalg.det(2 * np.pi * R))
    for seed in range(10):
        rng = np.random.default_rng(seed)
        t = np.arange(9) * 30.0
        z = np.stack([1000 + 3 * t, 2000 - 2 * t], -1) + rng.normal(0, sd, (9, 2))
        strays = rng.choice(9, rng.integers(0, 4), replace=False)
        z[strays] += rng.normal(0, 500, (len(strays), 2))
        live = rng.random(9) < 0.6
        fit = _CvFit(cap)
        for k in range(9):
            fit.add(t[k], z[k], R, live=bool(live[k]))
        got = -2 * fit.log_likelihood() - 9 * logdet
        best = _brute_capped_chi2(t, z, sd, cap)
        assert best - 1e-6 <= got <= best + 1.0, (seed, got, best)  # ln L within half a nat


def test_two_strays_cost_the_cap_each():
    rng = np.random.default_rng(5)
    t = np.arange(9) * 30.0
    z = np.stack([1000 + 3 * t, 2000 - 2 * t], -1) + rng.normal(0, 30, (9, 2))
    z[[2, 6]] += [[900.0, -400.0], [-300.0, 700.0]]
    R, cap = np.eye(2) * 900.0, 9.21
    fit, rest = _CvFit(cap), _CvFit()
    for k in range(9):
        fit.add(t[k], z[k], R)
        if k not in (2, 6):
            rest.add(t[k], z[k], R)
    strays = 0.5 * (2 * cap + 2 * np.log(np.linalg.det(2 * np.pi * R)))
    assert abs(fit.log_likelihood() - (rest.log_likelihood() - strays)) < 1e-6


def test_twins_both_decided_on_their_side_are_neither_decided_nor_rejected():
    # a track and its mirror twin each with ln LR above the threshold "on its side": one target cannot be on both
    # sides, so neither is decided and neither is rejected (GhostDeleter deleted both before: bench_active_turns)
    st = SideTracker()
    thr = st.min_log_lr
    st._history = {1: [(0.0, thr + 1.0)], 2: [(0.0, thr + 3.0)], 3: [(0.0, -(thr + 1.0))], 4: [(0.0, thr + 1.0)]}
    st._twins = {1: 2, 2: 1, 3: 4, 4: 3}
    assert st.decision(1) == 0 and st.decision(2) == 0
    assert not st.rejected(1) and not st.rejected(2)
    # a consistent pair: 4 on its side, 3 a ghost
    assert st.decision(4) == 1 and st.decision(3) == -1 and st.rejected(3) and not st.rejected(4)
    # below the threshold the twin does not contradict
    st._history[2] = [(0.0, thr - 0.5)]
    assert st.decision(1) == 1 and st.rejected(2)
    # both on their side, but the pair's mean view (ln LR_1 - ln LR_2) / 2 reaches the threshold: 1 decided
    st._history[2] = [(0.0, thr + 0.5)]
    st._history[1] = [(0.0, 3.0 * thr + 1.0)]
    # (the twin is then decided by the same mean view: its mirror, -1; it was left undecided, but rejected)
    assert st.decision(1) == 1 and st.decision(2) == -1 and st.rejected(2) and not st.rejected(1)
    st._history[1] = [(0.0, 3.0 * thr + 0.4)]
    assert st.decision(1) == 0 and not st.rejected(2)


def test_twins_both_decided_ghosts_are_judged_by_their_mean_view():
    # of a detection's two contacts one is the echo's: a track and its twin cannot both be ghosts either
    st = SideTracker()
    thr = st.min_log_lr
    st._history = {1: [(0.0, -(thr + 1.0))], 2: [(0.0, -(thr + 3.0))]}
    st._twins = {1: 2, 2: 1}
    assert st.decision(1) == 0 and st.decision(2) == 0 and not st.rejected(1) and not st.rejected(2)
    st._history[2] = [(0.0, -(3.0 * thr + 1.0))]  # mean view (ln LR_1 - ln LR_2) / 2 = thr + 0.5 / ... > thr
    assert st.decision(1) == 1 and st.decision(2) == -1 and st.rejected(2)


def test_a_track_on_a_decided_track_s_mirror_is_rejected_twin_or_not():
    # track 3 took the mirror contacts of decided track 1 on 3 pings, but its twin is 4 (more shared pings)
    st = SideTracker()
    thr = st.min_log_lr
    st._history = {1: [(0.0, thr + 1.0)]}
    st._shared = {(1, 3): 3, (3, 4): 5, (1, 6): 4, (1, 5): 2, (5, 7): 9}
    st._twins = st.twins()
    assert st.twin_of(3) == 4 and st.twin_of(1) == 6 and st.twin_of(5) == 7
    assert st.rejected(3) and st.rejected(6)
    assert not st.rejected(5)  # 2 pings: a crossing of the mirror, not a ghost
    st._history[1] = [(0.0, thr - 0.5)]
    assert not st.rejected(3)  # undecided: nothing rejects it
