"""The coordinated turn at a known rate (filters/coordinated_turn.py) against independent forms: the matrix exponential
of its continuous system (Van Loan's method for Q), Stone Soup's KnownTurnRate (F), a point on a circle worked by hand,
and the constant-velocity model (models/motion.py) as the turn rate goes to 0."""

import numpy as np
import pytest
from scipy.linalg import expm

from sonartrack.filters.coordinated_turn import ct_process_noise, ct_transition
from sonartrack.models.motion import cv_process_noise, cv_transition


def van_loan(dt_s: float, q: float, w: float) -> tuple[np.ndarray, np.ndarray]:
    """F and Q of dx = A x dt + G dW (E dW dW^T = q I dt) by Van Loan (1978): expm of [[-A, G q G^T], [0, A^T]] T."""
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 3], A[3, 2] = -w, w
    G = np.vstack([np.zeros((2, 2)), np.eye(2)])
    M = np.block([[-A, q * G @ G.T], [np.zeros((4, 4)), A.T]]) * dt_s
    E = expm(M)
    F = E[4:, 4:].T
    return F, F @ E[:4, 4:]


@pytest.mark.parametrize("dt_s, w", [(30.0, np.deg2rad(1.0)), (30.0, -np.deg2rad(0.5)), (5.0, 0.3), (30.0, 0.2)])
def test_transition_and_noise_equal_the_matrix_exponential(dt_s, w):
    F, Q = van_loan(dt_s, 0.01, w)
    np.testing.assert_allclose(ct_transition(dt_s, w), F, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(ct_process_noise(dt_s, 0.01, w), Q, rtol=1e-8, atol=1e-10 * np.abs(Q).max())


@pytest.mark.parametrize("w", [np.deg2rad(1.0), -np.deg2rad(0.3), 0.05])
def test_transition_equals_stone_soups_known_turn_rate(w):
    from stonesoup.models.transition.linear import KnownTurnRate

    theirs = KnownTurnRate(turn_noise_diff_coeffs=[0.0, 0.0], turn_rate=w).matrix(time_interval=_timedelta(30.0))
    order = [0, 2, 1, 3]  # theirs [x, vx, y, vy] -> ours [x, y, vx, vy]
    np.testing.assert_allclose(ct_transition(30.0, w), theirs[np.ix_(order, order)], rtol=1e-12, atol=1e-12)


def _timedelta(s):
    import datetime

    return datetime.timedelta(seconds=s)


def test_a_point_on_a_circle_stays_on_it():
    # radius 400 m, speed 4 m/s counter-clockwise about the origin: w = v / R; a quarter turn in 4 steps
    R, v = 400.0, 4.0
    w = v / R
    F = ct_transition(np.pi / 2 / w / 4, w)
    x = np.array([R, 0.0, 0.0, v])
    for _ in range(4):
        x = F @ x
        assert np.hypot(x[0], x[1]) == pytest.approx(R, rel=1e-12)
        assert np.hypot(x[2], x[3]) == pytest.approx(v, rel=1e-12)
    np.testing.assert_allclose(x, [0.0, R, -v, 0.0], atol=1e-9)


@pytest.mark.parametrize("w", [0.0, 1e-12, 1e-7, 1e-5])
def test_the_constant_velocity_limit(w):
    # within O(wT) of CV's F and Q (the rotation's first-order terms w T^2 / 2, sin wT, w T^3 / 6), exactly CV's at 0
    tol = max(abs(w * 30.0), 1e-15)
    np.testing.assert_allclose(ct_transition(30.0, w), cv_transition(30.0, 2), rtol=0, atol=tol * 30.0)
    Q = cv_process_noise(30.0, 0.05, 2)
    np.testing.assert_allclose(ct_process_noise(30.0, 0.05, w), Q, rtol=0, atol=tol * np.abs(Q).max())


@pytest.mark.parametrize("wt", [1e-4, 1e-2, 0.49, 0.51])
def test_small_turns_keep_their_digits(wt):
    # against the matrix exponential where the closed form's differences (wT - sin wT) cancel, and across the
    # series' switch at wT = 1/2
    F, Q = van_loan(30.0, 1.0, wt / 30.0)
    ours = ct_process_noise(30.0, 1.0, wt / 30.0)
    np.testing.assert_allclose(ours, Q, rtol=1e-12, atol=1e-13 * np.abs(Q).max())
    assert ours[0, 3] == pytest.approx(Q[0, 3], rel=1e-8)  # (wT - sin wT) / w^2, the cancelling entry
    np.testing.assert_allclose(ct_transition(30.0, wt / 30.0), F, rtol=1e-12, atol=1e-15)


def test_noise_is_a_covariance():
    Q = ct_process_noise(30.0, 1e-3, np.deg2rad(1.0))
    np.testing.assert_allclose(Q, Q.T)
    assert np.linalg.eigvalsh(Q).min() > 0
