"""The passive legs against the array's axis and the chain's checks (systems/passive/target_legs.py, targets.py
``legs_checked``, tma/sides.py ``crossing_events``): the tracker's jitter about endfire is one visit of the axis; a
crossing the tracker missed (the chosen side's bearings turned back into the mirror's) is found by the zig test as a
zig and is not counted when the crossing explains it; the legs' rows take the ML's side verdict, a missed zig's
verdict and the jackknife's. Worlds built here with numpy (straight-line geometry, Gaussian noise)."""

from dataclasses import replace

import numpy as np
import pytest

from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.systems.passive.target_legs import _checked_rows, legs_rows, target_legs
from sonartrack.systems.passive.targets import legs_checked, solve_target
from sonartrack.tma.record_verdict import undetermined
from sonartrack.tma.records import BearingRecord
from sonartrack.tma.settings import TmaSettings
from sonartrack.tma.sides import crossing_events, fit_cv_target
from sonartrack.tma.solve import solve_tma
from sonartrack.tma.verdict import NOT_ONE_TARGET, SIDE_UNRESOLVED

DEG = np.pi / 180.0


def test_jitter_about_the_axis_is_one_visit_and_a_later_pass_another():
    t = np.arange(0.0, 1000.0, 1.0)
    phi = np.deg2rad(10.0 - 0.02 * t)  # reaches the axis (0) at 500 s ...
    jitter = (t > 480) & (t < 540)
    phi[jitter] = np.deg2rad(0.3) * np.sign(np.sin(t[jitter]))  # ... and jitters through it for a minute
    phi[t >= 540] = -np.deg2rad(0.02) * (t[t >= 540] - 530.0)
    phi[t >= 900] = -np.pi + np.deg2rad(0.5) * (900.0 - t[t >= 900] + 10.0)  # a clean pass of the axis at -pi
    passes = int(np.sum(np.diff(np.floor(phi / np.pi)) != 0))
    assert passes > 10  # the premise: many passes
    visits = crossing_events(t, phi)
    assert len(visits) == 2
    assert 480.0 < visits[0][0] < 540.0 and visits[0][1] == 0.0
    assert visits[1][1] == pytest.approx(-np.pi)


CROSSING_S = 900.0


def missed_crossing_world(seed: int):
    """An array north at 3 m/s (heading 0) and a target east-bound at 8 m/s that crosses the array's axis 3 km
    ahead at 900 s; cone noise 0.05 deg in u; the chosen side's bearings are the true ones until 900 s and the
    mirror's after (a crossing the tracker missed). Returns (t, chosen, other, xy, rel, truth positions, nav)."""
    t = np.arange(0.0, 1800.0, 2.0)
    xy = np.column_stack([np.zeros_like(t), 3.0 * t])
    p = np.column_stack([-7200.0 + 8.0 * t, np.full_like(t, 5700.0)])
    b = np.arctan2(p[:, 0] - xy[:, 0], p[:, 1] - xy[:, 1])
    u = np.cos(b) + np.radians(0.05) * np.random.default_rng(seed).standard_normal(t.size)
    cone = np.arccos(np.clip(u, -1.0, 1.0))
    side = np.sign(b)
    true_b, mirror = side * cone, -side * cone
    chosen = np.where(t <= CROSSING_S, true_b, mirror)
    other = np.where(t <= CROSSING_S, mirror, true_b)
    rel = 1.0 / np.maximum(np.abs(np.sin(cone)), 0.05)
    nav = Navigation(time_s=t, x_m=xy[:, 0], y_m=xy[:, 1], heading_rad=np.zeros_like(t), array_x_m=xy[:, 0],
                     array_y_m=xy[:, 1], array_heading_rad=np.zeros_like(t))
    return t, chosen, other, xy, rel, p, nav


@pytest.mark.parametrize("seed", range(2))
def test_a_missed_crossing_is_not_counted_as_a_zig(seed):
    t, chosen, other, xy, rel, _, nav = missed_crossing_world(seed)
    fit = fit_cv_target(chosen, t, xy, relative_sigma=rel)
    sigma_u = float(np.sqrt(fit.objective / (len(t) - 4)))
    ml = solve_tma(BearingRecord(time_s=t, bearing_rad=chosen), nav.array_track(),
                   TmaSettings(method="ml", sigma_bearing_deg=np.rad2deg(sigma_u)), unobservable="flag",
                   record_checks=False)
    kw = dict(false_alarm_per_hour=0.05, max_range_sd_fraction=1.0)
    blind = target_legs(t, chosen, xy, rel, fit, sigma_u, ml, **kw)
    assert any(abs(z.time_s - CROSSING_S) < 120.0 for z in blind.zigs)  # the premise: seen as a zig
    seen = target_legs(t, chosen, xy, rel, fit, sigma_u, ml, other=other, axis_visits_s=[CROSSING_S], **kw)
    assert not any(abs(z.time_s - CROSSING_S) < 120.0 for z in seen.zigs)
    assert any(abs(z.time_s - CROSSING_S) < 120.0 for z in seen.crossings)
    far = target_legs(t, chosen, xy, rel, fit, sigma_u, ml, other=other, axis_visits_s=[1500.0], **kw)
    assert len(far.zigs) == len(blind.zigs)  # a visit far from the zig does not explain it


