"""A track's part after a crossing too short to test which ship it follows is left out (systems/passive/measurements.py
``swap_at_crossings``)."""

import numpy as np

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.io.navigation import Navigation
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.shared_scans import drop_unresolved

TIMES = np.arange(0.0, 1201.0, 1.0)
SHIP_A, SHIP_B = [4000.0, 3000.0, -3.0, 1.0], [1000.0, 5850.0, 2.0, -3.0]  # cone angles cross near 660 s


def _nav() -> Navigation:
    """Array at 3 m/s north, turning 40 deg to port from 400 s (no tow)."""
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((400.0, 480.0, -np.deg2rad(0.5)),)).state(TIMES)
    return Navigation(TIMES, own[:, 0], own[:, 1], heading, own[:, 0], own[:, 1], heading)


def _cone(x0, nav, seed):
    """(times, cone angles deg with 0.2 deg noise) of a CV ship [x, y, vx, vy] over 0..1200 s."""
    xy, heading = nav.array_at(TIMES)
    tgt = np.asarray(x0[:2]) + TIMES[:, None] * np.asarray(x0[2:])
    rel = wrap_angle(bearing_rad(tgt[:, 0] - xy[:, 0], tgt[:, 1] - xy[:, 1]) - heading)
    return np.clip(np.rad2deg(np.abs(rel)) + np.random.default_rng(seed).normal(0.0, 0.2, len(TIMES)), 0.0, 180.0)


def _record(track_id, t, cone):
    return TrackMeasurements(track_id, t, cone, np.full(len(t), 8.0), t, cone)


def test_a_few_peaks_after_a_crossing_are_not_given_to_either_ship():
    nav = _nav()
    a, b = _cone(SHIP_A, nav, 1), _cone(SHIP_B, nav, 2)
    close = np.abs(a - b) < 4.0
    t0, t1 = TIMES[close][0], TIMES[close][-1]
    assert 600.0 < t0 < t1 < 720.0
    # both tracks followed their ships up to the crossing; the recording ends 5 s after it, and the tracker left
    # each with the other ship's last 5 peaks (two ships one beam apart: which is which cannot be told by then)
    keep = np.less(TIMES, t1 + 6.0)
    one = _record(1, TIMES[keep], np.where(TIMES[keep] > t1, b[keep], a[keep]))
    two = _record(2, TIMES[keep], np.where(TIMES[keep] > t1, a[keep], b[keep]))
    out = drop_unresolved([one, two], 4.0, nav=nav)
    for m in out:
        assert m.time_s[-1] <= t1 and m.track_time_s[-1] <= t1  # nothing after the crossing, nor of its track
    # with 60 s after the crossing the swap is tested and undone (swap_at_crossings), as before
    keep = np.less(TIMES, t1 + 61.0)
    one = _record(1, TIMES[keep], np.where(TIMES[keep] > t1, b[keep], a[keep]))
    two = _record(2, TIMES[keep], np.where(TIMES[keep] > t1, a[keep], b[keep]))
    out = drop_unresolved([one, two], 4.0, nav=nav)
    assert np.array_equal(out[0].cone_deg[out[0].time_s > t1], a[keep][TIMES[keep] > t1])
