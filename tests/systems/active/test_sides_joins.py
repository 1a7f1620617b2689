"""Side evidence carried over a join (sides.py SideTracker.carry): a target seen before and after the array's turn by
two segments is decided once they are joined; with no turn it stays undecided; a maneuver between two segments does
not undo the first segment's decision; a duplicate's evidence goes to the kept track (GhostDeleter)."""

import numpy as np

from sonartrack.systems.active.contacts import Contacts
from sonartrack.systems.active.sides import MIN_LOG_LR, GhostDeleter, SideTracker

SD = 30.0
R = np.eye(2) * SD**2
P = np.diag([SD**2, SD**2, 1.0, 1.0])


def _mirror(xy, heading):
    """Reflection about the axis of heading ``heading`` through the origin (the receiver)."""
    a = np.array([np.sin(heading), np.cos(heading)])
    return 2.0 * (xy @ a) * a - xy


def _side(heading):
    return lambda _t, p: np.where(np.sin(np.arctan2(p[:, 0], p[:, 1]) - heading) >= 0, 1, -1)


def _target(t):
    """A CV target 5-6 km east of the receiver (m)."""
    return np.array([4000.0 + 3.0 * t, 3000.0 - 2.0 * t])


def _ping(st, k, h, segments, rng, target=_target):
    """Ping ``k`` (30 s apart): the target's detection (its contact and its mirror); ``segments`` the (target-side
    id, mirror-side id) pair of tracks confirmed at this ping (None: no track)."""
    t = 30.0 * k
    true = target(t)
    z = true + rng.normal(0, SD, 2)
    xy = np.stack([z, _mirror(z, h)])
    c = Contacts(np.array([k, k]), np.array([t, t]), np.array([k, k]), np.array([1, -1], np.int8), xy,
                 np.stack([R, R]), np.full(2, np.nan), np.full(2, 5000.0), np.ones(2))
    ids = [] if segments is None else list(segments)
    x = np.array([[*true, 3.0, -2.0], [*_mirror(true, h), 0.0, 0.0]])[:len(ids)]
    st.update(t, h, c, np.array(ids, np.int64), x.reshape(-1, 4), np.repeat(P[None], len(ids), 0), _side(h))


def _headings(n=41, start=15, stop=25):
    """The array's heading per ping: north, then turning 60 deg to port from ping ``start`` to ``stop``."""
    return np.deg2rad(np.interp(np.arange(n), [start, stop], [0.0, -60.0]))


def _two_segments(join: bool, headings, gap=(18, 22), seed=1, target=_target):
    """Tracks 1 (target) and 2 (its mirror) up to ping gap[0], then nothing, then 3 and 4 from gap[1]; joined
    (3 -> 1, 4 -> 2) at the ping 3 and 4 are confirmed when ``join``."""
    rng = np.random.default_rng(seed)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=0)
    for k, h in enumerate(headings):
        seg = (1, 2) if k < gap[0] else None if k < gap[1] else (3, 4)
        _ping(st, k, h, seg, rng, target)
        if join and k == gap[1]:
            st.carry(3, 1)
            st.carry(4, 2)
    return st.result()


def test_segments_before_and_after_the_turn_decide_once_joined():
    h = _headings()
    # each segment alone sees less than 20 deg of the turn: neither decides
    alone = _two_segments(False, h)
    assert set(alone.decision) == {"undecided"}
    assert np.rad2deg(h[17] - h[0]) > -20 and np.rad2deg(h[40] - h[22]) > -20
    d = _two_segments(True, h)
    k3, k4 = d.of(3), d.of(4)
    assert d.decision[k3] == "track" and d.log_lr[k3] >= MIN_LOG_LR
    assert d.decision[k4] == "mirror" and d.log_lr[k4] <= -MIN_LOG_LR
    assert d.side[k3] == "starboard" and d.side[k4] == "starboard"
    # the earlier segments keep their own (undecided) rows; the joined track counts both segments' contacts
    assert d.decision[d.of(1)] == "undecided" and d.contacts[k3] == 41 - 4


def test_joined_segments_with_no_turn_stay_undecided():
    d = _two_segments(True, np.zeros(41))
    np.testing.assert_allclose(d.log_lr, 0.0, atol=1e-9)
    assert set(d.decision) == {"undecided"}


