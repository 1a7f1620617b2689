"""A passive target's zigs and legs (systems/passive/target_legs.py through solve_target): a target that turns
50 deg mid-record gets its zig and legs near the truth and no determined constant-velocity answer; a
constant-velocity target keeps its rows; targets.csv has the leg column and the legs rows, the summary line names
the zig. The worlds are built here with numpy: an array that turns twice, cone angles with the line array's noise
in u = cos(theta)."""

from types import SimpleNamespace

import numpy as np
import pytest

import sonartrack.systems.passive.targets as targets_module
from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.systems.passive.tables import target_line, targets_columns
from sonartrack.systems.passive.targets import solve_target
from sonartrack.tma.verdict import MANOEUVRED

KN = 1852.0 / 3600.0
T_END_S = 1800.0
ZIG_S = 900.0
STAGES = PassiveSettings(spacing_m=5.0).stages(2000.0, channels=8)


def velocity(course_deg, speed_kn):
    c = np.radians(course_deg)
    return speed_kn * KN * np.array([np.sin(c), np.cos(c)])


def navigation(dt_s=1.0, speed_mps=3.0):
    """Array (at the ship) north at 3 m/s; 45 deg to port at 300-390 s, 45 deg back to starboard at 1000-1090 s."""
    t = np.arange(0.0, T_END_S + dt_s, dt_s)
    rate = np.deg2rad(0.5) * (((t >= 1000.0) & (t < 1090.0)).astype(float) - ((t >= 300.0) & (t < 390.0)))
    h = np.concatenate([[0.0], np.cumsum(rate[:-1]) * dt_s])
    x = np.concatenate([[0.0], np.cumsum(speed_mps * np.sin(h[:-1]) * dt_s)])
    y = np.concatenate([[0.0], np.cumsum(speed_mps * np.cos(h[:-1]) * dt_s)])
    return Navigation(time_s=t, x_m=x, y_m=y, heading_rad=h, array_x_m=x, array_y_m=y, array_heading_rad=h)


NAV = navigation()


def world(seed, second_course_deg):
    """(track, true positions, times): a target from (5, 4) km at 10 kn on 200 deg, on ``second_course_deg`` from
    ZIG_S; a cone angle every 2 s with sigma_u 0.05 deg."""
    t = np.arange(3.0, T_END_S, 2.0)
    xy, heading = NAV.array_at(t)
    p = (np.array([5000.0, 4000.0]) + np.minimum(t, ZIG_S)[:, None] * velocity(200, 10)
         + np.maximum(t - ZIG_S, 0.0)[:, None] * velocity(second_course_deg, 10))
    bearing = np.arctan2(p[:, 0] - xy[:, 0], p[:, 1] - xy[:, 1])
    cone = np.abs(np.angle(np.exp(1j * (bearing - heading))))
    u = np.cos(cone) + np.radians(0.05) * np.random.default_rng(seed).standard_normal(t.size)
    cone_deg = np.degrees(np.arccos(np.clip(u, -1.0, 1.0)))
    track = TrackMeasurements(track_id=1, time_s=t, cone_deg=cone_deg, amplitude=np.ones_like(t), track_time_s=t,
                              track_cone_deg=cone_deg)
    return track, p, t


@pytest.fixture(scope="module")
def zigging():
    track, p, t = world(0, 250.0)
    return solve_target(1, track, None, NAV, STAGES), p, t


def test_a_zigging_target_gets_its_zig_and_legs_near_the_truth(zigging):
    target, p, t = zigging
    legs = target.legs
    assert len(legs.zigs) == 1 and len(legs.fit.legs) == 2
    zig = legs.zigs[0]
    assert abs(zig.time_s - ZIG_S) < 60.0
    last = legs.fit.legs[-1]
    assert abs(last.course_deg - 250.0) < max(3.0 * last.course_sd_deg, 2.0)
    assert abs(last.speed_kn - 10.0) < max(3.0 * last.speed_sd_kn, 0.5)
    sol = legs.result.solution
    assert sol.range_flags()[-1]
    d = sol.state[-1, :2] - p[-1]
    assert d @ np.linalg.solve(sol.covariance[-1, :2, :2], d) < 5.0**2  # within 5 of its own sds
    # the constant-velocity answers the zig rejects: none determined
    assert all(r.startswith(MANOEUVRED) for r in target.ml.solution.reasons())
    assert not target.sequential.solution.range_flags().any()


def test_the_csv_has_the_leg_column_and_the_legs_rows_and_the_summary_names_the_zig(zigging):
    target, _, t = zigging
    cols = targets_columns(SimpleNamespace(targets=[target]))
    method, leg, time_s = cols["method"], cols["leg"], cols["time_s"]
    assert set(method) == {"ml", "imm-mgekf", "legs"}
    c = target.legs.fit.change_times_s[0]
    for m in ("ml", "legs"):
        rows = method == m
        assert np.array_equal(leg[rows], (time_s[rows] > c).astype(int))
    assert np.sum(method == "legs") == len(t)
    line = target_line(target)
    assert f"zig at {target.legs.zigs[0].time_s:.0f} s" in line and "2 legs; current leg" in line


@pytest.mark.parametrize("seed", range(3))
def test_a_constant_velocity_target_keeps_its_rows_and_one_leg(seed, monkeypatch):
    track, _, _ = world(seed, 200.0)
    target = solve_target(1, track, None, NAV, STAGES)
    assert target.legs is not None and target.legs.zigs == () and target.legs.result is None
    cols = targets_columns(SimpleNamespace(targets=[target]))
    assert set(cols["method"]) == {"ml", "imm-mgekf"} and not np.any(cols["leg"])
    assert "zig" not in target_line(target)
    monkeypatch.setattr(targets_module, "_with_legs", lambda ml, *args: (ml, None))  # the chain without its zig test
    plain = solve_target(1, track, None, NAV, STAGES)
    for a, b in ((target.ml, plain.ml), (target.sequential, plain.sequential)):
        assert np.array_equal(a.solution.state, b.solution.state)
        assert np.array_equal(a.solution.covariance, b.solution.covariance)
        assert list(a.solution.reasons()) == list(b.solution.reasons())
