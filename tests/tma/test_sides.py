"""Port/starboard ambiguity of a line array (tma/sides.py): mirror bearings, and the side decided by which mirror
image a constant-velocity target explains (only after the array turns)."""

import numpy as np
import pytest

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.core.errors import InputError
from sonartrack.sim.passive_scene import scene_geometry
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.tma import sides
from sonartrack.tma.sides import mirror_bearings_rad, resolve_side

SIGMA = np.deg2rad(0.5)
LN100 = np.log(100.0)


def cone_record(target_x0, course_deg=0.0, turn_deg=0.0, seed=3, sigma=SIGMA, step_s=10.0):
    """Own array (no tow) at 3 m/s from the origin on ``course_deg``, turning ``turn_deg`` at 0.5 deg/s from
    t = 600 s; a CV target [x, y, vx, vy] at t = 0; cone angles |wrap(b - h)| every ``step_s`` for 20 min with
    Gaussian noise. Returns (t, cone, heading, sensor_xy, true side)."""
    t = np.arange(0.0, 1200.0 + 1.0, step_s)
    turns = () if turn_deg == 0 else ((600.0, 600.0 + abs(turn_deg) / 0.5, np.sign(turn_deg) * np.deg2rad(0.5)),)
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, np.deg2rad(course_deg), turns).state(t)
    x0 = np.asarray(target_x0, float)
    tgt = x0[:2] + t[:, None] * x0[2:]
    rel = wrap_angle(bearing_rad(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1]) - heading)
    assert np.all(np.sin(rel) > 0.1) or np.all(np.sin(rel) < -0.1)  # the target stays on one side of the axis
    cone = np.clip(np.abs(rel) + np.random.default_rng(seed).normal(0.0, sigma, len(t)), 0.0, np.pi)
    return t, cone, heading, own, ("starboard" if rel.mean() > 0 else "port")


STARBOARD_TARGET = [4000.0, 3000.0, -1.5, 1.0]  # 5 km at bearing 53 deg, moving WNW at 1.8 m/s


def test_mirror_bearings_hand_worked_and_wrapped():
    s, p = mirror_bearings_rad(np.deg2rad([30.0, 120.0, 0.0, 180.0]), np.deg2rad([350.0, 90.0, 10.0, 10.0]))
    # 350 + 30 = 380 -> 20; 350 - 30 = 320 -> -40; 90 + 120 = 210 -> -150; 90 - 120 = -30; endfire: both equal
    np.testing.assert_allclose(np.rad2deg(s), [20.0, -150.0, 10.0, -170.0], atol=1e-12)
    np.testing.assert_allclose(np.rad2deg(p), [-40.0, -30.0, 10.0, -170.0], atol=1e-12)


def test_the_simulators_true_side_mirror_is_its_true_bearing():
    g = scene_geometry(PassiveSceneSettings(), np.arange(0.0, 1200.0, 30.0))
    s, p = mirror_bearings_rad(g.cone_rad, g.array_heading_rad[None])
    starboard = np.sin(g.bearing_rad - g.array_heading_rad[None]) >= 0  # truth.csv's side column
    assert starboard.any() and (~starboard).any()
    np.testing.assert_allclose(wrap_angle(np.where(starboard, s, p) - g.bearing_rad), 0.0, atol=1e-9)


def test_no_turn_leaves_the_side_unresolved():
    t, cone, h, xy, truth = cone_record(STARBOARD_TARGET)
    assert truth == "starboard"
    d = resolve_side(t, cone, h, xy)
    assert d.side == "unresolved" and "turned" in d.note
    assert abs(d.log_likelihood_ratio) < 0.01  # the mirror images fit exactly equally well


def test_a_port_turn_resolves_both_a_starboard_target_and_its_mirror():
    d = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0)[:4])
    assert d.side == "starboard" and d.log_likelihood_ratio > LN100
    # the global ML: within 3 standard deviations (its covariance, scaled by sigma^2) of the truth
    assert np.all(np.abs(d.starboard.x0 - STARBOARD_TARGET) < 3 * np.sqrt(np.diag(d.starboard.covariance)))
    # a port target: the start mirrored about the array's first leg (its exact mirror would pass ahead of the array
    # after the port turn, at endfire), moving so that it stays abeam
    t, cone, h, xy, truth = cone_record([-4000.0, 3000.0, 1.5, -1.0], turn_deg=-45.0)
    assert truth == "port"
    d_port = resolve_side(t, cone, h, xy)
    assert d_port.side == "port" and d_port.log_likelihood_ratio < -LN100


