"""Fragments of one target joined (track-to-track association), fragments of two kept apart."""

import numpy as np

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.io.navigation import Navigation
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.passive.fragments import _fragments_joined, join_fragments
from sonartrack.systems.passive.measurements import TrackMeasurements

TIMES = np.arange(0.0, 1201.0, 1.0)


def _nav() -> Navigation:
    """Array at 3 m/s north, turning 40 deg to port from 400 s (no tow)."""
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((400.0, 480.0, -np.deg2rad(0.5)),)).state(TIMES)
    return Navigation(TIMES, own[:, 0], own[:, 1], heading, own[:, 0], own[:, 1], heading)


def _fragment(track_id, x0, t0, t1, nav, seed):
    """Cone angles (deg, 0.2 deg noise) of a CV target [x, y, vx, vy] at t = 0 over [t0, t1)."""
    t = TIMES[np.logical_and(np.greater_equal(TIMES, t0), np.less(TIMES, t1))]
    xy, heading = nav.array_at(t)
    tgt = np.asarray(x0[:2]) + t[:, None] * np.asarray(x0[2:])
    rel = wrap_angle(bearing_rad(tgt[:, 0] - xy[:, 0], tgt[:, 1] - xy[:, 1]) - heading)
    cone = np.clip(np.rad2deg(np.abs(rel)) + np.random.default_rng(seed).normal(0.0, 0.2, len(t)), 0.0, 180.0)
    return TrackMeasurements(track_id, t, cone, np.full(len(t), 8.0), t, cone)


def test_fragments_of_one_target_are_joined_and_of_two_are_not():
    nav = _nav()
    ship_a, ship_b = [4000.0, 3000.0, -3.0, 1.0], [1000.0, 5850.0, 2.0, -3.0]  # b near a at 650 s
    first = _fragment(1, ship_a, 0.0, 600.0, nav, 1)
    later = _fragment(5, ship_a, 680.0, 1200.0, nav, 2)  # the same ship after an 80 s gap
    other = _fragment(7, ship_b, 650.0, 1200.0, nav, 3)  # another ship starting near the same cone angle
    out = join_fragments([first, later, other], nav)
    assert [m.track_id for m in out] == [1, 7]
    assert out[0].joined_track_ids == (5,) and out[0].time_s[-1] == later.time_s[-1]
    assert out[1].joined_track_ids == ()


def _line(t0, t1, f_hz, seed):
    """A tonal line seen every 2 s over [t0, t1) (0.05 Hz noise), as acoustics/tonal.py's TonalTrack holds it."""
    from sonartrack.acoustics.tonal import TonalTrack

    t = np.arange(t0, t1, 2.0)
    f = f_hz + np.random.default_rng(seed).normal(0.0, 0.05, len(t))
    f[::7] = np.nan  # windows where the line was not seen
    return TonalTrack(float(f_hz), 10.0, t, f, 0.05)


def test_the_tonal_line_vetoes_a_join_of_two_ships_and_allows_one_ship():
    nav = _nav()
    ship_a = [4000.0, 3000.0, -3.0, 1.0]
    first = _fragment(1, ship_a, 0.0, 600.0, nav, 1)
    later = _fragment(5, ship_a, 680.0, 1200.0, nav, 2)
    # the bearings alone join them (test above); a line 55 Hz away on the later one says another ship
    apart = join_fragments([first, later], nav, tonals={1: _line(0.0, 600.0, 120.0, 1), 5: _line(680.0, 1200.0,
                                                                                                 175.0, 2)})
    assert [m.track_id for m in apart] == [1, 5] and apart[0].joined_track_ids == ()
    # the same line, Doppler-shifted by a range-rate change of 2 m/s (0.16 Hz at 120 Hz): one ship
    same = join_fragments([first, later], nav, tonals={1: _line(0.0, 600.0, 120.0, 1), 5: _line(680.0, 1200.0,
                                                                                                120.16, 2)})
    assert [m.track_id for m in same] == [1] and same[0].joined_track_ids == (5,)
    # a line on one fragment only: judged on the bearings
    one = join_fragments([first, later], nav, tonals={1: _line(0.0, 600.0, 120.0, 1), 5: None})
    assert one[0].joined_track_ids == (5,)


