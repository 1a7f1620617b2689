"""OSPA and GOSPA (metrics/ospa.py): hand-worked cases, the closed-form minimum by brute force, and Stone Soup's
OSPAMetric / GOSPAMetric (an independent implementation) on random sets, empty sets and track switches."""

import itertools

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.metrics.ospa import gospa, gospa_fixed_sets, gospa_over_time, ospa, ospa_over_time


def brute_force_ospa(x, y, c, p):
    """Schuhmacher et al. 2008, eq. 3 by enumerating every injection of the smaller set into the larger."""
    x, y = (x, y) if len(x) <= len(y) else (y, x)
    m, n = len(x), len(y)
    if n == 0:
        return 0.0
    best = min(sum(min(c, np.linalg.norm(x[i] - y[j])) ** p for i, j in enumerate(perm))
               for perm in itertools.permutations(range(n), m))
    return ((best + c**p * (n - m)) / n) ** (1 / p)


def brute_force_gospa(x, y, c, p):
    """Rahmathullah et al. 2017, Prop. 1 (alpha = 2) by enumerating every partial assignment."""
    best = c**p / 2 * (len(x) + len(y))  # nothing assigned
    for k in range(1, min(len(x), len(y)) + 1):
        for rows in itertools.combinations(range(len(x)), k):
            for cols in itertools.permutations(range(len(y)), k):
                d = [np.linalg.norm(x[i] - y[j]) for i, j in zip(rows, cols, strict=True)]
                if max(d) < c:
                    best = min(best, sum(v**p for v in d) + c**p / 2 * (len(x) + len(y) - 2 * k))
    return best ** (1 / p)


# ---- hand-worked


@pytest.mark.parametrize("p", [1.0, 2.0, 3.5])
def test_one_truth_one_estimate_inside_the_cutoff_is_their_distance(p):
    assert ospa([[0.0, 0.0]], [[3.0, 4.0]], c=10.0, p=p) == pytest.approx(5.0, rel=1e-12)
    g = gospa([[0.0, 0.0]], [[3.0, 4.0]], c=10.0, p=p)
    assert g.distance == pytest.approx(5.0, rel=1e-12) and g.missed == 0 and g.false == 0
    assert list(g.truth_to_estimate) == [0]


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_all_missed_is_the_cutoff(p):
    assert ospa([[0.0, 0.0], [5.0, 5.0]], np.zeros((0, 2)), c=7.0, p=p) == 7.0
    assert ospa([[0.0, 0.0]], [[100.0, 0.0]], c=7.0, p=p) == pytest.approx(7.0)  # beyond c: as missed
    assert ospa([], [], c=7.0, p=p) == 0.0
    g = gospa([[0.0, 0.0], [5.0, 5.0]], [], c=7.0, p=p)  # two missed: (2 c^p / 2)^(1/p)
    assert g.distance == pytest.approx((7.0**p) ** (1 / p)) and g.missed == pytest.approx(7.0**p) and g.false == 0


def test_gospa_parts_by_hand():
    # truth (0,0) and (100,0); estimates (3,4) [5 m from the first], (0,50) and (7,7): c = 10, p = 2
    g = gospa([[0, 0], [100, 0]], [[3, 4], [0, 50], [7, 7]], c=10.0, p=2.0)
    assert g.localisation == pytest.approx(25.0)  # 5^2
    assert g.missed == pytest.approx(50.0) and g.false == pytest.approx(100.0)  # 1 and 2 times c^2 / 2
    assert g.distance == pytest.approx(np.sqrt(175.0)) and list(g.truth_to_estimate) == [0, -1]


