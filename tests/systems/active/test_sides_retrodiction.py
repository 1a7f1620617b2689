"""Retrodiction of the side decision in clutter: a ghost track confirmed after the array's turn must not be taken
for its target. Its backward gate grows by kilometres over the look-back, so the contact of its own side nearest
its back-extrapolated line is then clutter chosen for fitting that line (and the true target's contacts, on the
other side, lie inside the gate too); the decision must come out "mirror" (the ghost of a target on the other
side), and the true track's "track"."""

import numpy as np

from sonartrack.systems.active.contacts import Contacts
from sonartrack.systems.active.sides import MIN_LOG_LR, SideTracker

SD = 40.0  # contact error (m)


def _mirror(xy, heading):
    a = np.array([np.sin(heading), np.cos(heading)])
    return 2.0 * (xy @ a)[..., None] * a - xy


def _side_of(heading):
    return lambda _t, p: np.where(np.sin(np.arctan2(p[:, 0], p[:, 1]) - heading) >= 0, 1, -1)


def _ping(k, t, h, points, rng):
    """The mirror-pair contacts of one ping: each point and its mirror about the axis (receiver at the origin)."""
    z = points + rng.normal(0, SD, points.shape)
    n = len(z)
    xy = np.empty((2 * n, 2))
    xy[0::2], xy[1::2] = z, _mirror(z, h)
    side = np.where(_side_of(h)(t, xy) > 0, 1, -1).astype(np.int8)
    R = np.repeat(np.eye(2)[None] * SD**2, 2 * n, axis=0)
    return Contacts(np.full(2 * n, k), np.full(2 * n, t), np.repeat(np.arange(n) + 100 * k, 2), side, xy, R,
                    np.full(2 * n, np.nan), np.full(2 * n, 5000.0), np.ones(2 * n))


def _scene(seed, clutter=30, confirm=32, pings=42):
    """Array heading 0 for 15 pings, turning to -60 deg over 10, then straight; a CV target on starboard; clutter
    spread over 30 km x 30 km. The true track (id 1) lives from ping 0; the ghost (id 2, the target's mirror about
    the new axis) is confirmed at ping ``confirm``, after the turn. Returns the decisions."""
    rng = np.random.default_rng(seed)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), q=0.05, lookback=40)
    headings = np.deg2rad(np.concatenate([np.zeros(15), np.linspace(0, -60, 10), np.full(pings - 25, -60.0)]))
    P = np.diag([50.0**2, 50.0**2, 0.3**2, 0.3**2])
    for k, h in enumerate(headings):
        t = 30.0 * k
        true = np.array([4000.0 + 3.0 * t, 3000.0 - 2.0 * t])
        pts = np.vstack([true, rng.uniform(-15000, 15000, (clutter, 2))])
        c = _ping(k, t, h, pts, rng)
        ids, xs = [1], [[*true, 3.0, -2.0]]
        if k >= confirm:
            ids.append(2)
            xs.append([*_mirror(true, h), *_mirror(np.array([3.0, -2.0]), h)])
        st.update(t, h, c, np.array(ids), np.array(xs), np.stack([P] * len(ids)), _side_of(h))
    return st.result()


def test_ghost_confirmed_after_the_turn_is_called_a_mirror():
    for seed in range(4):
        d = _scene(seed)
        k1, k2 = d.of(1), d.of(2)
        assert d.decision[k1] == "track" and d.side[k1] == "starboard", seed
        assert d.decision[k2] == "mirror" and d.log_lr[k2] <= -MIN_LOG_LR, (seed, d.log_lr[k2])
        assert d.side[k2] == "starboard", seed


def test_no_clutter_same_decisions():
    d = _scene(0, clutter=0)
    assert d.decision[d.of(1)] == "track" and d.decision[d.of(2)] == "mirror"
