"""The passive scene's zig-zag and relative ship placement, against hand-worked geometry; the default scene keeps
its single turn."""

import numpy as np
import pytest
from pydantic import ValidationError

from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.passive_scene import ownship_track, place_ship, scene_geometry
from sonartrack.sim.scene import PassiveSceneSettings

OWN_V = 6.0 * KNOT_MPS
TOW = 200.0


def straight(**kw) -> PassiveSceneSettings:
    base = {"duration_s": 600.0, "ownship": {"turn_deg": 0.0}, "ships": []}
    return PassiveSceneSettings(**(base | kw))


def placed(**ship) -> dict:
    return {"name": "p", "course_deg": 270.0, "speed_kn": 10.0, "source_level_db": 140.0} | ship


def test_a_ship_placed_abeam_by_hand():
    # ownship north at 6 kn from (0, 0), no turn: the array centre at t is (0, v t - 200); a ship 3 km to
    # starboard of it at t = 100 s heading west at 10 kn started at (3000 + 10 kn x 100 s, v 100 - 200)
    s = straight(ships=[placed(at_time_s=100.0, at_range_m=3000.0, at_relative_bearing_deg=90.0)])
    p = place_ship(s, s.ships[0])
    assert p.x_m == pytest.approx(3000.0 + 10.0 * KNOT_MPS * 100.0, abs=1e-9)
    assert p.y_m == pytest.approx(OWN_V * 100.0 - TOW, abs=1e-9)
    assert not p.placed and p.at_time_s is None
    g = scene_geometry(s, np.array([100.0]))
    assert np.rad2deg(g.cone_rad[0, 0]) == pytest.approx(90.0, abs=1e-9)
    assert g.range_m[0, 0] == pytest.approx(3000.0, abs=1e-6)


def test_a_ship_placed_astern_on_the_axis_crosses_it():
    s = straight(ships=[placed(at_time_s=300.0, at_range_m=4000.0, at_relative_bearing_deg=180.0)])
    g = scene_geometry(s, np.array([250.0, 300.0, 350.0]))
    assert np.rad2deg(g.cone_rad[0, 1]) == pytest.approx(180.0, abs=1e-6)
    side = np.sin(g.bearing_rad[0] - g.array_heading_rad)
    assert side[0] > 0 > side[2]  # heading west across the wake: starboard before, port after


def test_two_ships_placed_together_cross_in_cone_angle():
    ships = [placed(name="a", at_time_s=200.0, at_range_m=3000.0, at_relative_bearing_deg=60.0, course_deg=120.0),
             placed(name="b", at_time_s=200.0, at_range_m=7000.0, at_relative_bearing_deg=60.0, course_deg=300.0)]
    s = straight(ships=ships)
    g = scene_geometry(s, np.array([150.0, 200.0, 250.0]))
    d = np.rad2deg(g.cone_rad[0] - g.cone_rad[1])
    assert d[1] == pytest.approx(0.0, abs=1e-9) and d[0] * d[2] < 0


def test_a_ship_is_given_one_way():
    with pytest.raises(ValidationError, match="either x_m and y_m"):
        straight(ships=[placed(x_m=1.0, y_m=2.0, at_time_s=1.0, at_range_m=1.0, at_relative_bearing_deg=0.0)])
    with pytest.raises(ValidationError, match="either x_m and y_m"):
        straight(ships=[placed(at_time_s=1.0, at_range_m=1000.0)])
    with pytest.raises(ValidationError, match="either x_m and y_m"):
        straight(ships=[placed(x_m=1.0)])


def test_zigzag_headings_alternate_by_hand():
    # course 0, turns of +30 deg at 1 deg/s (30 s each) starting 100, 300, 500 s: +30, -30, +30
    s = straight(ownship={"turn_deg": 30.0, "turn_rate_deg_s": 1.0, "turn_start_s": 100.0, "zigzag_turns": 3,
                          "leg_s": 200.0})
    _, _, h = ownship_track(s).state(np.array([50.0, 115.0, 200.0, 400.0, 600.0]))
    np.testing.assert_allclose(np.rad2deg(h), [0.0, 15.0, 30.0, 0.0, 30.0], atol=1e-9)
    assert s.ownship.maneuver_s == pytest.approx(2 * 200.0 + 30.0)


def test_zigzag_centred_when_its_start_is_not_given():
    s = straight(duration_s=1000.0, ownship={"turn_deg": -20.0, "turn_rate_deg_s": 1.0, "zigzag_turns": 2,
                                             "leg_s": 300.0})
    # pattern 300 + 20 s, centred on 500 s: starts at 340 s
    assert s.turn_start_s == pytest.approx(340.0)


def test_zigzag_legs_must_outlast_the_turns():
    with pytest.raises(ValidationError, match="leg_s"):
        straight(ownship={"turn_deg": 90.0, "turn_rate_deg_s": 0.5, "zigzag_turns": 2, "leg_s": 120.0})


def test_the_default_scene_keeps_its_one_turn():
    s = PassiveSceneSettings()
    (t0, t1, rate), = ownship_track(s).turns
    # 45 deg to port at 0.5 deg/s centred on 600 s: 555 .. 645 s
    assert (t0, t1) == (555.0, 645.0) and rate == pytest.approx(-np.deg2rad(0.5))
    assert all(not ship.placed for ship in s.ships)
