"""One row per target: a ghost with no live twin is reflected onto its target's side (sides.py GhostDeleter), and a
target's track lost and re-confirmed is one row (contact_tracker.py ``rejoin_s``, targets.py chains).

The re-join test's contacts come from a generator written here from the geometry (not the scene simulator): a
monostatic sonar on a ship steaming north at 2.5 m/s; each echo of a constant-velocity target gives its position and
its reflection about the ship's axis, with a range / cross-range covariance (range sd 40 m, bearing sd 0.9 deg), plus
a few uniform clutter echoes (each also a mirror pair); the target's echoes stop for a stretch of pings."""

import numpy as np
import pytest

from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.run import ContactTracker
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.active.sides import GhostDeleter, SideTracker
from sonartrack.systems.active.targets import mirror_targets, track_hypotheses
from sonartrack.tracking.deleters import ExistenceDeleter
from sonartrack.tracking.tracks import TrackArrays

PING_S, SPEED_MPS = 30.0, 2.5


def _one_track(x, P, tid=5):
    return TrackArrays(np.asarray(x, float)[None, None], np.asarray(P, float)[None, None], np.ones((1, 1)),
                       np.array([0.9]), np.array([True]), np.array([tid], np.int64), np.zeros(1), np.eye(4)[None], {})


def test_a_ghost_without_a_live_twin_is_reflected_and_keeps_its_identity():
    sides = SideTracker()
    sides._history[5] = [(0.0, 2.0), (30.0, -10.0)]  # ln LR -10: decided a ghost, no twin
    part = GhostDeleter(ExistenceDeleter(0.5, 0.01), sides)
    # the array's axis: through (100, 0) heading north; a track at (1100, 500) moving (3, -1) m/s, cov_xy 40
    part.axis = (np.array([100.0, 0.0]), 0.0)
    P = np.diag([400.0, 900.0, 4.0, 1.0])
    P[0, 1] = P[1, 0] = 40.0
    P[2, 3] = P[3, 2] = 0.5
    T = part.manage(_one_track([1100.0, 500.0, 3.0, -1.0], P), np.array([True]))
    # by hand: x -> 100 - (1100 - 100) = -900, y kept; vx -> -3; the x-y and vx-vy covariances change sign
    assert T.track_id.tolist() == [5] and T.confirmed.tolist() == [True]
    assert np.allclose(T.x[0, 0], [-900.0, 500.0, -3.0, -1.0])
    want = P.copy()
    want[0, 1] = want[1, 0] = -40.0
    want[2, 3] = want[3, 2] = -0.5
    want[0, 2], want[2, 0] = P[0, 2], P[2, 0]
    assert np.allclose(T.P[0, 0], want)
    assert sides.decision(5) == 1 and not sides.rejected(5)  # now on its target's side, not flipped back
    # a ghost whose twin (the track on the target's side) is alive is deleted instead
    sides._history[6] = [(30.0, -10.0)]
    sides._shared = {(6, 7): 3}
    sides._twins = sides.twins()
    two = TrackArrays(np.zeros((2, 1, 4)), np.stack([np.eye(4)] * 2)[:, None], np.ones((2, 1)), np.full(2, 0.9),
                      np.ones(2, bool), np.array([6, 7], np.int64), np.zeros(2), np.stack([np.eye(4)] * 2), {})
    assert part.manage(two, np.ones(2, bool)).track_id.tolist() == [7]


def _cov(xy, rx):
    d = xy - rx
    u = d / np.hypot(*d)
    n = np.array([-u[1], u[0]])
    return 40.0**2 * np.outer(u, u) + (np.hypot(*d) * np.deg2rad(0.9)) ** 2 * np.outer(n, n)


def _targets(t):
    """Two CV targets (m): a east of the ship, b far to its west, appearing at ping 34."""
    return [np.array([4000.0 + 3.0 * t, 6000.0 - 1.0 * t]), np.array([-9000.0 + 2.0 * t, 2000.0 + 1.5 * t])]


