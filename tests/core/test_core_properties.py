"""core/: angle wrapping, Gaussian densities, random streams (property and hand-worked tests)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.core.gaussian import gaussian_logpdf, inv_and_logdet, logsumexp, mahalanobis_sq
from sonartrack.core.random import trial_rng


@settings(max_examples=500, deadline=None)
@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_wrap_lands_in_half_open_interval_and_is_idempotent(a):
    w = wrap_angle(a)
    assert -np.pi < w <= np.pi
    assert wrap_angle(w) == w
    assert abs(np.sin(w) - np.sin(a)) < 1e-6 and abs(np.cos(w) - np.cos(a)) < 1e-6


def test_wrap_boundaries():
    assert wrap_angle(np.pi) == np.pi
    assert wrap_angle(-np.pi) == np.pi
    assert wrap_angle(3 * np.pi) == np.pi
    np.testing.assert_allclose(wrap_angle(np.array([0.0, 2 * np.pi, -0.5])), [0.0, 0.0, -0.5], atol=1e-15)


def test_bearing_is_clockwise_from_north():
    assert bearing_rad(0.0, 1.0) == 0.0
    assert bearing_rad(1.0, 0.0) == pytest.approx(np.pi / 2)
    assert bearing_rad(0.0, -1.0) == pytest.approx(np.pi)
    assert bearing_rad(-1.0, 0.0) == pytest.approx(-np.pi / 2)


def test_gaussian_logpdf_equals_scipy():
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(0)
    for m in (1, 2, 3):
        A = rng.normal(size=(m, m))
        S = A @ A.T + m * np.eye(m)
        nu = rng.normal(size=(10, m))
        np.testing.assert_allclose(gaussian_logpdf(nu, S), multivariate_normal(np.zeros(m), S).logpdf(nu), rtol=1e-12)


def test_two_by_two_closed_form_matches_numpy():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(50, 2, 2))
    S = A @ np.swapaxes(A, -1, -2) + np.eye(2)
    inv, logdet = inv_and_logdet(S)
    np.testing.assert_allclose(inv, np.linalg.inv(S), rtol=1e-10)
    np.testing.assert_allclose(logdet, np.linalg.slogdet(S)[1], rtol=1e-12)
    nu = rng.normal(size=(50, 2))
    np.testing.assert_allclose(mahalanobis_sq(nu, inv), np.einsum("ni,nij,nj->n", nu, np.linalg.inv(S), nu))


def test_singular_covariance_is_refused():
    with pytest.raises(np.linalg.LinAlgError):
        inv_and_logdet(np.zeros((2, 2)))


def test_logsumexp_handles_extremes():
    assert logsumexp(np.array([-1e4, -1e4])) == pytest.approx(-1e4 + np.log(2))
    assert logsumexp(np.array([-np.inf, -np.inf])) == -np.inf


def test_trial_streams_are_the_spawned_children():
    children = np.random.SeedSequence(42).spawn(5)
    for i, ss in enumerate(children):
        a = np.random.Generator(np.random.PCG64(ss)).random(3)
        np.testing.assert_array_equal(a, trial_rng(42, i).random(3))
