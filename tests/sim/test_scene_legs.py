"""Ships and the ownship on legs (sim/scene.py legs, sim/platforms.py LegTrack): positions continuous at the leg
changes, each leg's velocity its stated course and speed, the array towed along the track through turns and speed
changes, truth bearings and Doppler from the positions, the default scene as before, bad legs refused in one line,
and the shipped zigzag scene."""

import tomllib

import numpy as np
import pytest

from sonartrack.cli._settings import resolve
from sonartrack.core.errors import InputError
from sonartrack.core.settings import to_commented_toml
from sonartrack.core.units import KNOT_MPS
from sonartrack.io.toml import validate
from sonartrack.sim.passive_scene import received_levels, scene_geometry
from sonartrack.sim.sample_inputs import tma_record
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.systems.simulate.files import shipped_scene_path

SILENT = -100.0
ZIG_LEGS = [{"duration_s": 600.0, "course_deg": 250.0, "speed_kn": 8.0},
            {"duration_s": 720.0, "course_deg": 310.0, "speed_kn": 8.0},
            {"duration_s": 600.0, "course_deg": 230.0, "speed_kn": 10.0},
            {"course_deg": 280.0, "speed_kn": 8.0}]
OWN_LEGS = [{"duration_s": 1200.0, "course_deg": 0.0, "speed_kn": 6.0}, {"course_deg": 80.0, "speed_kn": 6.0}]


def unit(course_deg: float) -> np.ndarray:
    c = np.deg2rad(course_deg)
    return np.array([np.sin(c), np.cos(c)])


def leg_scene(ship_legs=ZIG_LEGS, own=None, **kw) -> PassiveSceneSettings:
    ship = {"name": "zig", "x_m": 7000.0, "y_m": 9000.0, "legs": ship_legs, "source_level_db": SILENT,
            "tonal_hz": 200.0, "tonal_level_db": SILENT}
    base = {"duration_s": 2700.0, "noise_level_db": SILENT, "ownship": own or {"legs": OWN_LEGS}, "ships": [ship]}
    return PassiveSceneSettings(**(base | kw))


def by_hand(legs, p0, t: float) -> np.ndarray:
    """Position on instantaneous-change legs: p0 plus each leg's velocity times the time spent on it by t."""
    p, start = np.array(p0, float), 0.0
    for k, leg in enumerate(legs):
        end = start + leg["duration_s"] if k < len(legs) - 1 else np.inf
        p = p + leg["speed_kn"] * KNOT_MPS * unit(leg["course_deg"]) * np.clip(t - start, 0.0, end - start)
        start = end
    return p


def test_ship_positions_continuous_at_leg_changes_and_equal_to_the_legs_by_hand():
    s = leg_scene()
    changes = np.array([600.0, 1320.0, 1920.0])
    eps = 1e-3
    g = scene_geometry(s, np.concatenate([changes - eps, changes + eps]))
    before, after = g.ship_xy[0, :3], g.ship_xy[0, 3:]
    assert np.all(np.hypot(*(after - before).T) < 10.0 * KNOT_MPS * 2 * eps + 1e-9)
    t = np.array([0.0, 300.0, 600.0, 1000.0, 1320.0, 1700.0, 1920.0, 2500.0, 2700.0])
    g = scene_geometry(s, t)
    expected = np.array([by_hand(ZIG_LEGS, (7000.0, 9000.0), ti) for ti in t])
    np.testing.assert_allclose(g.ship_xy[0], expected, atol=1e-6)


def test_each_leg_velocity_is_its_course_and_speed():
    s = leg_scene()
    mids = np.array([300.0, 960.0, 1620.0, 2300.0])
    g = scene_geometry(s, mids)
    for k, leg in enumerate(ZIG_LEGS):
        v = leg["speed_kn"] * KNOT_MPS * unit(leg["course_deg"])
        np.testing.assert_allclose(g.ship_velocity[0, k], v, atol=1e-9)
        # and the positions move so (a finite difference inside the leg)
        p = scene_geometry(s, np.array([mids[k] - 5.0, mids[k] + 5.0])).ship_xy[0]
        np.testing.assert_allclose((p[1] - p[0]) / 10.0, v, atol=1e-9)