def test_tonals_agree_by_hand():
    from sonartrack.systems.passive.fragments import tonals_agree

    t = np.arange(0.0, 100.0, 2.0)
    a = (t, np.full(len(t), 100.0), 0.1)
    # tolerance 3 sqrt(0.1^2 + 0.1^2) + f_max 5 / 1500 = 0.424 + 0.336 = 0.760 Hz (f_max = 100.75 or 100.77)
    assert tonals_agree(a, (t + 200.0, np.full(len(t), 100.75), 0.1))
    assert not tonals_agree(a, (t + 200.0, np.full(len(t), 100.77), 0.1))
    assert tonals_agree(a, None) and tonals_agree(None, a)


def test_a_joined_targets_tonal_is_its_fragments_lines():
    from sonartrack.systems.passive.fragments import joined_tonal

    nav = _nav()
    ship_a = [4000.0, 3000.0, -3.0, 1.0]
    first = _fragment(1, ship_a, 0.0, 600.0, nav, 1)
    later = _fragment(5, ship_a, 680.0, 1200.0, nav, 2)
    lines = {1: _line(0.0, 600.0, 120.0, 1), 5: _line(680.0, 1200.0, 120.1, 2)}
    target = join_fragments([first, later], nav, tonals=lines)[0]
    line = joined_tonal(target, lines)
    assert line.line_hz == 120.0 and len(line.time_s) == len(lines[1].time_s) + len(lines[5].time_s)
    assert np.all(np.diff(line.time_s) > 0)
    assert np.array_equal(line.frequency_hz[line.time_s >= 680.0], lines[5].frequency_hz, equal_nan=True)
    assert joined_tonal(target, {1: None, 5: None}) is None
    only_later = joined_tonal(target, {5: lines[5]})
    assert only_later.line_hz == 120.1 and np.array_equal(only_later.time_s, lines[5].time_s)


SHIP_A, SHIP_B = [4000.0, 3000.0, -3.0, 1.0], [1000.0, 5850.0, 2.0, -3.0]  # cone angles cross near 660 s


def _record(track_id, parts, track_parts):
    """A track's record from pieces of the ships' peaks (each (t, cone)) and of a filtered track."""
    t, cone = (np.concatenate(v) for v in zip(*parts, strict=True))
    tt, tc = (np.concatenate(v) for v in zip(*track_parts, strict=True))
    return TrackMeasurements(track_id, t, cone, np.full(len(t), 8.0), tt, tc)


def _crossing_ships():
    """The two ships' peaks over 0..1200 s and where they lie within 4 deg (a beamwidth) of each other."""
    nav = _nav()
    a, b = (_fragment(0, s, 0.0, 1200.0, nav, seed) for s, seed in ((SHIP_A, 1), (SHIP_B, 2)))
    close = np.abs(a.cone_deg - b.cone_deg) < 4.0
    t0, t1 = a.time_s[close][0], a.time_s[close][-1]
    assert 600.0 < t0 < t1 < 720.0  # one crossing, its ships' cone rates ~0.1 deg/s apart
    return nav, a, b, t0, t1


def _span(m, lo, hi):
    keep = (m.time_s >= lo) & (m.time_s < hi)
    return m.time_s[keep], m.cone_deg[keep]


def test_two_tracks_on_one_ship_after_a_crossing_keep_its_peaks_in_the_one_that_followed_it():
    from sonartrack.systems.passive.shared_scans import drop_unresolved

    nav, a, b, t0, t1 = _crossing_ships()
    mid = (a.time_s >= t0) & (a.time_s <= t1)
    merged = (a.time_s[mid], 0.5 * (a.cone_deg[mid] + b.cone_deg[mid]))
    # track 1 follows ship A up to the crossing, then takes ship B's peaks (coalesced onto B); track 2 follows B
    one = _record(1, [_span(a, 0.0, t0), _span(b, t1 + 1.0, 1200.0)],
                  [_span(a, 0.0, t0), merged, _span(b, t1 + 1.0, 1200.0)])
    two = _record(2, [_span(b, 0.0, 1200.0)], [_span(b, 0.0, t0), merged, _span(b, t1 + 1.0, 1200.0)])
    old = drop_unresolved([one, two], 4.0)
    # without the navigation (as before): the shared peaks leave both records, ship B's target ends at the crossing
    assert old[1].time_s[-1] < t1 + 1.0 and old[0].time_s[-1] < t1 + 1.0
    new = drop_unresolved([one, two], 4.0, nav=nav)
    # with it: the peaks after the crossing are B's, and only track 2's history (B's) predicts them
    assert new[1].time_s[-1] == 1199.0 and np.all(new[1].time_s[new[1].time_s > t1] > t1)
    assert new[0].time_s[-1] < t0 and new[0].track_time_s[-1] < t1 + 1.0  # track 1's record and track end there
    assert np.sum(new[1].time_s > t1) == np.sum(a.time_s > t1)


