"""The measured range rate (a CW's Doppler) as a factor on each contact's likelihood ratio in P4's IMM-IPDA
(tracking/measurements.py), against hand-worked cases, and through the active chain's tracker."""

from __future__ import annotations

import numpy as np

from sonartrack.tracking.measurements import PositionMeasurements, RangeRatePositionMeasurements, range_rate_log_factor
from sonartrack.tracking.tracks import Scan

STILL = (np.zeros(2), np.zeros(2))


def test_radial_target_by_hand():
    """Source and receiver still at the origin, target 1 km east opening at 2 m/s: h = 2 u . v = 4;
    g = [0, 0, 2, 0] (the position gradient is 0 for a radial velocity), P_v = 1: s^2 = 0.5^2 + 4; rate 5 measured."""
    x = np.array([[[1000.0, 0.0, 2.0, 0.0]]])
    P = np.diag([100.0, 100.0, 1.0, 1.0])[None, None]
    got = range_rate_log_factor(x, P, np.array([5.0]), STILL, STILL, 0.5, 15.0)
    s2 = 0.25 + 4.0
    want = np.log(30.0) - 0.5 * np.log(2 * np.pi * s2) - 0.5 * 1.0 / s2
    np.testing.assert_allclose(got, [[want]], rtol=1e-12)


def test_tangential_target_by_hand():
    """Target 1 km east moving 3 m/s north: h = 0; dh/dp = 2 (I - u u^T) v / d = (0, 0.006), dh/dv = (2, 0):
    s^2 = 0.1^2 + 0.006^2 * 1e4 + 4 * 0.5."""
    x = np.array([[[1000.0, 0.0, 0.0, 3.0]]])
    P = np.diag([1e4, 1e4, 0.5, 0.5])[None, None]
    got = range_rate_log_factor(x, P, np.array([0.3]), STILL, STILL, 0.1, 10.0)
    s2 = 0.01 + 0.36 + 2.0
    want = np.log(20.0) - 0.5 * np.log(2 * np.pi * s2) - 0.5 * 0.09 / s2
    np.testing.assert_allclose(got, [[want]], rtol=1e-12)


def test_no_rate_no_factor_and_ratios_shift_by_it():
    """A NaN rate (an LFM's) leaves the ratio alone; a measured one adds the factor to the gated pair's ratio."""
    x = np.array([[[1000.0, 0.0, 2.0, 0.0]]])
    P = np.diag([1e4, 1e4, 1.0, 1.0])[None, None]
    scan = Scan(0.0, np.array([[1010.0, 5.0], [1005.0, -3.0]]), np.tile(np.eye(2) * 100.0, (2, 1, 1)))
    base = PositionMeasurements(0.7, 0.99, 1e-6).likelihoods(x, P, scan, {})
    aided = RangeRatePositionMeasurements(0.7, 0.99, 1e-6, 0.5, 15.0).at_scan(STILL, STILL, [4.0, np.nan])
    lik = aided.likelihoods(x, P, scan, {})
    f = range_rate_log_factor(x, P, np.array([4.0]), STILL, STILL, 0.5, 15.0)[0, 0]
    assert f > 0  # a rate on the prediction is more likely from the target than from the uniform clutter law
    np.testing.assert_allclose(lik.pair_log_ratio[lik.pair_meas == 0], base.pair_log_ratio[base.pair_meas == 0] + f)
    np.testing.assert_allclose(lik.pair_log_ratio[lik.pair_meas == 1], base.pair_log_ratio[base.pair_meas == 1])
