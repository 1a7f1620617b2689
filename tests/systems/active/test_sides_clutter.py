"""Side decision with clutter taken into a track's history and with too short a history (sides.py SideTracker).

The worlds are built here from the geometry (a line array's contact and its mirror about the array's axis through
the receiver), not by the simulator: a CV target 5-6 km off a receiver whose array turns 60 deg to port."""

import numpy as np

from sonartrack.systems.active.contacts import Contacts
from sonartrack.systems.active.sides import SideTracker

SD = 30.0
R = np.eye(2) * SD**2
P = np.diag([SD**2, SD**2, 1.0, 1.0])


def _mirror(xy, heading):
    a = np.array([np.sin(heading), np.cos(heading)])
    return 2.0 * (np.asarray(xy) @ a)[..., None] * a - xy


def _target(t):
    return np.array([4000.0 + 3.0 * t, 3000.0 - 2.0 * t])


def _world(detected, stray, tracked, lookback=0, n=41, seed=2, replace=True):
    """Per ping k (30 s apart; the array turns from ping 15 to 25): the target's echo when ``detected(k)``, a stray
    detection 100 m off the target (inside the tracks' gates, nearer than the echo) when ``stray(k)``, two far
    clutter detections always; tracks 1 (the target) and 2 (its mirror) confirmed when ``tracked(k)``; the stray
    replaces the echo when ``replace``."""
    rng = np.random.default_rng(seed)
    h = np.deg2rad(np.interp(np.arange(n), [15, 25], [0.0, -60.0]))
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=lookback)
    for k in range(n):
        t = 30.0 * k
        true = _target(t)
        pts = [true + rng.uniform(-3000, 3000, 2) + 4000.0 for _ in range(2)]
        if stray(k):
            pts.append(true + 100.0 * np.array([np.cos(k), np.sin(k)]))
        if detected(k) and not (replace and stray(k)):
            pts.append(true + rng.normal(0, SD, 2))
        z = np.array(pts)
        m = len(z)
        c = Contacts(np.full(2 * m, k), np.full(2 * m, t), np.tile(np.arange(m) + 100 * k, 2),
                     np.repeat(np.array([1, -1], np.int8), m), np.concatenate([z, _mirror(z, h[k])]),
                     np.repeat(R[None], 2 * m, 0), np.full(2 * m, np.nan), np.full(2 * m, 5000.0), np.ones(2 * m))
        ids = np.array([1, 2]) if tracked(k) else np.zeros(0, np.int64)
        v_m = _mirror(true + [3.0, -2.0], h[k]) - _mirror(true, h[k])
        x = np.array([[*true, 3.0, -2.0], [*_mirror(true, h[k]), *v_m]])[: len(ids)]
        st.update(t, h[k], c, ids, x, np.repeat(P[None], len(ids), 0),
                  lambda _t, p, hk=h[k]: np.where(np.sin(np.arctan2(p[:, 0], p[:, 1]) - hk) >= 0, 1, -1))
    return st


def test_strays_taken_into_the_history_across_the_turn_still_decide_the_true_side():
    # one ping in four through the whole run (the turn included) the tracks take a stray contact, not the echo
    st = _world(lambda k: True, lambda k: k % 4 == 1, lambda k: True)
    assert st.decision(1) == 1 and st.decision(2) == -1
    clean = _world(lambda k: True, lambda k: False, lambda k: True)
    assert clean.decision(1) == 1 and clean.decision(2) == -1


def test_too_short_a_history_is_undecided():
    # confirmed during the turn, the run ends two pings later: 3 contacts over ~12 deg of turn, retrodiction finds
    # no earlier echo (the target was not detected before)
    st = _world(lambda k: k >= 19, lambda k: False, lambda k: k >= 20, lookback=40, n=22)
    assert st.decision(1) == 0 and st.decision(2) == 0
    # detected and tracked only after the turn: no turn in its history
    st = _world(lambda k: k >= 27, lambda k: False, lambda k: k >= 30, lookback=40)
    assert st.decision(1) == 0 and st.decision(2) == 0


def test_a_search_through_clutter_raises_the_threshold_by_its_choices():
    # retrodiction through pings with the echo and a stray in the gates: each such ping doubles the choices
    st = _world(lambda k: True, lambda k: False, lambda k: k >= 30, lookback=40)
    assert st.threshold(1) == st.min_log_lr  # only the echo inside the gates: one choice per ping
    assert st.decision(1) == 1
    busy = _world(lambda k: True, lambda k: 20 <= k < 30, lambda k: k >= 30, lookback=40, replace=False)
    assert busy.threshold(1) > busy.min_log_lr + 5 * np.log(2.0)  # >= 2 detections in the gates, 10 pings