def test_ownship_turns_at_its_rate_and_tows_the_array_along_its_track():
    s = leg_scene()
    v, rate = 6.0 * KNOT_MPS, np.deg2rad(0.5)
    radius = v / rate
    turn_end = 1200.0 + 80.0 / 0.5
    corner = np.array([0.0, v * 1200.0])
    after_turn = corner + radius * np.array([1.0 - np.cos(np.deg2rad(80.0)), np.sin(np.deg2rad(80.0))])
    t = np.array([600.0, 1200.0 + 40.0 / 0.5, 2000.0])
    g = scene_geometry(s, t)
    own_expected = [np.array([0.0, v * 600.0]),
                    corner + radius * np.array([1.0 - np.cos(np.deg2rad(40.0)), np.sin(np.deg2rad(40.0))]),
                    after_turn + v * (2000.0 - turn_end) * unit(80.0)]
    np.testing.assert_allclose(g.own_xy, own_expected, atol=1e-6)
    np.testing.assert_allclose(np.rad2deg(g.own_heading_rad), [0.0, 40.0, 80.0], atol=1e-9)
    # the array centre is 200 m of track behind: on the first leg straight astern, in the turn where the ship was
    # 200 / v s before (heading lagging), after it straight astern again
    np.testing.assert_allclose(g.array_xy[0], own_expected[0] - [0.0, 200.0], atol=1e-6)
    lag = 200.0 / v
    back = corner + radius * np.array([1.0 - np.cos(rate * (80.0 - lag)), np.sin(rate * (80.0 - lag))])
    np.testing.assert_allclose(g.array_xy[1], back, atol=1e-6)
    assert np.rad2deg(g.array_heading_rad[1]) == pytest.approx(np.rad2deg(rate * (80.0 - lag)), abs=1e-9)
    np.testing.assert_allclose(g.array_xy[2], own_expected[2] - 200.0 * unit(80.0), atol=1e-6)


def test_array_keeps_its_tow_length_through_a_speed_change():
    own = {"legs": [{"duration_s": 600.0, "course_deg": 0.0, "speed_kn": 6.0}, {"course_deg": 0.0, "speed_kn": 12.0}]}
    g = scene_geometry(leg_scene(own=own), np.array([610.0, 620.0]))
    y_own = 6.0 * KNOT_MPS * 600.0 + 12.0 * KNOT_MPS * np.array([10.0, 20.0])
    np.testing.assert_allclose(g.own_xy[:, 1], y_own, atol=1e-6)
    np.testing.assert_allclose(g.array_xy[:, 1], y_own - 200.0, atol=1e-6)  # not 200 m x 12 / 6 behind


def test_truth_bearings_range_rate_and_doppler_follow_the_positions():
    s = leg_scene()
    t = np.arange(0.0, 2701.0, 1.0)
    g = scene_geometry(s, t)
    d = g.ship_xy[0] - g.array_xy
    np.testing.assert_allclose(g.bearing_rad[0], np.arctan2(d[:, 0], d[:, 1]), atol=1e-12)
    axis = np.stack([np.sin(g.array_heading_rad), np.cos(g.array_heading_rad)], axis=-1)
    cone = np.arccos(np.clip(np.sum(d * axis, axis=1) / np.hypot(*d.T), -1, 1))
    np.testing.assert_allclose(g.cone_rad[0], cone, atol=1e-9)
    # range rate = d range / dt inside the legs (central differences; the zigs and the array's turn, 1200 + 64.8 s
    # to 1360 + 64.8 s, excluded)
    r = np.hypot(*d.T)
    rdot_fd = (r[2:] - r[:-2]) / 2.0
    inside = np.ones(t.size - 2, bool)
    for c in (600.0, 1264.8, 1320.0, 1424.8, 1920.0):
        inside &= np.abs(t[1:-1] - c) > 2.0
    np.testing.assert_allclose(g.range_rate_mps[0, 1:-1][inside], rdot_fd[inside], atol=1e-4)
    f = received_levels(s, g).tonal_hz[0]
    np.testing.assert_allclose(f, 200.0 * (1.0 - g.range_rate_mps[0] / s.sound_speed_mps), rtol=1e-12)