def _run(rejoin_s, pings=50, gap=range(20, 28), seed=3, pd=0.9, clutter=3.0, image=False, clutter_map=None):
    """The contacts of the module doc through a ContactTracker; ``image``: each echo of target a has a weaker
    lobe image at the same range on the opposite bearing (a line array's other endfire)."""
    rng = np.random.default_rng(seed)
    nav_t = np.arange(-60.0, PING_S * pings + 60.0, 10.0)
    rx_all = np.stack([np.zeros_like(nav_t), SPEED_MPS * nav_t], -1)
    geometry = ActiveGeometry(nav_t, rx_all, rx_all, np.zeros_like(nav_t))
    trk = ContactTracker(ActiveSettings().tracker_settings(), geometry, None, 1.0, side_turn_deg=20.0,
                         merge_probability=0.99, rejoin_s=rejoin_s, scan_interval_s=PING_S, clutter_map=clutter_map)
    det = 0
    for k in range(pings):
        tk = PING_S * k
        rx = np.array([0.0, SPEED_MPS * tk])
        a, b = _targets(tk)
        echoes = ([a] if k not in gap and rng.random() < pd else []) + ([b] if k >= 34 and rng.random() < pd else [])
        echoes += [rx + rng.uniform(-12000, 12000, 2) for _ in range(rng.poisson(clutter))]
        xy, R, side, dets, stat = [], [], [], [], []
        noisy = [(e + rng.multivariate_normal(np.zeros(2), _cov(e, rx)), 30.0) for e in echoes]
        if image and len(echoes) and echoes[0] is a:  # the image: same range, opposite bearing, weaker
            noisy[0] = (noisy[0][0], 100.0)
            noisy.append((2 * rx - noisy[0][0], 20.0))
        for z, level in noisy:
            for p, s in ((z, 1), (np.array([2 * rx[0] - z[0], z[1]]), -1)):
                xy += [p]
                R += [_cov(p, rx)]
                side += [s]
                dets += [det]
                stat += [level]
            det += 1
        m = len(xy)
        xy = np.array(xy).reshape(-1, 2)
        trk.step(tk, Contacts(np.full(m, k), np.full(m, tk), np.array(dets, np.int64), np.array(side, np.int8), xy,
                              np.array(R).reshape(-1, 2, 2), np.full(m, np.nan), np.hypot(*(xy - rx).T),
                              np.array(stat)))
    return trk.result(), geometry


def _rows_of(tracks, geometry, which):
    """Rows of the listing holding a confirmed track within 1 km of target ``which`` (or its mirror)."""
    m = mirror_targets(tracks, geometry)
    tg, _ = track_hypotheses(tracks, m, geometry)
    t = tracks.tracks
    out = set()
    for r in np.nonzero(t.confirmed)[0]:
        p = _targets(t.time_s[r])[which]
        if min(np.hypot(*(t.x[r, :2] - p)), np.hypot(*(t.x[r, :2] - [-p[0], p[1]]))) < 1000.0:
            out.add(int(tg[r]))
    return m, out


@pytest.fixture(scope="module")
def runs():
    return {"rejoin": _run(600.0), "none": _run(None)}


def test_a_target_lost_and_reconfirmed_is_one_row(runs):
    tracks, geometry = runs["none"]
    m, rows_a = _rows_of(tracks, geometry, 0)
    assert len(rows_a) == 2  # without re-joining: the lost track's row and the new one's (what a user saw)
    tracks, geometry = runs["rejoin"]
    m, rows_a = _rows_of(tracks, geometry, 0)
    assert len(rows_a) == 1 and -1 not in rows_a
    k = rows_a.pop() - 1
    own, other = m.chains[k]
    assert len(own) == 2 and len(other) == 2  # two segments a side (the target and its mirror), joined pairwise
    assert m.first_s[k] < 20 * PING_S and m.last_s[k] == 49 * PING_S
    assert tracks.joins  # the chain's record: each later segment -> the lost one
    # the target appearing far off after the gap is not joined onto the lost one: a row of its own
    _, rows_b = _rows_of(tracks, geometry, 1)
    assert len(rows_b) == 1 and rows_b.isdisjoint({k + 1})


