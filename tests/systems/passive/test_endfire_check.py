"""The check of a track near the array's axis (endfire), where a crossing may go unseen: the endfire beam's reach,
the near-axis stretches, and the crossing alternative against tracks that do and do not cross the axis."""

from types import SimpleNamespace

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.systems.passive.targets import _end_stretch_note, endfire_reach_rad
from sonartrack.tma.sides import axis_end_stretches, crossing_alternative, fit_cv_target, near_axis_times

MIN_LOG_LR = float(np.log(100.0))


def test_endfire_reach_is_the_half_power_point_of_a_beam_steered_to_the_axis():
    # du = 0.5 rad: half-power at u = 1 - 0.25 -> theta = arccos(0.75) = 41.41 deg
    assert np.isclose(np.rad2deg(endfire_reach_rad(np.rad2deg(0.5))), 41.4096, atol=1e-3)
    # small du: ~ sqrt(du); a 3.64 deg beam at broadside reaches ~14.5 deg from the axis
    du = np.deg2rad(3.642)
    assert np.isclose(endfire_reach_rad(3.642), np.sqrt(du), rtol=0.01)


def test_axis_end_stretches_are_the_leading_and_trailing_scans_near_either_axis():
    cone = np.deg2rad([2.0, 8.0, 30.0, 90.0, 175.0, 120.0, 170.0, 178.0, 185.0])  # 185: unfolded past 180
    masks = axis_end_stretches(cone, np.deg2rad(12.0))
    assert [np.flatnonzero(m).tolist() for m in masks] == [[0, 1], [6, 7, 8]]
    assert axis_end_stretches(np.deg2rad([40.0, 90.0, 140.0]), np.deg2rad(12.0)) == []
    whole = axis_end_stretches(np.deg2rad([179.0, 178.0]), np.deg2rad(12.0))
    assert all(m.all() for m in whole)


def test_near_axis_times_spread_over_each_stretch_with_the_scan_nearest_the_axis():
    t = np.arange(10.0)
    cone = np.deg2rad([90.0, 100.0, 170.0, 179.0, 172.0, 120.0, 90.0, 60.0, 5.0, 9.0])
    got = near_axis_times(t, cone, np.deg2rad(12.0), per_stretch=2)
    assert got.tolist() == [2.0, 3.0, 4.0, 8.0, 9.0]
    assert near_axis_times(t, np.deg2rad(np.full(10, 90.0)), np.deg2rad(12.0)).size == 0


def _scene(target_xy, target_v, n=300, dt=2.0, seed=3, sigma_u=0.002, turn_deg=-60.0, turn_s=300.0):
    """Own ship north at 3 m/s, turning to ``turn_deg`` at ``turn_s``; the array's heading = own ship's; a CV target.
    Cone angles with noise white in u = cos(theta). Returns t, starboard and port bearings, array centre, cone, truth
    xy, and the truth's bearing relative to the array's heading (rad; > 0 starboard, < 0 port)."""
    t = np.arange(n) * dt
    head = np.where(t < turn_s, 0.0, np.deg2rad(turn_deg))
    v = 3.0 * np.stack([np.sin(head), np.cos(head)], 1)
    xy = np.concatenate([[[0.0, 0.0]], np.cumsum(v[:-1] * dt, 0)])
    tgt = np.asarray(target_xy, float) + np.outer(t, target_v)
    rel = wrap_angle(np.arctan2(tgt[:, 0] - xy[:, 0], tgt[:, 1] - xy[:, 1]) - head)
    u = np.cos(np.abs(rel)) + np.random.default_rng(seed).normal(0.0, sigma_u, n)
    cone = np.arccos(np.clip(u, -1.0, 1.0))
    return t, head + cone, head - cone, xy, cone, tgt, rel


def _crossings(t, rel):
    """Times (s) at which the truth changes side (the scan after the change)."""
    return t[1:][np.sign(rel[1:]) != np.sign(rel[:-1])]