def test_ospa_is_the_minimum_of_eq3():
    rng = np.random.default_rng(3)
    for _ in range(60):
        x, y = rng.uniform(0, 20, (rng.integers(0, 5), 2)), rng.uniform(0, 20, (rng.integers(0, 5), 2))
        for p in (1.0, 2.0):
            assert ospa(x, y, 8.0, p) == pytest.approx(brute_force_ospa(x, y, 8.0, p), rel=1e-12, abs=1e-12)
            assert gospa(x, y, 8.0, p).distance == pytest.approx(brute_force_gospa(x, y, 8.0, p), rel=1e-12,
                                                                abs=1e-12)


def test_bad_parameters_are_refused():
    with pytest.raises(InputError, match="cut-off"):
        ospa([[0, 0]], [[1, 1]], c=0.0)
    with pytest.raises(InputError, match="order p"):
        gospa([[0, 0]], [[1, 1]], c=1.0, p=0.5)
    with pytest.raises(InputError, match="same dimension"):
        ospa([[0, 0]], [[1, 1, 1]], c=1.0)


# ---- switching by hand


def test_switching_counts_by_hand():
    """Target 7 held by track 1 at t0, by track 2 at t1 (a switch: 1), by no track at t2 (1/2, the estimate is
    beyond c), by track 1 again at t3 (1/2); lambda = 4, p = 1: S = 4 s_k."""
    truth_t, truth_id, truth_x = [0, 1, 2, 3], [7, 7, 7, 7], [[0, 0]] * 4
    est_t, est_id, est_x = [0, 1, 2, 3], [1, 2, 1, 1], [[1, 0], [0, 1], [50, 0], [0, 2]]
    g = gospa_over_time(truth_t, truth_id, truth_x, est_t, est_id, est_x, c=10.0, p=1.0, switching_penalty=4.0)
    np.testing.assert_allclose(g.switches, [0, 1, 0.5, 0.5])
    np.testing.assert_allclose(g.switching, [0, 4, 2, 2])
    np.testing.assert_allclose(g.gospa, [1, 1, 10, 2])  # at t2: one missed + one false = 2 c / 2
    np.testing.assert_allclose(g.distance, np.hypot(g.gospa, g.switching))


def test_a_target_with_no_estimate_at_all_loses_its_track():
    """The deviation from Stone Soup (module doc): an empty estimate set is a loss (1/2), like one beyond c."""
    g = gospa_over_time([0, 1, 2], [5, 5, 5], [[0, 0]] * 3, [0, 2], [3, 3], [[1, 0], [1, 0]], c=10.0, p=2.0,
                        switching_penalty=1.0)
    np.testing.assert_allclose(g.switches, [0, 0.5, 0.5])
    np.testing.assert_allclose(g.switching, [0, np.sqrt(0.5), np.sqrt(0.5)])


# ---- the vectorised form for fixed sets against the per-step one


@pytest.mark.parametrize(("m", "n", "p"), [(1, 1, 1.0), (2, 2, 2.0), (2, 3, 1.0), (3, 2, 2.0), (3, 3, 1.0),
                                           (2, 1, 1.0)])
def test_gospa_fixed_sets_equals_the_per_step_form(m, n, p):
    """Same m targets and n tracks at every step, in 2-D (no ties), tracks swapped at random steps so that the
    switching term works: distance, parts and switch counts equal gospa_over_time's to 1e-12."""
    rng = np.random.default_rng(10 * m + n)
    K = 300
    x = rng.normal(size=(K, m, 2)) * 3.0
    y = np.concatenate([x, rng.normal(size=(K, max(n - m, 0), 2)) * 3.0], axis=1)[:, :n]
    y = y + rng.normal(size=y.shape) * 1.5
    if n >= 2:
        sw = rng.random(K) < 0.2
        y[sw, 0], y[sw, 1] = y[sw, 1].copy(), y[sw, 0].copy()
    t, ti = np.repeat(np.arange(K), m).astype(float), np.tile(np.arange(m), K)
    te, ei = np.repeat(np.arange(K), n).astype(float), np.tile(np.arange(n), K)
    a = gospa_over_time(t, ti, x.reshape(-1, 2), te, ei, y.reshape(-1, 2), 2.0, p, 1.0)
    b = gospa_fixed_sets(x, y, 2.0, p, 1.0)
    assert np.any(a.switches > 0) or n < 2
    for f in ("distance", "gospa", "localisation", "missed", "false", "switches"):
        np.testing.assert_allclose(getattr(b, f), getattr(a, f), rtol=0, atol=1e-12, err_msg=f)


