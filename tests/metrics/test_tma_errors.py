"""TMA error metrics (metrics/tma_errors.py) on hand-worked cases: every study claim of P2 rests on them."""

import warnings

import numpy as np
import pytest

from sonartrack.core.units import KNOT_MPS as KN
from sonartrack.metrics.tma_errors import diverged, time_averaged_rmse, tma_errors


def state(x, y, course_deg, speed_mps):
    c = np.deg2rad(course_deg)
    return np.array([x, y, speed_mps * np.sin(c), speed_mps * np.cos(c)])


def test_position_and_velocity_errors_hand_case():
    """A 3-4-5 position error and a 0.6-0.8-1.0 velocity error."""
    e = tma_errors(np.array([103.0, 204.0, 1.6, 2.8]), np.array([100.0, 200.0, 1.0, 2.0]))
    assert e["position_m"] == pytest.approx(5.0)
    assert e["velocity_mps"] == pytest.approx(1.0)


@pytest.mark.parametrize("est_deg,true_deg,err_deg", [
    (350.0, 10.0, -20.0),  # across north, counter-clockwise: -20, not +340
    (10.0, 350.0, 20.0),  # across north, clockwise: +20, not -340
    (-170.0, 170.0, 20.0),  # across south (courses given in -180..180)
    (100.0, 90.0, 10.0),
    (90.0, 270.0, 180.0),  # opposite courses: +180 (the wrap is onto (-180, 180])
    (270.0, 90.0, 180.0),
])
def test_course_error_wraps(est_deg, true_deg, err_deg):
    e = tma_errors(state(0, 0, est_deg, 5.0), state(0, 0, true_deg, 5.0))
    assert np.rad2deg(e["course_rad"]) == pytest.approx(err_deg, abs=1e-9)
    assert e["speed_mps"] == pytest.approx(0.0, abs=1e-12)


def test_speed_error_is_signed():
    slow = tma_errors(state(0, 0, 45.0, 8 * KN), state(0, 0, 45.0, 10 * KN))
    fast = tma_errors(state(0, 0, 45.0, 12 * KN), state(0, 0, 45.0, 10 * KN))
    assert slow["speed_mps"] == pytest.approx(-2 * KN) and fast["speed_mps"] == pytest.approx(2 * KN)
    # the same speed on another course: no speed error, all of it in the velocity and course errors
    turned = tma_errors(state(0, 0, 135.0, 10 * KN), state(0, 0, 45.0, 10 * KN))
    assert turned["speed_mps"] == pytest.approx(0.0, abs=1e-12)
    assert turned["velocity_mps"] == pytest.approx(np.sqrt(2) * 10 * KN)
    assert np.rad2deg(turned["course_rad"]) == pytest.approx(90.0)


def test_errors_broadcast_over_runs_and_times():
    truth = np.tile(state(0, 1000, 90, 5), (3, 4, 1))
    est = truth.copy()
    est[1, 2, 0] += 30.0
    e = tma_errors(est, truth)
    assert e["position_m"].shape == (3, 4)
    assert e["position_m"][1, 2] == 30.0 and np.count_nonzero(e["position_m"]) == 1


def test_nan_estimate_gives_nan_errors():
    e = tma_errors(np.full(4, np.nan), state(0, 0, 10, 5))
    assert all(np.isnan(v) for v in e.values())


def test_time_averaged_rmse_hand_case_skips_nan():
    errors = np.array([[3.0, 4.0, 12.0],
                       [0.0, np.nan, 5.0]])
    assert time_averaged_rmse(errors) == pytest.approx(np.sqrt((9 + 16 + 144 + 0 + 25) / 5))  # NaN skipped
    assert time_averaged_rmse(errors, 0, 2) == pytest.approx(np.sqrt((9 + 16 + 0) / 3))  # window [0, 2)
    assert time_averaged_rmse(errors, 2) == pytest.approx(np.sqrt((144 + 25) / 2))
    assert time_averaged_rmse(errors, 1, 2) == pytest.approx(4.0)  # one value in the window


def test_time_averaged_rmse_with_no_values_is_nan():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # quietly: NaN is the documented answer, not a warning
        assert np.isnan(time_averaged_rmse(np.full((2, 3), np.nan)))
        assert np.isnan(time_averaged_rmse(np.array([[1.0, np.nan]]), 1))


def test_divergence_threshold_boundary():
    r = np.array([10_000.0] * 4)
    e = np.array([2499.0, 2500.0, 2500.0 + 1e-9, np.nan])
    np.testing.assert_array_equal(diverged(e, r, 0.25), [False, False, True, True])  # at the threshold: not
    # the default threshold is a quarter of the range
    np.testing.assert_array_equal(diverged(e, r), diverged(e, r, 0.25))
    # the range can vary per checkpoint (broadcast)
    np.testing.assert_array_equal(diverged(np.array([300.0, 300.0]), np.array([1000.0, 2000.0]), 0.2), [True, False])
