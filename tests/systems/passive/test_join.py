"""Fragments of one target joined (track-to-track association), fragments of two kept apart."""

import numpy as np

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.io.navigation import Navigation
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.passive.measurements import TrackMeasurements, join_fragments

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
