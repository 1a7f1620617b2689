"""Bistatic geometry (models/bistatic.py): exact inverse, Jacobian, and J Sigma J^T vs Monte Carlo."""

import numpy as np
import pytest

from sonartrack.models.bistatic import (
    BistaticErrors,
    bistatic_covariance,
    bistatic_inputs,
    bistatic_jacobian,
    bistatic_position,
)


def random_geometry(rng):
    rx = rng.uniform(-1000, 1000, 2)
    tx = rx + rng.uniform(-400, 400, 2)
    rng_m = rng.uniform(2000, 25000)
    bearing = rng.uniform(-np.pi, np.pi)
    target = rx + rng_m * np.array([np.sin(bearing), np.cos(bearing)])
    phi = rng.uniform(-np.pi, np.pi)
    c = rng.uniform(1480, 1520)
    return target, tx, rx, phi, c


def test_noise_free_inputs_return_the_true_position():
    rng = np.random.default_rng(0)
    for _ in range(500):
        target, tx, rx, phi, c = random_geometry(rng)
        t, theta = bistatic_inputs(target, tx, rx, phi, c)
        pos, rr = bistatic_position(t, theta, phi, c, tx, rx)
        np.testing.assert_allclose(pos, target, atol=1e-6)
        assert rr == pytest.approx(np.linalg.norm(target - rx), rel=1e-10)


def test_monostatic_limit_is_half_the_path():
    # Tx at Rx: r_R = r_B / 2 = c t / 2, straight along the bearing
    pos, rr = bistatic_position(10.0, 0.3, 0.2, 1500.0, np.zeros(2), np.zeros(2))
    assert rr == pytest.approx(7500.0)
    np.testing.assert_allclose(pos, 7500.0 * np.array([np.sin(0.5), np.cos(0.5)]))


def test_jacobian_equals_finite_differences():
    rng = np.random.default_rng(1)
    for _ in range(20):
        target, tx, rx, phi, c = random_geometry(rng)
        t, theta = bistatic_inputs(target, tx, rx, phi, c)
        p = np.r_[t, theta, phi, c, tx, rx]

        def f(p):
            return bistatic_position(p[0], p[1], p[2], p[3], p[4:6], p[6:8])[0]

        steps = np.array([1e-6, 1e-7, 1e-7, 1e-4, 1e-3, 1e-3, 1e-3, 1e-3])
        num = np.stack([(f(p + np.eye(8)[k] * h) - f(p - np.eye(8)[k] * h)) / (2 * h) for k, h in enumerate(steps)], -1)
        J = bistatic_jacobian(t, theta, phi, c, tx, rx)
        np.testing.assert_allclose(J, num, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("geometry", range(4))
def test_covariance_agrees_with_monte_carlo(geometry):
    """J Sigma J^T vs the sample covariance of the nonlinear map of 40000 noisy inputs.

    Each entry must agree within 5 standard errors of the sample covariance (Gaussian approximation
    var(S_ij) = (C_ij^2 + C_ii C_jj) / n); the linearisation error at these ranges is far smaller.
    """
    rng = np.random.default_rng(100 + geometry)
    target, tx, rx, phi, c = random_geometry(rng)
    t, theta = bistatic_inputs(target, tx, rx, phi, c)
    err = BistaticErrors(sigma_heading_rad=np.deg2rad(0.2))
    sd = np.sqrt(err.variances())
    n = 40000
    noise = rng.normal(size=(n, 8)) * sd
    p = np.r_[t, theta, phi, c, tx, rx] + noise
    pts, _ = bistatic_position(p[:, 0], p[:, 1], p[:, 2], p[:, 3], p[:, 4:6], p[:, 6:8])
    sample = np.cov(pts.T)
    C = bistatic_covariance(t, theta, phi, c, tx, rx, err.variances())
    se = np.sqrt((C**2 + np.outer(np.diag(C), np.diag(C))) / n)
    assert np.all(np.abs(sample - C) < 5 * se), (sample, C)
    # and the nonlinear bias is small against the spread (the study measures it at its geometry)
    bias = pts.mean(axis=0) - target
    assert np.linalg.norm(bias) < 0.2 * np.sqrt(np.trace(C))


def test_covariance_grows_with_bearing_error():
    rng = np.random.default_rng(3)
    target, tx, rx, phi, c = random_geometry(rng)
    t, theta = bistatic_inputs(target, tx, rx, phi, c)
    small = bistatic_covariance(t, theta, phi, c, tx, rx, BistaticErrors().variances(np.deg2rad(0.5)))
    big = bistatic_covariance(t, theta, phi, c, tx, rx, BistaticErrors().variances(np.deg2rad(1.5)))
    diff = big - small  # only the bearing term grows: positive semi-definite, rank one
    assert np.linalg.eigvalsh(diff).min() > -1e-9 * np.trace(big)
    assert np.trace(big) > np.trace(small)