def test_the_mirrored_scene_negates_the_log_likelihood_ratio():
    # reflect everything about the north axis (target x -> -x, turn to starboard): the same noise makes the port
    # hypothesis of one scene the exact mirror of the starboard hypothesis of the other
    d = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0)[:4], sigma_bearing_rad=SIGMA)
    mirrored = [-STARBOARD_TARGET[0], STARBOARD_TARGET[1], -STARBOARD_TARGET[2], STARBOARD_TARGET[3]]
    d_m = resolve_side(*cone_record(mirrored, turn_deg=45.0)[:4], sigma_bearing_rad=SIGMA)
    np.testing.assert_allclose(d_m.log_likelihood_ratio, -d.log_likelihood_ratio, rtol=1e-4)
    assert d_m.side == "port"


def test_bearings_that_wrap_through_south_are_resolved():
    # array heading east; the target, south of it, crosses bearing 180 deg (the (-pi, pi] seam) mid-record
    target = [3000.0, -5000.0, -5.0, 0.0]
    t, cone, h, xy, truth = cone_record(target, course_deg=90.0, turn_deg=45.0)
    z = mirror_bearings_rad(cone, h)[0]
    assert truth == "starboard" and z.max() > 3.0 and z.min() < -3.0
    d = resolve_side(t, cone, h, xy)
    assert d.side == "starboard" and d.log_likelihood_ratio > LN100
    assert d.sigma_bearing_rad < 1.2 * SIGMA


def test_the_multi_start_fit_does_not_run_off_to_infinite_range():
    # a port target opening to 10 km: from the pseudo-linear start alone Levenberg-Marquardt drifts out along the flat
    # far-range valley (to ~1e12 m, cost 0.0075 rad^2); the multi-start fit must reach the lower-cost minimum that an
    # ML started at the truth finds (the noise moves that minimum to ~18 km)
    truth = np.array([-1940.3, -2848.6, -3.6, -2.8])
    t, cone, h, xy, side = cone_record(truth, turn_deg=-45.0, seed=5)
    z_port = mirror_bearings_rad(cone, h)[1]
    fit = sides.fit_cv_target(z_port, t, xy)
    from_truth = sides.ml_bearings_only(z_port, t, xy, 1.0, x_init=truth, check=False)
    assert side == "port" and fit.objective <= from_truth.objective * (1 + 1e-9)
    assert np.hypot(*fit.x0[:2]) < 50e3


@pytest.fixture(scope="module")
def default_scene():
    scene = PassiveSceneSettings()
    t = np.arange(0.0, scene.duration_s, 5.0)
    return scene, t, scene_geometry(scene, t)


def test_every_ship_of_the_default_scene_is_on_its_true_side_after_the_turn(default_scene):
    scene, t, g = default_scene
    rng = np.random.default_rng(11)
    for i, ship in enumerate(scene.ships):
        truth = np.where(np.sin(g.bearing_rad[i] - g.array_heading_rad) >= 0, "starboard", "port")
        assert len(set(truth)) == 1, ship.name  # no ship crosses the array axis in the default scene
        cone = np.clip(g.cone_rad[i] + rng.normal(0.0, SIGMA, len(t)), 0.0, np.pi)
        d = resolve_side(t, cone, g.array_heading_rad, g.array_xy)
        assert d.side == truth[0], (ship.name, d)
        assert abs(d.log_likelihood_ratio) > 10 * LN100, ship.name
        before = t < scene.turn_start_s  # the array has not started to turn yet
        d0 = resolve_side(t[before], cone[before], g.array_heading_rad[before], g.array_xy[before])
        assert d0.side == "unresolved", (ship.name, d0)


def test_measured_sigma_is_the_true_bearing_noise():
    for seed in (1, 2, 3):
        d = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0, seed=seed)[:4])
        assert abs(d.sigma_bearing_rad / SIGMA - 1.0) < 0.2, seed
    given = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0)[:4], sigma_bearing_rad=2 * SIGMA)
    measured = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0)[:4])
    assert given.sigma_bearing_rad == 2 * SIGMA
    # ln LR scales as 1 / sigma^2
    np.testing.assert_allclose(given.log_likelihood_ratio * 4 * SIGMA**2,
                               measured.log_likelihood_ratio * measured.sigma_bearing_rad**2, rtol=1e-9)


def test_noise_free_cones_use_the_sigma_floor():
    d = resolve_side(*cone_record(STARBOARD_TARGET, turn_deg=-45.0, sigma=0.0)[:4])
    assert d.sigma_bearing_rad == sides.SIGMA_FLOOR_RAD and d.side == "starboard"