KN = 1852.0 / 3600.0


def turning_navigation(t_end_s=1800.0):
    """Array north at 3 m/s; 45 deg to port at 300-390 s, 45 deg back to starboard at 1000-1090 s."""
    t = np.arange(0.0, t_end_s + 1.0, 1.0)
    rate = np.deg2rad(0.5) * (((t >= 1000.0) & (t < 1090.0)).astype(float) - ((t >= 300.0) & (t < 390.0)))
    h = np.concatenate([[0.0], np.cumsum(rate[:-1])])
    x = np.concatenate([[0.0], np.cumsum(3.0 * np.sin(h[:-1]))])
    y = np.concatenate([[0.0], np.cumsum(3.0 * np.cos(h[:-1]))])
    return Navigation(time_s=t, x_m=x, y_m=y, heading_rad=h, array_x_m=x, array_y_m=y, array_heading_rad=h)


@pytest.fixture(scope="module")
def zig_target():
    """A target from (5, 4) km at 10 kn on 200 deg that turns to 260 deg at 900 s, a cone angle every 2 s with
    sigma_u 0.05 deg, seen from the turning array: (target, true positions, stages)."""
    nav, stages = turning_navigation(), PassiveSettings(spacing_m=5.0).stages(2000.0, channels=8)
    t = np.arange(3.0, 1800.0, 2.0)
    xy, heading = nav.array_at(t)
    c1, c2 = np.radians(200.0), np.radians(260.0)
    p = (np.array([5000.0, 4000.0]) + np.minimum(t, 900.0)[:, None] * 10 * KN * np.array([np.sin(c1), np.cos(c1)])
         + np.maximum(t - 900.0, 0.0)[:, None] * 10 * KN * np.array([np.sin(c2), np.cos(c2)]))
    cone = np.abs(np.angle(np.exp(1j * (np.arctan2(p[:, 0] - xy[:, 0], p[:, 1] - xy[:, 1]) - heading))))
    u = np.cos(cone) + np.radians(0.05) * np.random.default_rng(1).standard_normal(t.size)
    cone_deg = np.degrees(np.arccos(np.clip(u, -1.0, 1.0)))
    track = TrackMeasurements(track_id=1, time_s=t, cone_deg=cone_deg, amplitude=np.ones_like(t), track_time_s=t,
                              track_cone_deg=cone_deg)
    target = solve_target(1, track, None, nav, stages)
    assert target.legs is not None and target.legs.result is not None  # the premise: a zig and legs rows
    return target, p, stages


def test_the_legs_take_the_ml_side_verdict(zig_target):
    target, _, stages = zig_target
    sol = target.ml.solution  # the ML as the chain checks it before the zigs' verdict, then its side undecided
    n = len(sol.time_s)
    clean = replace(sol, range_determined=np.ones(n, bool), undetermined_reason=np.full(n, "", dtype=object))
    ml = undetermined(replace(target.ml, solution=clean), SIDE_UNRESOLVED, "side unresolved (this test)")
    rows = legs_checked(target.legs, ml, float(target.ml.solution.time_s[-1]), stages.min_separation_deg)
    assert not rows.solution.range_flags().any()
    assert set(rows.solution.reasons()) == {SIDE_UNRESOLVED}


def test_a_block_of_another_source_leaves_the_legs_undetermined(zig_target):
    target, _, stages = zig_target
    tb, zb, own, sb = target.legs.blocks
    zb = zb.copy()
    zb[(tb > 1300.0) & (tb < 1450.0)] += 8.0 * DEG  # another ship's bearings in one stretch
    legs = replace(target.legs, blocks=(tb, zb, own, sb))
    rows = legs_checked(legs, target.ml, float(target.ml.solution.time_s[-1]), stages.min_separation_deg)
    assert set(rows.solution.reasons()) == {NOT_ONE_TARGET}


def test_a_leg_fit_its_residuals_reject_is_not_determined(zig_target):
    target, _, _ = zig_target
    fit = target.legs.fit
    t = target.ml.solution.time_s
    rows = legs_rows(fit, t, target.ml.record, target.ml.ownship, target.ml.settings)
    assert _checked_rows(rows, fit, 1.0).solution.range_flags()[-1]  # the premise: determined as fitted
    missed = replace(fit, motion_note="target manoeuvred: residuals reject constant velocity on leg 2")
    checked = _checked_rows(rows, missed, 1.0)
    assert not checked.solution.range_flags().any()
    assert set(checked.solution.reasons()) == {"target manoeuvred"}


def test_the_zigging_target_legs_still_near_the_truth(zig_target):
    target, p, _ = zig_target
    sol = target.legs.result.solution
    assert sol.range_flags()[-1]
    d = sol.state[-1, :2] - p[-1]
    assert d @ np.linalg.solve(sol.covariance[-1, :2, :2], d) < 5.0**2