def test_a_strong_targets_lobe_image_starts_no_track():
    from sonartrack.systems.active.run import clutter_map_of

    def image_tracks(tracks):
        t, n = tracks.tracks, set()
        for r in np.nonzero(t.confirmed)[0]:
            rx = np.array([0.0, SPEED_MPS * t.time_s[r]])
            p = 2 * rx - _targets(t.time_s[r])[0]  # the image, and its mirror about the axis
            if min(np.hypot(*(t.x[r, :2] - p)), np.hypot(*(t.x[r, :2] - [-p[0], p[1]]))) < 1000.0:
                n.add(int(t.track_id[r]))
        return n

    without, _ = _run(None, pings=30, gap=(), image=True)
    assert image_tracks(without)  # the image is a CV line: tracked and confirmed when nothing withholds it
    with_map, geometry = _run(None, pings=30, gap=(), image=True, clutter_map=clutter_map_of(ActiveSettings()))
    assert not image_tracks(with_map)
    _, rows_a = _rows_of(with_map, geometry, 0)
    assert len(rows_a) == 1  # the target itself still held


def test_a_ghost_whose_twin_joined_an_earlier_row_is_listed_in_that_row():
    """By hand: track 37 and its twin 38; 83 a later segment of 37 (merged into it); 81 the twin of 83, decided a
    ghost. One target: (37, 83) on its side, (38, 81) the other; before, 81 was a row of its own ("only its mirror
    was tracked")."""
    from sonartrack.systems.active.contact_tracker import ActiveTracks
    from sonartrack.systems.active.sides import SideDecisions
    from sonartrack.tracking.run import PositionTracks

    rows = [(0.0, 37), (0.0, 38), (30.0, 37), (30.0, 38), (30.0, 83), (30.0, 81), (60.0, 37), (60.0, 83), (60.0, 81)]
    t = np.array([r[0] for r in rows])
    ids = np.array([r[1] for r in rows], np.int64)
    x = np.zeros((len(rows), 4))
    x[:, 0] = np.where(np.isin(ids, [38, 81]), -3000.0, 3000.0)
    x[:, 1] = 5000.0
    n = len(rows)
    tracks = PositionTracks(t, ids, np.ones(n, bool), np.full(n, 0.9), x, np.full(n, 50.0), np.full(n, 50.0),
                            np.ones((n, 1)))
    sides = SideDecisions(np.array([37, 38, 81, 83]), np.array(["track", "undecided", "mirror", "undecided"], object),
                          np.array(["starboard", "", "starboard", ""], object), np.array([9.0, 0.0, -9.0, 0.0]),
                          np.array([30.0, np.nan, 30.0, np.nan]), np.full(4, 5), np.array([38, 37, 83, 81]))
    nav_t = np.array([-60.0, 120.0])
    geometry = ActiveGeometry(nav_t, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))
    P = np.stack([np.eye(4)] * n)
    m = mirror_targets(ActiveTracks(tracks, P, sides, {83: 37}), geometry)
    assert len(m) == 1 and m.decision[0] == "decided" and m.side[0] == "starboard"
    assert m.chains[0] == ((37, 83), (38, 81)) and int(m.track_id[0]) == 83
    # without the join the twins make two targets (37/38 and 83/81), each one row
    assert len(mirror_targets(ActiveTracks(tracks, P, sides), geometry)) == 2