def test_a_target_crossing_the_axis_astern_is_found_by_the_crossing_alternative():
    # target east of the own ship's track moving west, passes astern at 250 s (x = 1500 - 6 t = 0, own ship on the
    # y axis): starboard before, port after; the own ship's turn to port at 300 s keeps it on port (relative
    # bearing -111 deg right after the turn, -92 deg at the end)
    t, stbd, port, xy, cone, tgt, rel = _scene([1500.0, -1000.0], [-6.0, 0.0])
    crossed = _crossings(t, rel)
    assert crossed.tolist() == [252.0] and rel[0] > 0 and rel[-1] < 0, crossed
    assert np.rad2deg(np.pi - np.abs(rel)).min() < 1.0  # through the axis itself, not round the broadside
    reach = endfire_reach_rad(3.642)
    alt = crossing_alternative(t, stbd, port, xy, cone, near_axis_times(t, cone, reach), reach)
    assert alt is not None and alt.log_lr < -MIN_LOG_LR, alt
    assert abs(alt.time_s - 250.0) < 40.0, alt.time_s
    assert np.hypot(*(alt.fit.state_at(t[-1])[0][0, :2] - tgt[-1])) < 300.0
    # the true pattern (starboard then port) is what the alternative fitted: the decided side's starboard-throughout
    # fit ends far off
    decided = fit_cv_target(stbd, t, xy)
    assert np.hypot(*(decided.state_at(t[-1])[0][0, :2] - tgt[-1])) > 1000.0


def test_a_target_that_stays_on_its_side_near_the_axis_rejects_the_crossing():
    # target far astern to starboard, moving with the own ship: relative bearing 174 -> 172 deg over the first leg
    # (within the 14.5 deg reach of the axis), 112 -> 123 deg after the own ship's turn to starboard; never crosses
    t, stbd, port, xy, cone, tgt, rel = _scene([300.0, -3000.0], [0.5, 2.5], turn_deg=60.0)
    assert np.all(rel > 0) and _crossings(t, rel).size == 0
    assert np.all(np.rad2deg(np.abs(rel[t < 300.0])) > 171.0)
    reach = endfire_reach_rad(3.642)
    cands = near_axis_times(t, cone, reach)
    assert cands.size > 0
    alt = crossing_alternative(t, stbd, port, xy, cone, cands, reach)
    assert alt is not None and alt.log_lr > MIN_LOG_LR, alt
    # the noise of u = cos(theta) (0.002) from the weighted fit: the first leg's scans at 172-174 deg have
    # sigma_theta = 0.002 / sin(7 deg) ~ 0.016 rad but are weighted as at the 14.5 deg floor (0.008 rad), which
    # at most doubles it; unweighted, the fit would measure the bearing noise of those scans instead (~0.015)
    assert 0.002 <= alt.sigma_u < 0.005, alt.sigma_u


def _end_crossing_scene(n=211):
    """Own ship north, turning to 300 deg at 200 s; the target 1500 m astern of the second leg at 380 s, moving
    5 m/s to port across it: 45 -> 71 deg starboard on the first leg, 137 -> 180 deg starboard on the second, across
    the axis at 380 s, and at -173 deg (port) when the record ends at 420 s."""
    head = np.deg2rad(-60.0)
    ahead, to_port = np.array([np.sin(head), np.cos(head)]), np.array([-np.cos(head), np.sin(head)])
    own_380 = np.array([0.0, 600.0]) + 3.0 * 180.0 * ahead
    v = 5.0 * to_port
    x0 = own_380 - 1500.0 * ahead - 380.0 * v
    return _scene(x0, v, n=n, turn_deg=-60.0, turn_s=200.0)


def _fitted(t, z, xy, sigma):
    fit = fit_cv_target(z, t, xy)
    x, p = fit.state_at(t[-1])
    return SimpleNamespace(solution=SimpleNamespace(state=x, covariance=p * sigma**2))


def test_a_record_ending_after_an_unseen_crossing_is_flagged_and_a_clean_one_is_not():
    sigma = 0.002 / np.sin(np.deg2rad(20.0))
    side = SimpleNamespace(sigma_bearing_rad=sigma)
    reach = endfire_reach_rad(3.642)
    t, stbd, port, xy, cone, tgt, rel = _end_crossing_scene()
    crossed = _crossings(t, rel)
    assert crossed.size == 1 and 378.0 <= crossed[0] <= 382.0 and rel[0] > 0 and rel[-1] < 0, crossed
    assert np.pi - abs(rel[-1]) < reach and np.pi - cone[-1] < reach
    # starboard bearings throughout are wrong for the last 40 s: the refit without the end stretch disagrees
    note = _end_stretch_note(_fitted(t, stbd, xy, sigma), side, (t, stbd, xy, cone), reach)
    assert note is not None and "ends within a beam" in note
    # the true bearings (starboard, then port) fitted throughout: the refit without the end stretch agrees
    true = np.where(rel > 0, stbd, port)
    assert _end_stretch_note(_fitted(t, true, xy, sigma), side, (t, true, xy, cone), reach) is None
    # the same record stopped before it comes near the axis: no end stretch, nothing to flag
    short = t < 300.0
    assert np.all(np.pi - cone[short] > reach)
    assert _end_stretch_note(_fitted(t[short], stbd[short], xy[short], sigma), side,
                             (t[short], stbd[short], xy[short], cone[short]), reach) is None