def test_brg_and_own_files_agree_with_the_legs():
    s = leg_scene(samples={"sigma_bearing_deg": 0.0, "sigma_freq_hz": 0.0, "tma_interval_s": 30.0})
    bearings, own = tma_record(s, np.random.default_rng(0))
    for t, b, x, y in zip(bearings["time_s"], bearings["bearing_deg"], own["x_m"], own["y_m"], strict=True):
        p = by_hand(ZIG_LEGS, (7000.0, 9000.0), t)
        assert b == pytest.approx(np.rad2deg(np.arctan2(p[0] - x, p[1] - y)) % 360.0, abs=1e-9)


def test_a_ship_on_legs_placed_relative_to_the_array_is_there_at_its_time():
    ship = {"name": "p", "at_time_s": 1500.0, "at_range_m": 5000.0, "at_relative_bearing_deg": 90.0,
            "legs": ZIG_LEGS, "source_level_db": SILENT}
    s = PassiveSceneSettings(duration_s=2700.0, noise_level_db=SILENT, ownship={"legs": OWN_LEGS}, ships=[ship])
    g = scene_geometry(s, np.array([1500.0]))
    assert g.range_m[0, 0] == pytest.approx(5000.0, abs=1e-6)
    assert np.rad2deg(g.cone_rad[0, 0]) == pytest.approx(90.0, abs=1e-9)


def test_default_scene_is_the_constant_velocity_one_by_hand():
    """The default scene (no legs): ships p0 + v t from passive.toml's values, the ownship north at 6 kn turning
    45 deg to port at 0.5 deg/s from 555 s (centred on 600 s), the array 200 m astern."""
    s = PassiveSceneSettings()
    assert all(ship.legs is None for ship in s.ships) and s.ownship.legs is None
    v = 6.0 * KNOT_MPS
    t = np.array([100.0, 500.0, 1100.0])
    g = scene_geometry(s, t)
    merchant = np.array([4700.0, 6900.0]) + 12.0 * KNOT_MPS * unit(140.0) * t[:, None]
    np.testing.assert_allclose(g.ship_xy[0], merchant, atol=1e-6)
    np.testing.assert_allclose(g.ship_velocity[1], np.tile(8.0 * KNOT_MPS * unit(325.0), (3, 1)), atol=1e-12)
    array_before = np.array([[0.0, v * 100.0 - 200.0], [0.0, v * 500.0 - 200.0]])
    np.testing.assert_allclose(g.array_xy[:2], array_before, atol=1e-6)
    d = merchant[:2] - array_before
    np.testing.assert_allclose(g.bearing_rad[0, :2], np.arctan2(d[:, 0], d[:, 1]), atol=1e-12)
    radius = v / np.deg2rad(0.5)  # after the turn (555..645 s): course 315
    out = np.array([0.0, v * 555.0]) + radius * np.array([np.cos(np.pi / 4) - 1.0, np.sin(np.pi / 4)])
    np.testing.assert_allclose(g.own_xy[2], out + v * (1100.0 - 645.0) * unit(315.0), atol=1e-6)


@pytest.mark.parametrize("legs, field", [
    ([{"duration_s": -900.0, "course_deg": 270.0, "speed_kn": 8.0}, {"course_deg": 210.0, "speed_kn": 10.0}],
     "legs.0.duration_s"),
    ([{"duration_s": 900.0, "course_deg": 270.0, "speed_kn": 61.0}, {"course_deg": 210.0, "speed_kn": 10.0}],
     "legs.0.speed_kn"),
    ([{"duration_s": float("nan"), "course_deg": 270.0, "speed_kn": 8.0}, {"course_deg": 210.0, "speed_kn": 10.0}],
     "legs.0.duration_s"),
    ([{"duration_s": 900.0, "course_deg": 270.0, "speed_kn": 8.0}, {"course_deg": float("inf"), "speed_kn": 1.0}],
     "legs.1.course_deg"),
    ([], "legs"),
    ([{"duration_s": 900.0, "course_deg": 360.0, "speed_kn": 8.0}, {"course_deg": 210.0, "speed_kn": 10.0}],
     "legs.0.course_deg"),
    ([{"duration_s": 900.0, "course_deg": -5.0, "speed_kn": 8.0}, {"course_deg": 210.0, "speed_kn": 10.0}],
     "legs.0.course_deg"),
    ([{"course_deg": 270.0, "speed_kn": 8.0}, {"course_deg": 210.0, "speed_kn": 10.0}], "legs[0] has no duration_s"),
    ([{"duration_s": 900.0, "course_deg": 270.0, "speed_kn": 8.0}, {"duration_s": 60.0, "course_deg": 210.0,
                                                                     "speed_kn": 10.0}], "legs[1].duration_s"),
])
def test_bad_ship_legs_are_refused_in_one_line(legs, field):
    ship = {"name": "zig", "x_m": 0.0, "y_m": 5000.0, "source_level_db": 130.0, "legs": legs}
    with pytest.raises(InputError) as e:
        validate(PassiveSceneSettings, {"ships": [ship]}, source="config zig.toml")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("config zig.toml: ") and field in msg


