"""Batch bearings-only ML (paper P3, eqs. 15-18): Jacobian, efficiency against the CRB, observability, bad input."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.batch_ml import bearing_model, check_observability, crb, fisher_information, ml_bearings_only

KN = 1852.0 / 3600.0


def scenario():
    """Observer 5 kn with two 90-deg turns, target ~6 km at 4 kn; bearings every 60 s for 30 min."""
    t = np.arange(0.0, 1800.0 + 1.0, 60.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KN, 0.0, ((600.0, 660.0, np.deg2rad(1.5)), (1200.0, 1260.0, np.deg2rad(-1.5))))
    po, _, _ = obs.state(t)
    c = np.deg2rad(250.0)
    x0 = np.array([3000.0, 5200.0, 4 * KN * np.sin(c), 4 * KN * np.cos(c)])
    return t, po, x0


def test_jacobian_matches_finite_differences():
    t, po, x0 = scenario()
    _, H, _ = bearing_model(x0, t, po)
    eps = np.array([1.0, 1.0, 1e-3, 1e-3])
    for i in range(4):
        dp = np.eye(4)[i] * eps[i]
        num = (bearing_model(x0 + dp, t, po)[0] - bearing_model(x0 - dp, t, po)[0]) / (2 * eps[i])
        np.testing.assert_allclose(H[:, i], num, rtol=1e-5, atol=1e-12)


def test_ml_rmse_is_within_20_percent_of_the_crb():
    t, po, x0 = scenario()
    sigma = np.deg2rad(1.0)
    h, _, _ = bearing_model(x0, t, po)
    rng = np.random.default_rng(2019)
    errs = np.array([ml_bearings_only(h + rng.normal(0, sigma, len(t)), t, po, sigma).x0 - x0 for _ in range(300)])
    rmse = np.sqrt(np.mean(errs**2, axis=0))
    bound = np.sqrt(np.diag(crb(x0, t, po, sigma)))
    np.testing.assert_allclose(rmse, bound, rtol=0.2)
    assert np.all(np.abs(errs.mean(axis=0)) < 0.3 * bound)  # nearly unbiased here


def test_noise_free_bearings_give_the_truth_and_the_crb_is_the_inverse_fisher():
    t, po, x0 = scenario()
    h, _, _ = bearing_model(x0, t, po)
    est = ml_bearings_only(h, t, po, np.deg2rad(1.0))
    np.testing.assert_allclose(est.x0, x0, rtol=1e-6, atol=1e-6)
    assert est.converged
    np.testing.assert_allclose(est.covariance @ fisher_information(x0, t, po, np.deg2rad(1.0)), np.eye(4), atol=1e-6)
    x, P = est.state_at(t[[0, -1]])
    np.testing.assert_allclose(x[0], x0, rtol=1e-6)
    assert P.shape == (2, 4, 4)


def test_no_maneuver_is_unobservable():
    t = np.arange(0.0, 1800.0, 60.0)
    po = np.column_stack([np.zeros_like(t), 2.5 * t])
    x0 = np.array([4000.0, 5000.0, -1.0, 0.5])
    h, _, _ = bearing_model(x0, t, po)
    assert "unobservable" in check_observability(t, po)
    with pytest.raises(InputError, match="has not maneuvered.*unobservable") as e:
        ml_bearings_only(h, t, po, 0.01)
    assert "\n" not in str(e.value)


def test_unsorted_times_are_refused():
    t, po, x0 = scenario()
    h, _, _ = bearing_model(x0, t, po)
    t2 = t.copy()
    t2[[3, 4]] = t2[[4, 3]]
    with pytest.raises(InputError, match="increase strictly"):
        ml_bearings_only(h, t2, po, 0.01)


def test_crb_position_sd_by_hand():
    """A stationary target at the origin seen from (0, -R) and (-R, 0) at t = 0 and again at t = T: the bearings
    from (0, -R) carry only x (H = [1, 0, tau, 0] / R), those from (-R, 0) only y (H = [0, -1, 0, -tau] / R), so
    each axis has J = [[2, T], [T, T^2]] / (sigma R)^2, J^-1 = (sigma R)^2 [[1, -1 / T], [-1 / T, 2 / T^2]] and
    var(x0 + tau vx) = (sigma R)^2 (1 - 2 tau / T + 2 tau^2 / T^2): sigma R per axis at 0 and T, sigma R / sqrt(2)
    at T / 2; the position sd sqrt(2) sigma R and sigma R."""
    from sonartrack.tma.batch_ml import crb_position_sd_m

    R, T, sigma = 1000.0, 100.0, 0.01
    tau = np.array([0.0, 0.0, T, T])
    own = np.array([[0.0, -R], [-R, 0.0], [0.0, -R], [-R, 0.0]])
    x0 = np.zeros(4)
    assert crb_position_sd_m(x0, tau, own, sigma, 0.0) == pytest.approx(np.sqrt(2.0) * sigma * R, rel=1e-9)
    assert crb_position_sd_m(x0, tau, own, sigma, T) == pytest.approx(np.sqrt(2.0) * sigma * R, rel=1e-9)
    assert crb_position_sd_m(x0, tau, own, sigma, T / 2) == pytest.approx(sigma * R, rel=1e-9)
    # per-bearing noise: doubling every sigma doubles the bound
    assert crb_position_sd_m(x0, tau, own, np.full(4, 2 * sigma), T) == pytest.approx(2 * np.sqrt(2) * sigma * R)
    # the bearings at t = 0 alone say nothing about the velocity: no bound
    assert np.isnan(crb_position_sd_m(x0, tau[:2], own[:2], sigma, T))


def test_crb_position_sd_is_nan_for_an_ownship_that_never_turns():
    """Nardone, Lindgren and Gong (IEEE TAC 29(9), 1984): a constant-velocity target seen from an ownship on one
    straight leg is unobservable, so the Fisher information is singular in exact arithmetic; in floating point it
    is ~1e17-conditioned and its inverse gave ~1e10 m, a "bound" any error passes. It must be NaN, and a turn must
    give a finite bound."""
    from sonartrack.tma.batch_ml import crb_position_sd_m

    t = np.arange(0.0, 1800.0, 60.0)
    x0 = np.array([6000.0, 8000.0, -3.0, 1.0])
    sigma = np.deg2rad(1.0)
    for course_deg in (0.0, 38.7, 90.0, 141.3, 200.0):  # off-axis courses gave ~1e9 m, on-axis ones a negative variance
        c = np.deg2rad(course_deg)
        leg = np.column_stack([1000.0 + 2.5 * np.sin(c) * t, 30.0 + 2.5 * np.cos(c) * t])
        assert np.isnan(crb_position_sd_m(x0, t, leg, sigma, t[-1])), course_deg
    own_straight = np.column_stack([np.zeros_like(t), 2.5 * t])
    turned = np.where(t[:, None] < 900.0, own_straight,
                      own_straight[t == 900.0][0] + np.column_stack([2.5 * (t - 900.0), np.zeros_like(t)]))
    sd = crb_position_sd_m(x0, t, turned, sigma, t[-1])
    assert np.isfinite(sd) and 1.0 < sd < 5000.0


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_fisher_information_of_ar1_errors_is_h_r_inverse_h(rho):
    """With AR(1) errors, R_ij = sigma_i sigma_j rho^|i - j|, the information is H^T R^-1 H (R inverted by numpy, not
    whitened); rho = 0 gives the white sum, and a larger rho less information about the position."""
    t, po, x0 = scenario()
    sigma = np.deg2rad(np.linspace(0.5, 1.5, len(t)))
    _, H, _ = bearing_model(x0, t, po)
    lag = np.abs(np.subtract.outer(np.arange(len(t)), np.arange(len(t))))
    R = np.outer(sigma, sigma) * rho**lag
    np.testing.assert_allclose(fisher_information(x0, t, po, sigma, rho), H.T @ np.linalg.solve(R, H), rtol=1e-9)
    if rho > 0:
        assert np.trace(crb(x0, t, po, sigma, rho)[:2, :2]) > np.trace(crb(x0, t, po, sigma)[:2, :2])
