"""CTT (Park, Song, Lee 2017, eq. 23) on hand-worked cases: ctt_test and scan_ctt_measures (metrics/tracking.py)."""

import numpy as np
import pytest

from sonartrack.metrics.tracking import CTT_CHI2_4DOF_99, ctt_test, scan_ctt_measures

X_TRUE = np.array([1000.0, 2000.0, 3.0, -4.0])  # [x, y, vx, vy] (m, m/s)
P_DIAG = np.diag([100.0, 400.0, 25.0, 25.0])  # sd 10 m, 20 m, 5 m/s, 5 m/s


def test_threshold_is_the_chi_square_4_quantile():
    from scipy.stats import chi2

    assert abs(CTT_CHI2_4DOF_99 - chi2.ppf(0.99, 4)) < 1e-4


def test_diagonal_initiation_covariance_by_hand():
    # track A: x_hat = [1010, 1980, 3, -4] -> d = x - x_hat = [-10, 20, 0, 0]
    #   d^T P^-1 d = (-10)^2 / 100 + 20^2 / 400 = 1 + 1 = 2 < 13.28: a CTT
    # track B: x_hat = [1040, 2000, 13, -4] -> d = [-40, 0, -10, 0]
    #   d^T P^-1 d = 1600 / 100 + 100 / 25 = 16 + 4 = 20 > 13.28: not a CTT (a confirmed false track)
    x_hat = np.array([[1010.0, 1980.0, 3.0, -4.0], [1040.0, 2000.0, 13.0, -4.0]])
    P = np.stack([P_DIAG, P_DIAG])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, P), [True, False])
    # the distances themselves, through the threshold: A's is 2 (passes 2.001, fails 1.999), B's 20
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, P, threshold=2.001), [True, False])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, P, threshold=1.999), [False, False])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, P, threshold=20.001), [True, True])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, P, threshold=19.999), [True, False])


def test_correlated_position_covariance_by_hand():
    # position block [[100, 50], [50, 100]]: det = 7500, inverse = [[100, -50], [-50, 100]] / 7500
    # d = [10, 10, 0, 0]:  (100*100 - 2*50*100 + 100*100) / 7500 = 10000 / 7500 = 4/3
    # d = [10, -10, 0, 0]: (100*100 + 2*50*100 + 100*100) / 7500 = 30000 / 7500 = 4
    # (a correlated error along the correlation is cheaper than across it)
    P = P_DIAG.copy()
    P[:2, :2] = [[100.0, 50.0], [50.0, 100.0]]
    x_hat = X_TRUE - np.array([[10.0, 10.0, 0.0, 0.0], [10.0, -10.0, 0.0, 0.0]])
    Ps = np.stack([P, P])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, Ps, threshold=4 / 3 + 1e-9), [True, False])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, Ps, threshold=4 / 3 - 1e-9), [False, False])
    np.testing.assert_array_equal(ctt_test(X_TRUE, x_hat, Ps, threshold=4 + 1e-9), [True, True])


def test_scan_measures_pick_the_most_existing_ctt_and_count_false_ones():
    # 0: CTT (d^2 = 2), existence 0.95; 1: false (d^2 = 20); 2: CTT (d = [-30, 0, 0, 0], d^2 = 9), existence 0.99;
    # 3: would be a CTT but is not confirmed
    x_hat = np.array([[1010.0, 1980.0, 3.0, -4.0], [1040.0, 2000.0, 13.0, -4.0], [1030.0, 2000.0, 3.0, -4.0],
                      X_TRUE])
    P = np.stack([P_DIAG] * 4)
    confirmed = np.array([True, True, True, False])
    existence = np.array([0.95, 0.999, 0.99, 1.0])
    has, n_false, err, i = scan_ctt_measures(X_TRUE, x_hat, P, confirmed, existence)
    assert has and n_false == 1 and i == 2
    assert err == pytest.approx(30.0)  # position error of track 2: hypot(30, 0)
    # the first CTT wins when it exists more; its error is hypot(10, 20)
    has, n_false, err, i = scan_ctt_measures(X_TRUE, x_hat, P, confirmed, [0.999, 0.5, 0.9, 1.0])
    assert (has, n_false, i) == (True, 1, 0) and err == pytest.approx(np.hypot(10.0, 20.0))


def test_scan_measures_without_confirmed_or_true_tracks():
    x_hat = np.array([[1040.0, 2000.0, 13.0, -4.0]])
    P = P_DIAG[None]
    has, n_false, err, i = scan_ctt_measures(X_TRUE, x_hat, P, [False], [0.5])
    assert (has, n_false, i) == (False, 0, -1) and np.isnan(err)
    has, n_false, err, i = scan_ctt_measures(X_TRUE, x_hat, P, [True], [0.95])
    assert (has, n_false, i) == (False, 1, -1) and np.isnan(err)
