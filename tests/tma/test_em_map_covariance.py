"""EM/MAP covariance (tma/em_map.py module doc): the inverse observed information plus the level's consider term is
consistent by Monte Carlo NEES when the level SL + DI - NL of the SNR model is off by b ~ N(0, sigma_level^2) (the
inverse information alone is not); for a small sigma_level the term is the linear consider covariance
sigma_level^2 s s^T, s = P d2L/dX0 db, here from finite differences of L."""

import numpy as np
import pytest

from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.batch_ml import bearing_model
from sonartrack.tma.em_map import (
    level_covariance,
    level_shifted,
    make_problem,
    objective,
    observed_information,
    solve_em_map,
)

KN = 1852.0 / 3600.0
SIGMA_BEARING_RAD = np.deg2rad(1.0)


def snr_smooth_db(r_m):
    """Spherical spreading + 0.01 dB/km absorption with a 100 dB level."""
    return 100.0 - 20.0 * np.log10(r_m) - 1e-5 * r_m


def scenario(n_frames=40):
    """A straight ownship (the bearings alone do not give the range) and a target 6 km off at 160 deg."""
    t = np.arange(n_frames) * (800.0 / n_frames)
    po, _, _ = ManeuveringTrack(0.0, 0.0, 5 * KN, np.deg2rad(90.0), ()).state(t)
    b = np.deg2rad(160.0)
    x0 = np.array([6000 * np.sin(b), 6000 * np.cos(b), -4 * KN, 1 * KN])
    h, _, r = bearing_model(x0, t, po)
    return t, po, x0, h, r


def last_position_nees(t, x0, x0_hat, cov):
    F = np.array([[1.0, 0.0, t[-1], 0.0], [0.0, 1.0, 0.0, t[-1]]])
    e = F @ (x0_hat - x0)
    return float(e @ np.linalg.solve(F @ cov @ F.T, e))


def test_monte_carlo_nees_with_an_unknown_level():
    """80 runs, level error b ~ N(0, 1 dB) per run, SNR noise 1 dB: the mean NEES of the last position is
    chi-square(2)'s 2 (sd of the mean ~0.25) with the level carried (measured 1.9); the inverse information alone
    is ~10x overconfident (measured mean NEES 22: the covariance before the level was carried)."""
    t, po, x0, h, r = scenario()
    rng = np.random.default_rng(2026)
    nees, nees_info_only = [], []
    for _ in range(80):
        level_error_db = rng.normal(0.0, 1.0)
        z = h + rng.normal(0.0, SIGMA_BEARING_RAD, len(t))
        xi = snr_smooth_db(r) + level_error_db + rng.normal(0.0, 1.0, len(t))
        prob = make_problem(z, xi, t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0, sigma_level_db=1.0)
        est = solve_em_map(prob)
        nees.append(last_position_nees(t, x0, est.x0, est.covariance))
        nees_info_only.append(last_position_nees(t, x0, est.x0, np.linalg.inv(observed_information(prob, est.x0))))
    assert 1.4 < np.mean(nees) < 2.8
    assert np.mean(nees_info_only) > 8.0


def test_monte_carlo_nees_with_an_exact_level():
    """sigma_level = 0 and no level error: the inverse observed information is consistent (mean NEES ~ 2)."""
    t, po, x0, h, r = scenario()
    rng = np.random.default_rng(7)
    nees = []
    for _ in range(80):
        z = h + rng.normal(0.0, SIGMA_BEARING_RAD, len(t))
        xi = snr_smooth_db(r) + rng.normal(0.0, 1.0, len(t))
        prob = make_problem(z, xi, t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0, sigma_level_db=0.0)
        est = solve_em_map(prob)
        np.testing.assert_array_equal(est.covariance, np.linalg.inv(observed_information(prob, est.x0)))
        nees.append(last_position_nees(t, x0, est.x0, est.covariance))
    assert 1.4 < np.mean(nees) < 2.8


def test_level_shifted_is_the_problem_of_the_raised_model():
    t, po, x0, h, r = scenario()
    xi = snr_smooth_db(r) + 0.4
    xi[3] = np.nan
    prob = make_problem(h, xi, t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0)
    raised = make_problem(h, xi, t, po, SIGMA_BEARING_RAD, 1.0, lambda r_m: snr_smooth_db(r_m) + 0.7, 500.0, 30_000.0)
    np.testing.assert_allclose(level_shifted(prob, 0.7).log_snr_lik, raised.log_snr_lik, rtol=0, atol=1e-12)


def test_small_level_sd_gives_the_linear_consider_covariance():
    """Smooth TL, sigma_level = 0.05 dB: the sigma-point term equals sigma_level^2 s s^T with s = P C,
    P = (-d2L/dX0^2)^-1 and C = d2L/dX0 db from central differences of L over X0 and the level."""
    t, po, x0, h, r = scenario()
    rng = np.random.default_rng(4)
    z, xi = h + rng.normal(0.0, SIGMA_BEARING_RAD, len(t)), snr_smooth_db(r) + rng.normal(0.0, 1.0, len(t))
    sigma_level = 0.05
    prob = make_problem(z, xi, t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0,
                        sigma_level_db=sigma_level)
    x = solve_em_map(prob, covariance=False).x0
    P = np.linalg.inv(observed_information(prob, x))
    db, h_x = 1e-2, np.array([6.0, 6.0, 1e-3, 1e-3])
    up, down = level_shifted(prob, db), level_shifted(prob, -db)
    C = np.empty(4)
    for i in range(4):
        e = np.eye(4)[i] * h_x[i]
        C[i] = (objective(up, x + e) - objective(up, x - e) - objective(down, x + e) + objective(down, x - e)) / (
            4 * h_x[i] * db)
    s = P @ C
    np.testing.assert_allclose(level_covariance(prob, x), sigma_level**2 * np.outer(s, s), rtol=0.03,
                               atol=0.03 * sigma_level**2 * np.abs(np.outer(s, s)).max())


def test_no_level_sd_or_no_snr_adds_nothing():
    t, po, x0, h, r = scenario()
    exact = make_problem(h, snr_smooth_db(r), t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0,
                         sigma_level_db=0.0)
    no_snr = make_problem(h, None, t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0)
    assert not level_covariance(exact, x0).any()
    assert not level_covariance(no_snr, x0).any()


@pytest.mark.parametrize("sigma_level", [-0.1])
def test_negative_level_sd_is_refused(sigma_level):
    t, po, x0, h, r = scenario()
    with pytest.raises(Exception, match="sigma_level"):
        make_problem(h, snr_smooth_db(r), t, po, SIGMA_BEARING_RAD, 1.0, snr_smooth_db, 500.0, 30_000.0,
                     sigma_level_db=sigma_level)
