"""A source whose cone angle is fixed to the array (own-ship or array noise) gives no range, however the array turns:
the passive chain's ML must not print one (systems/passive/targets.py fixed_cone_checked), a real target must keep its.
"""

import numpy as np
import pytest

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.systems.passive.targets import fixed_cone_cost, fixed_cone_f, solve_target
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.verdict import FIXED_CONE


def turning_nav(t_end_s=600.0, dt_s=1.0, speed_mps=3.0):
    """Array (at the ship) north at 3 m/s, a 45 deg turn to port at 0.5 deg/s from 200 to 290 s, then straight."""
    t = np.arange(0.0, t_end_s + dt_s, dt_s)
    rate = np.where((t >= 200.0) & (t < 290.0), -np.deg2rad(0.5), 0.0)
    h = np.concatenate([[0.0], np.cumsum(rate[:-1]) * dt_s])
    x = np.concatenate([[0.0], np.cumsum(speed_mps * np.sin(h[:-1]) * dt_s)])
    y = np.concatenate([[0.0], np.cumsum(speed_mps * np.cos(h[:-1]) * dt_s)])
    return Navigation(time_s=t, x_m=x, y_m=y, heading_rad=h, array_x_m=x, array_y_m=y, array_heading_rad=h)


def track(t, cone_deg):
    return TrackMeasurements(track_id=1, time_s=t, cone_deg=cone_deg, amplitude=np.ones_like(t), track_time_s=t,
                             track_cone_deg=cone_deg)


NAV = turning_nav()
STAGES = PassiveSettings(spacing_m=5.0).stages(2000.0, channels=8)
T = np.arange(4.0, 600.0, 8.0)
SIGMA_DEG = 0.5


@pytest.mark.parametrize("seed", range(4))
def test_a_source_at_a_fixed_cone_angle_through_a_turn_has_no_range(seed):
    # the cone angle stays at 70 deg while the array turns 45 deg: the CV ML fits a target ~120 m away moving with
    # the array (range sd ~20 m), which the fixed cone explains as well (better: F < 0)
    m = track(T, 70.0 + SIGMA_DEG * np.random.default_rng(seed).standard_normal(T.size))
    target = solve_target(1, m, None, NAV, STAGES)
    assert target.side.side != "unresolved"
    assert list(target.ml.solution.reasons()) == [FIXED_CONE] * len(T)
    assert not target.sequential.solution.range_flags().any()


@pytest.mark.parametrize("drift_hz", [0.0, 12.0])
def test_nor_through_its_line_s_frequency(drift_hz):
    # a line of the source (steady, or drifting 50.5 -> 62.5 Hz as helper N's a8 artefact): a source moving with
    # the array has no Doppler, so no bearings + frequency ML is fitted and the bearings' verdict stands (without
    # the check the bearings + frequency ML gives "bearings of more than one target" or "inconsistent residuals")
    rng = np.random.default_rng(1)
    m = track(T, 70.0 + SIGMA_DEG * rng.standard_normal(T.size))
    f = 50.5 + drift_hz * T / T[-1] + 0.05 * rng.standard_normal(T.size)
    tonal = TonalTrack(line_hz=float(f.mean()), line_snr_db=10.0, time_s=T, frequency_hz=f, sigma_hz=0.1)
    target = solve_target(1, m, tonal, NAV, STAGES, use_frequency_ml=True)
    assert list(target.ml.solution.reasons()) == [FIXED_CONE] * len(T)
    assert not target.sequential.solution.range_flags().any()


@pytest.mark.parametrize("seed", range(4))
def test_a_real_target_at_5_km_keeps_its_range(seed):
    xy, h = NAV.array_at(T)
    ship = np.array([3000.0, 4000.0]) + np.outer(T, [-2.0, 1.0])
    b = np.arctan2(ship[:, 0] - xy[:, 0], ship[:, 1] - xy[:, 1])
    cone = np.rad2deg(np.abs(np.angle(np.exp(1j * (b - h)))))  # starboard all along
    m = track(T, cone + SIGMA_DEG * np.random.default_rng(seed).standard_normal(T.size))
    target = solve_target(1, m, None, NAV, STAGES)
    assert target.ml.solution.range_flags()[-1]
    cols = solution_columns(target.ml.solution, target.ml.ownship)
    truth = float(np.hypot(*(ship[-1] - xy[-1])))
    assert abs(cols["range_m"][-1] - truth) < 4.0 * cols["range_std_m"][-1]


def test_the_fixed_cone_cost_is_the_weighted_spread_about_the_weighted_mean():
    # cone angles 90, 90, 30 deg: relative sigmas 1, 1, 2 (1 / sin 30), weights 1, 1, 1/4;
    # mean (90 + 90 + 30 / 4) / 2.25 = 83.33 deg; cost 2 (6.667)^2 + (53.33)^2 / 4 = 800 deg^2
    cone = np.deg2rad([90.0, 90.0, 30.0])
    assert fixed_cone_cost(cone, np.array([1.0, 1.0, 2.0])) == pytest.approx(np.deg2rad(1.0) ** 2 * 800.0)


def test_the_extra_sum_of_squares_f_and_its_table_value():
    # J0 = 10, J_cv = 4, n = 14: s2 = 4 / 10, F = (6 / 3) / 0.4 = 5; F(3, 10) at 0.999 is 12.55 (tables)
    f, critical = fixed_cone_f(10.0, 4.0, 14)
    assert f == pytest.approx(5.0)
    assert critical == pytest.approx(12.55, abs=0.01)
    assert fixed_cone_f(3.0, 4.0, 14)[0] < 0  # the fixed cone fitting better than the CV target: F < 0