def test_two_tracks_swapped_at_a_crossing_get_their_parts_after_it_exchanged():
    from sonartrack.systems.passive.shared_scans import drop_unresolved

    nav, a, b, t0, t1 = _crossing_ships()
    mid = (a.time_s >= t0) & (a.time_s <= t1)
    merged = (a.time_s[mid], 0.5 * (a.cone_deg[mid] + b.cone_deg[mid]))
    after = (t1 + 1.0, 1200.0)

    def rec(track_id, before, later):
        return _record(track_id, [_span(before, 0.0, t0), _span(later, *after)],
                       [_span(before, 0.0, t0), merged, _span(later, *after)])

    swapped = drop_unresolved([rec(1, a, b), rec(2, b, a)], 4.0, nav=nav)
    for m, ship in zip(swapped, (a, b), strict=True):
        t, cone = _span(m, *after)
        assert len(t) == np.sum(a.time_s > t1) and np.array_equal(cone, _span(ship, *after)[1]), m.track_id
        assert np.array_equal(m.track_cone_deg[m.track_time_s > t1], _span(ship, *after)[1])
    # tracks that kept their ships are left as they are
    kept = drop_unresolved([rec(1, a, a), rec(2, b, b)], 4.0, nav=nav)
    for m, ship in zip(kept, (a, b), strict=True):
        assert np.array_equal(_span(m, *after)[1], _span(ship, *after)[1])
    # without the navigation nothing is exchanged (the crossing's scans are only left out)
    plain = drop_unresolved([rec(1, a, b), rec(2, b, a)], 4.0)
    assert np.array_equal(_span(plain[0], *after)[1], _span(b, *after)[1])


def _starboard_turn_nav() -> Navigation:
    """Array at 3 m/s north, turning 60 deg to starboard over 400..520 s (no tow)."""
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((400.0, 520.0, np.deg2rad(0.5)),)).state(TIMES)
    return Navigation(TIMES, own[:, 0], own[:, 1], heading, own[:, 0], own[:, 1], heading)


def test_a_ships_fragments_either_side_of_the_arrays_turn_are_joined_on_the_right_fold_branch():
    from sonartrack.systems.passive.fragments import _join_statistic

    nav = _starboard_turn_nav()
    ship = [6000.0, 2000.0, -2.0, 1.0]
    first, later = _fragment(1, ship, 0.0, 470.0, nav, 1), _fragment(5, ship, 560.0, 1200.0, nav, 2)
    # the turn drives the cone angle down 0.5 deg/s at the first fragment's end; carried over the 90 s gap that
    # rate predicts the later fragment's start below 0 deg, on the mirror branch (-phi), though the turn ended at 520 s
    rate = np.polyfit(first.time_s[-20:], first.cone_deg[-20:], 1)[0]
    predicted = first.cone_deg[-1] + rate * (later.time_s[0] - first.time_s[-1])
    assert abs(-later.cone_deg[0] - predicted) < abs(later.cone_deg[0] - predicted)
    # one target on its own branch: the ratio of one ship (about 1)
    assert _join_statistic(first, later, nav) < 1.2
    out = join_fragments([first, later], nav)
    assert [m.track_id for m in out] == [1] and out[0].joined_track_ids == (5,)
    # another ship starting where the first one's fragment ended is still kept apart
    other = _fragment(7, [3000.0, 6000.0, -1.0, -2.0], 560.0, 1200.0, nav, 3)
    assert [m.track_id for m in join_fragments([first, other], nav)] == [1, 7]