def test_a_maneuver_in_the_gap_keeps_the_first_segment_s_decision():
    # segment 1 lives through the whole turn (pings 0-30) and decides; the target then turns 90 deg in the gap, so
    # no one CV motion explains both segments: the evidence is each segment's own (one CV motion per segment)
    h = _headings(60, 5, 15)

    def turning(t):
        t1 = 30.0 * 32
        if t <= t1:
            return _target(t)
        return _target(t1) + np.array([2.0, 3.0]) * (t - t1)

    first = _two_segments(False, h, gap=(31, 35), target=turning)
    d = _two_segments(True, h, gap=(31, 35), target=turning)
    lr1 = first.log_lr[first.of(1)]
    assert lr1 >= MIN_LOG_LR and first.decision[first.of(3)] == "undecided"
    assert d.decision[d.of(3)] == "track" and d.log_lr[d.of(3)] >= MIN_LOG_LR
    assert d.decision[d.of(4)] == "mirror"


class _Merger:
    """A deleter part that deletes track ``gone`` as the duplicate of ``kept`` at its first call (the record of
    tracking/duplicates.py DuplicateMerger: ``merged``)."""

    def __init__(self, gone, kept):
        self.gone, self.kept, self.merged, self.inner = gone, kept, {}, None

    def manage(self, T, hit):
        if not self.merged:
            self.merged[self.gone] = self.kept
        return T


class _Tracks:
    """The least of TrackArrays GhostDeleter.manage reads."""

    def __init__(self, ids):
        self.track_id = np.asarray(ids, np.int64)

    def __len__(self):
        return len(self.track_id)


def test_a_merged_duplicate_s_evidence_goes_to_the_kept_track():
    h = _headings()
    rng = np.random.default_rng(1)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=0)
    for k in range(18):
        _ping(st, k, h[k], (1, 2), rng)
    GhostDeleter(_Merger(1, 3), st).manage(_Tracks([3]), None)  # track 1 deleted as 3's duplicate
    GhostDeleter(_Merger(2, 4), st).manage(_Tracks([4]), None)
    for k in range(22, 41):
        _ping(st, k, h[k], (3, 4), rng)
    d = st.result()
    assert d.decision[d.of(3)] == "track" and d.decision[d.of(4)] == "mirror"
    assert d.contacts[d.of(3)] == 41 - 4  # pings 0-17 (carried) and 22-40 (its own)


def test_flip_swaps_the_carried_evidence():
    h = _headings()
    rng = np.random.default_rng(1)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=0)
    for k, hk in enumerate(h):
        seg = (1, 2) if k < 18 else None if k < 22 else (3, 4)
        _ping(st, k, hk, seg, rng)
        if k == 22:
            st.carry(3, 1)
    before = st.result().log_lr[st.result().of(3)]
    st.flip(3)
    # the history and the recomputed ratio (own contacts and the carried piece both swapped) change sign
    assert st.result().log_lr[st.result().of(3)] == -before and abs(before) >= MIN_LOG_LR
    assert abs(st._log_lr(3) + before) < 1e-6 * abs(before)


def test_a_carry_before_the_kept_track_s_first_update_keeps_its_retrodiction():
    # a duplicate merged into a track confirmed at this very scan (GhostDeleter runs before SideTracker.update): the
    # kept track is still new to the side tracker, so its retrodiction runs (lookback > 0) and the carry neither
    # breaks it nor counts a ping twice
    h = _headings()
    rng = np.random.default_rng(1)
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=40)
    for k in range(18):
        _ping(st, k, h[k], (1, 2), rng)
    st.carry(3, 1)
    st.carry(4, 2)
    assert 3 not in st._sums  # the carry leaves the track new: its first update retrodicts
    _ping(st, 18, h[18], (3, 4), rng)
    retro = st._sums[3][0].live.count(False)
    assert retro >= 10  # the target's contacts of pings 0-17 found again backwards
    for k in range(19, 41):
        _ping(st, k, h[k], (3, 4), rng)
    d = st.result()
    assert d.decision[d.of(3)] == "track" and d.decision[d.of(4)] == "mirror"
    assert d.contacts[d.of(3)] == 41  # each ping's contact once: the retrodicted pings are not counted twice


def test_a_segment_of_another_object_is_not_carried():
    # segments 1/2 held a still object 6 km from the target (a false track that later merged into the target's
    # track): its contacts cannot be the target's (20 m/s over the gap does not reach), so 3 keeps its own evidence
    rng = np.random.default_rng(4)
    h = _headings()
    st = SideTracker(min_turn_rad=np.deg2rad(20.0), lookback=0)
    for k, hk in enumerate(h):
        if k < 18:
            _ping(st, k, hk, (1, 2), rng, lambda t: np.array([-2000.0, 8000.0]))
        elif k >= 22:
            _ping(st, k, hk, (3, 4), rng)
            if k == 22:
                st.carry(3, 1)
                st.carry(4, 2)
    d = st.result()
    assert d.contacts[d.of(3)] == 41 - 22 and d.decision[d.of(3)] == "undecided"