def test_too_few_bearings_and_failed_fits_are_unresolved(monkeypatch):
    t, cone, h, xy, _ = cone_record(STARBOARD_TARGET, turn_deg=-45.0)
    d = resolve_side(t[:5], cone[:5], h[:5], xy[:5])
    assert (d.side, d.log_likelihood_ratio, d.starboard) == ("unresolved", 0.0, None) and "too few" in d.note

    def fail(*args, **kwargs):
        raise np.linalg.LinAlgError("singular")

    monkeypatch.setattr(sides, "ml_bearings_only", fail)
    d = resolve_side(t, cone, h, xy)
    assert (d.side, d.log_likelihood_ratio) == ("unresolved", 0.0) and "starboard and port" in d.note


@pytest.mark.parametrize("bad", ["nan_cone", "nan_xy", "shape", "unsorted", "cone_range"])
def test_bad_input_raises_input_error(bad):
    t, cone, h, xy, _ = cone_record(STARBOARD_TARGET, turn_deg=-45.0)
    t, cone, xy = t.copy(), cone.copy(), xy.copy()
    if bad == "nan_cone":
        cone[3] = np.nan
    elif bad == "nan_xy":
        xy[4, 1] = np.nan
    elif bad == "shape":
        h = h[:-1]
    elif bad == "unsorted":
        t[[2, 3]] = t[[3, 2]]
    else:
        cone[0] = 4.0
    with pytest.raises(InputError, match="resolve_side"):
        resolve_side(t, cone, h, xy)


def _crossing_record(seed=5):
    """Own array at 3 m/s north, turning 30 deg to starboard from 600 s; a CV target from (2000, -3000) m going west
    at 5 m/s crosses astern (the array's axis, cone angle 180 deg) at 400 s (and the turn sweeps the axis past it
    twice more). Returns (t, unfolded phi with noise,
    heading, sensor, true bearing)."""
    t = np.arange(0.0, 1201.0, 10.0)
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((600.0, 660.0, np.deg2rad(0.5)),)).state(t)
    tgt = np.array([2000.0, -3000.0]) + t[:, None] * np.array([-5.0, 0.0])
    b = bearing_rad(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])
    phi = np.unwrap(wrap_angle(b - heading))  # starts on starboard (0 < phi < pi), passes pi at the crossing
    assert 0 < phi[0] < np.pi and phi[-1] > np.pi
    return t, phi + np.random.default_rng(seed).normal(0.0, SIGMA, len(t)), heading, own, b


def test_axis_crossings_and_sides_per_segment_by_hand():
    assert sides.axis_crossings([0.0, 1.0, 2.0, 3.0], np.deg2rad([170.0, 178.0, 182.0, 190.0])).tolist() == [1.5]
    d = sides.SideDecision("starboard", 10.0, 0.01, None, None, crossings_s=(100.0, 300.0))
    assert d.side_at([50.0, 150.0, 400.0]).tolist() == ["starboard", "port", "starboard"]
    assert d.final_side == "starboard"
    assert sides.SideDecision("port", -9.0, 0.01, None, None, crossings_s=(5.0,)).final_side == "starboard"


@pytest.mark.parametrize("tracker_bounced", [False, True])
def test_a_target_crossing_the_axis_keeps_a_continuous_true_bearing(tracker_bounced):
    t, phi, heading, own, b_true = _crossing_record()
    if tracker_bounced:  # the tracker reflected back at 180 deg: the crossing alternative must restore it
        cross = float(t[np.argmax(phi > np.pi)])
        phi = np.where(t >= cross, 2.0 * np.pi - phi, phi)
    d = sides.resolve_side_through_crossings(t, phi, heading, own, min_log_lr=LN100)
    # the true side changes at 400 s (the target passes astern), 625 s (the array's turn swings its axis back past
    # the target) and 965 s: starboard, port, starboard, port
    truth = np.where(np.sin(b_true - heading) >= 0, "starboard", "port")
    assert d.side == "starboard" and d.final_side == "port", (d.side, d.crossings_s)
    assert np.mean(d.side_at(t) == truth) > 0.95
    assert len(d.crossings_s) == 3 and abs(d.crossings_s[0] - 400.0) < 30.0
    b = heading + d.unfolded_rad  # the starboard hypothesis through the crossings
    err = np.rad2deg(np.abs(wrap_angle(b - b_true)))
    assert np.max(err[t > 420.0]) < 4.0 * np.rad2deg(SIGMA)  # within noise, not the mirror (tens of deg)