def test_a_decided_track_keeps_its_row_when_joins_put_its_twin_on_its_side():
    """By hand: track 34 (confirmed first, at x = -3000), 33 a later segment joined to it (at +3000, decided on its
    target's side, twin 41), 41 (at -3000, 33's twin) also joined to 34. The joins put 33 and its twin 41 on one side
    of the row; the decision names them: the row's target is 33's position, its mirror 41's (before, the row listed
    no target track: a ghost-only row)."""
    from sonartrack.systems.active.contact_tracker import ActiveTracks
    from sonartrack.systems.active.sides import SideDecisions
    from sonartrack.tracking.run import PositionTracks

    rows = [(0.0, 34), (30.0, 34), (30.0, 33), (30.0, 41), (60.0, 33), (60.0, 41)]
    t = np.array([r[0] for r in rows])
    ids = np.array([r[1] for r in rows], np.int64)
    x = np.zeros((len(rows), 4))
    x[:, 0] = np.where(ids == 33, 3000.0, -3000.0)
    x[:, 1] = 5000.0
    n = len(rows)
    tracks = PositionTracks(t, ids, np.ones(n, bool), np.full(n, 0.9), x, np.full(n, 50.0), np.full(n, 50.0),
                            np.ones((n, 1)))
    sides = SideDecisions(np.array([33, 34, 41]), np.array(["track", "undecided", "undecided"], object),
                          np.array(["starboard", "", ""], object), np.array([9.0, 0.0, 0.0]),
                          np.array([30.0, np.nan, np.nan]), np.full(3, 5), np.array([41, -1, 33]))
    geometry = ActiveGeometry(np.array([-60.0, 120.0]), np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))
    m = mirror_targets(ActiveTracks(tracks, np.stack([np.eye(4)] * n), sides, {33: 34, 41: 34}), geometry)
    assert len(m) == 1 and m.decision[0] == "decided"
    assert int(m.track_id[0]) == 33 and int(m.mirror_track_id[0]) == 41
    assert m.xy[0].tolist() == [3000.0, 5000.0]


def test_a_track_confirmed_on_one_or_two_pings_then_lost_makes_no_row():
    """targets.MIN_ROW_PINGS: a target row needs its tracks confirmed on >= 3 pings together, unless still confirmed
    at the last ping (a target just acquired). Hand-built table: track 1 confirmed on pings 0-9 (a target), track 2
    on ping 3 only and track 4 on pings 5-6 (fleeting fragments, then lost), track 3 on the last ping only (new)."""
    from types import SimpleNamespace

    from sonartrack.systems.active.targets import MIN_ROW_PINGS

    assert MIN_ROW_PINGS == 3
    times = PING_S * np.arange(10)
    ids, tt = [1] * 10 + [2, 4, 4, 3], list(times) + [times[3], times[5], times[6], times[9]]
    xy = np.array([[4000.0, 6000.0]] * 10 + [[-3000.0, 2000.0], [6000.0, 9000.0], [6000.0, 9000.0], [1000.0, 8000.0]])
    order = np.argsort(tt, kind="stable")

    class Rows(SimpleNamespace):
        def __len__(self):
            return len(self.track_id)

    tracks = Rows(track_id=np.array(ids, np.int64)[order], time_s=np.array(tt)[order],
                             confirmed=np.ones(len(ids), bool), x=np.hstack([xy, np.zeros_like(xy)])[order])
    nav_t = np.arange(-60.0, 400.0, 10.0)
    rx = np.stack([np.zeros_like(nav_t), SPEED_MPS * nav_t], -1)
    geometry = ActiveGeometry(nav_t, rx, rx, np.zeros_like(nav_t))
    rows = mirror_targets(SimpleNamespace(tracks=tracks, sides=None, joins=None), geometry)
    assert rows.track_id.tolist() == [1, 3] and rows.target.tolist() == [1, 2]
    target, _ = track_hypotheses(SimpleNamespace(tracks=tracks), rows, geometry)
    assert set(target[np.isin(tracks.track_id, [2, 4])]) == {-1}  # kept in tracks.csv, with no target