@pytest.mark.parametrize("own, words", [
    ({"legs": [{"duration_s": 600.0, "course_deg": 0.0, "speed_kn": 6.0},
               {"duration_s": 60.0, "course_deg": 90.0, "speed_kn": 6.0}, {"course_deg": 0.0, "speed_kn": 6.0}]},
     "not longer than the turn"),
    ({"turn_deg": 30.0, "legs": OWN_LEGS}, "ownship.turn_deg"),
    ({"legs": [{"duration_s": 600.0, "course_deg": 0.0, "speed_kn": 0.0}, {"course_deg": 9.0, "speed_kn": 6.0}]},
     "ownship.legs.0.speed_kn"),
    ({"legs": []}, "ownship.legs"),
])
def test_bad_ownship_legs_are_refused_in_one_line(own, words):
    with pytest.raises(InputError) as e:
        validate(PassiveSceneSettings, {"ownship": own}, source="config own.toml")
    assert "\n" not in str(e.value) and words in str(e.value)


def test_shipped_zigzag_scene_has_its_legs_and_reads_back(tmp_path):
    s = resolve(PassiveSceneSettings, shipped_scene_path("zigzag"))
    zig = next(ship for ship in s.ships if ship.name == s.tma_ship_name())
    courses = [leg.course_deg for leg in zig.legs]
    turns = np.abs((np.diff(courses) + 180.0) % 360.0 - 180.0)
    assert len(turns) == 3 and np.all((turns >= 40.0) & (turns <= 90.0))
    durations = [leg.duration_s for leg in zig.legs[:-1]]
    assert all(600.0 <= d <= 1200.0 for d in durations) and s.duration_s - sum(durations) >= 600.0
    assert len(s.ownship.legs) == 2
    path = tmp_path / "printed.toml"
    path.write_text(to_commented_toml(s))
    assert resolve(PassiveSceneSettings, path) == s
    assert tomllib.loads(path.read_text())["ships"][0]["legs"][3]["course_deg"] == courses[3]


def test_a_leg_value_out_of_range_names_its_range_and_unit():
    """A bound inside a list of legs is reported like any other setting's: its range and unit (io/toml.py looks
    inside ``list[Leg] | None``), and a check across fields without pydantic's 'Value error, ' prefix."""
    legs = [{"duration_s": 900.0, "course_deg": 270.0, "speed_kn": 61.0}, {"course_deg": 210.0, "speed_kn": 10.0}]
    ship = {"name": "zig", "x_m": 0.0, "y_m": 5000.0, "source_level_db": 130.0, "legs": legs}
    with pytest.raises(InputError) as e:
        validate(PassiveSceneSettings, {"ships": [ship]}, source="config zig.toml")
    assert "is outside its range" in str(e.value) and "(kn)" in str(e.value)
    own = {"legs": [{"duration_s": 600.0, "course_deg": 0.0, "speed_kn": 6.0},
                    {"duration_s": 60.0, "course_deg": 90.0, "speed_kn": 6.0}, {"course_deg": 0.0, "speed_kn": 6.0}]}
    with pytest.raises(InputError) as e:
        validate(PassiveSceneSettings, {"ownship": own}, source="config own.toml")
    assert "Value error" not in str(e.value)