def test_gospa_fixed_sets_by_hand():
    """One target at 0 in 1-D; its track at 1, then beyond c = 3 (missed + false: 3), then back; two tracks that
    swap at step 1 for two targets: s = 1 + 1 at the swap, and back at step 2."""
    g = gospa_fixed_sets(np.zeros((3, 1, 1)), np.array([[[1.0]], [[5.0]], [[0.5]]]), c=3.0)
    np.testing.assert_allclose(g.gospa, [1.0, 3.0, 0.5])
    np.testing.assert_allclose(g.switches, [0.0, 0.5, 0.5])
    x = np.array([[[0.0], [10.0]]] * 3)
    y = np.array([[[0.2], [10.1]], [[10.2], [0.1]], [[0.3], [9.9]]])
    np.testing.assert_allclose(gospa_fixed_sets(x, y, c=3.0).switches, [0.0, 2.0, 2.0])


# ---- against Stone Soup

stonesoup = pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")
from sonartrack.stonesoup.metrics import stonesoup_gospa, stonesoup_ospa  # noqa: E402


def random_tables(rng, steps=12, targets=4, tracks=5, d=2, empty_steps=True):
    """Truth and track tables: each id present at a random subset of times, near-truth and clutter tracks."""
    truth_t, truth_id, truth_x, est_t, est_id, est_x = [], [], [], [], [], []
    centres = rng.uniform(0, 60, (targets, d))
    for k in range(steps):
        present = rng.random(targets) < 0.8
        alive = rng.random(tracks) < 0.7
        if not empty_steps:
            present[rng.integers(targets)], alive[rng.integers(tracks)] = True, True
        for i in np.nonzero(present)[0]:
            truth_t.append(k * 10.0), truth_id.append(i), truth_x.append(centres[i] + k)
        for j in np.nonzero(alive)[0]:
            near = centres[(j + k // 4) % targets] + k  # tracks wander between targets: switches
            est_t.append(k * 10.0), est_id.append(j)
            est_x.append(near + rng.normal(0, 3, d) if rng.random() < 0.8 else rng.uniform(0, 80, d))
    return [np.array(a, float) for a in (truth_t, truth_id, truth_x, est_t, est_id, est_x)]


@pytest.mark.parametrize("seed", range(6))
def test_ospa_equals_stonesoup_for_p1(seed):
    rng = np.random.default_rng(seed)
    tt, _, tx, et, _, ex = random_tables(rng)
    times, ours = ospa_over_time(tt, tx, et, ex, c=12.0, p=1.0)
    t_ss, theirs = stonesoup_ospa(tt, tx, et, ex, c=12.0, p=1.0)
    np.testing.assert_allclose(times, t_ss)
    np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-9)


def test_ospa_of_order_2_is_the_minimum_where_stonesoup_may_exceed_it():
    """Stone Soup assigns on the distances, not their p-th powers (module doc): it equals ours where the two
    assignments coincide and is never below; ours is the brute-force minimum of eq. 3 everywhere."""
    rng = np.random.default_rng(11)
    equal = 0
    for _ in range(5):
        tt, _, tx, et, _, ex = random_tables(rng, steps=8, targets=3, tracks=4)
        _, ours = ospa_over_time(tt, tx, et, ex, c=12.0, p=2.0)
        _, theirs = stonesoup_ospa(tt, tx, et, ex, c=12.0, p=2.0)
        assert np.all(ours <= theirs + 1e-9)
        equal += int(np.sum(np.abs(ours - theirs) <= 1e-9))
        times = np.union1d(tt, et)
        for k, t in enumerate(times):
            assert ours[k] == pytest.approx(brute_force_ospa(tx[tt == t], ex[et == t], 12.0, 2.0), rel=1e-12)
    assert equal >= 30  # most steps: one assignment optimal for both


def test_ospa_of_order_2_where_the_assignments_differ():
    """x = (5,3), (3,1); y = (1,0), (0,0). Pairing x1-y1, x2-y2: distances 5 and sqrt(10) (sum 8.16, squares 35);
    x1-y2, x2-y1: sqrt(34) and sqrt(5) (sum 8.07, squares 39). Eq. 3 takes the least squares: sqrt(35 / 2);
    Stone Soup the least sum: sqrt(39 / 2)."""
    x, y = np.array([[5.0, 3.0], [3.0, 1.0]]), np.array([[1.0, 0.0], [0.0, 0.0]])
    assert ospa(x, y, c=100.0, p=2.0) == pytest.approx(np.sqrt(35 / 2), rel=1e-12)
    assert stonesoup_ospa([0, 0], x, [0, 0], y, c=100.0, p=2.0)[1][0] == pytest.approx(np.sqrt(39 / 2), rel=1e-12)
    assert ospa(x, y, c=100.0, p=1.0) == pytest.approx((np.sqrt(34) + np.sqrt(5)) / 2, rel=1e-12)


@pytest.mark.parametrize("p", [1.0, 2.0])
@pytest.mark.parametrize("seed", range(4))
def test_gospa_equals_stonesoup_on_random_sets(seed, p):
    """Per step, with empty sets and n != m (no switching term)."""
    rng = np.random.default_rng(100 + seed)
    tables = random_tables(rng, steps=15)
    ours = gospa_over_time(*tables, c=9.0, p=p)
    theirs = stonesoup_gospa(*tables, c=9.0, p=p)
    np.testing.assert_allclose(ours.time_s, theirs.time_s)
    for part in ("distance", "gospa", "localisation", "missed", "false"):
        np.testing.assert_allclose(getattr(ours, part), getattr(theirs, part), rtol=1e-9, atol=1e-9, err_msg=part)


@pytest.mark.parametrize("p", [1.0, 2.0])
@pytest.mark.parametrize("seed", range(4))
def test_gospa_switching_equals_stonesoup(seed, p):
    """Tracks that wander between targets: the switching term and the combined distance, with both sets
    non-empty at every step (where Stone Soup's and our switching rules coincide: module doc)."""
    rng = np.random.default_rng(200 + seed)
    tables = random_tables(rng, steps=20, empty_steps=False)
    ours = gospa_over_time(*tables, c=9.0, p=p, switching_penalty=5.0)
    theirs = stonesoup_gospa(*tables, c=9.0, p=p, switching_penalty=5.0)
    assert ours.switches.sum() >= 2  # the case has switches
    np.testing.assert_allclose(ours.switching, theirs.switching, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ours.distance, theirs.distance, rtol=1e-9, atol=1e-9)


def test_empty_estimate_step_is_where_stonesoup_differs():
    """The one documented difference, shown on Stone Soup itself: no estimate at t1 costs it nothing."""
    tables = ([0, 1, 2], [5, 5, 5], [[0, 0]] * 3, [0, 2], [3, 3], [[1, 0], [1, 0]])
    theirs = stonesoup_gospa(*tables, c=10.0, p=1.0, switching_penalty=1.0)
    ours = gospa_over_time(*tables, c=10.0, p=1.0, switching_penalty=1.0)
    np.testing.assert_allclose(theirs.switching, [0, 0, 0])
    np.testing.assert_allclose(ours.switching, [0, 0.5, 0.5])
    np.testing.assert_allclose(ours.gospa, theirs.gospa, rtol=1e-12)