def test_fragments_that_are_each_others_best_match_at_a_crossing_are_joined_up_to_the_looser_ratio():
    from dataclasses import replace

    from sonartrack.systems.passive.fragments import (
        MAX_JOIN_VARIANCE_RATIO,
        MUTUAL_JOIN_VARIANCE_RATIO,
        _join_statistic,
    )

    nav = _nav()
    a1, b1 = _fragment(1, SHIP_A, 0.0, 600.0, nav, 1), _fragment(2, SHIP_B, 0.0, 600.0, nav, 2)
    a2, b2 = _fragment(3, SHIP_A, 720.0, 1200.0, nav, 3), _fragment(4, SHIP_B, 720.0, 1200.0, nav, 4)
    a2 = replace(a2, cone_deg=a2.cone_deg + 2.0)  # a slow bias of ship A's peaks after the crossing
    ratio = {(x.track_id, y.track_id): _join_statistic(x, y, nav) for x in (a1, b1) for y in (a2, b2)}
    # A's own fragments: above the plain bound, below the looser one, and far below either cross pairing
    assert MAX_JOIN_VARIANCE_RATIO < ratio[1, 3] < MUTUAL_JOIN_VARIANCE_RATIO
    assert min(ratio[2, 3], ratio[1, 4]) > 3.0 * MUTUAL_JOIN_VARIANCE_RATIO and ratio[2, 4] < MAX_JOIN_VARIANCE_RATIO
    out = join_fragments([a1, b1, a2, b2], nav)
    assert [(m.track_id, m.joined_track_ids) for m in out] == [(1, (3,)), (2, (4,))]
    # the biased fragment alone after A's: the two are each other's only match, joined as well
    assert join_fragments([a1, a2], nav)[0].joined_track_ids == (3,)
    # but not when A's first fragment has a better successor (an unbiased piece of A starting later)
    a3 = _fragment(5, SHIP_A, 760.0, 1200.0, nav, 5)
    assert ratio[1, 3] > _join_statistic(a1, a3, nav)
    out = join_fragments([a1, a2, a3], nav)
    assert [(m.track_id, m.joined_track_ids) for m in out] == [(1, (5,)), (3, ())]


def test_a_joined_targets_filtered_track_is_the_later_fragments_from_its_start():
    # the earlier fragment's filtered track runs on after its last peak (here onto another ship at 130 deg) while the
    # later fragment follows the target: from the later one's start the joined track is the later one's
    ta, tb = np.arange(0.0, 200.0, 1.0), np.arange(120.0, 200.0, 1.0)
    cone_a = np.where(ta < 110.0, 150.0, 130.0)
    a = TrackMeasurements(3, ta[:100], cone_a[:100], np.ones(100), ta, cone_a)
    b = TrackMeasurements(7, tb, np.full(80, 152.0), np.ones(80), tb, np.full(80, 152.0))
    j = _fragments_joined(a, b)
    np.testing.assert_array_equal(j.time_s, np.concatenate([ta[:100], tb]))
    np.testing.assert_array_equal(j.track_time_s, ta)
    np.testing.assert_array_equal(j.track_cone_deg, np.where(ta < 110.0, 150.0, np.where(ta < 120.0, 130.0, 152.0)))
    assert j.track_id == 3


def test_a_ship_that_crosses_the_arrays_axis_in_the_gap_is_joined_on_the_mirror_branch():
    from dataclasses import replace

    # array north at 3 m/s; the ship passes ahead of it through endfire (relative bearing 0) at 500 s, between
    # the fragments: its cone angle comes back up (4 -> 0 -> 4 deg) but on the other side of the axis, so the
    # later fragment's unfolded angles continue the first's on the mirror branch (-phi)
    nav = Navigation(TIMES, np.zeros_like(TIMES), 3.0 * TIMES, np.zeros_like(TIMES), np.zeros_like(TIMES),
                     3.0 * TIMES, np.zeros_like(TIMES))
    ship = [2000.0, 6000.0, -4.0, 0.0]
    first, later = (replace(m, unfolded_deg=m.cone_deg) for m in (_fragment(1, ship, 0.0, 430.0, nav, 1),
                                                                   _fragment(5, ship, 570.0, 1200.0, nav, 2)))
    out = join_fragments([first, later], nav)
    assert [(m.track_id, m.joined_track_ids) for m in out] == [(1, (5,))]
    t = out[0].time_s
    xy, heading = nav.array_at(t)
    truth = np.rad2deg(wrap_angle(bearing_rad(ship[0] + ship[2] * t - xy[:, 0], ship[1] + ship[3] * t - xy[:, 1])
                                  - heading))  # signed: + starboard before 500 s, - port after
    # each part on the truth's branch (0.2 deg noise); imaging the later peaks nearest the first fragment's last
    # unfolded angle put them at +4..+49 deg: back on the first fragment's side
    assert np.max(np.abs(out[0].unfolded_deg - truth)) < 1.5
