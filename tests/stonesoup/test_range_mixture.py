"""The range-parameterised mixture (stonesoup/range_mixture.py) against hand-worked cases of Peach's equations, and
its angle geometry against Stone Soup's own measurement models (an independent implementation)."""

import math

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")

from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing, CartesianToElevationBearing  # noqa: E402
from stonesoup.types.state import State  # noqa: E402

from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.stonesoup.range_mixture import (  # noqa: E402
    angles_and_jacobian,
    collapse,
    component_positions,
    filters_for_cv,
    mixture_update,
    range_cv,
    range_subintervals,
)


def test_subintervals_double_each_time_from_100_to_800_m():
    """rho = (800/100)^(1/3) = 2: subintervals [100, 200], [200, 400], [400, 800] m (worked by hand)."""
    r, sd, w = range_subintervals(100.0, 800.0, 3)
    np.testing.assert_allclose(r, [150.0, 300.0, 600.0])
    np.testing.assert_allclose(sd, np.array([100.0, 200.0, 400.0]) / math.sqrt(12.0))
    np.testing.assert_allclose(w, [1 / 3, 1 / 3, 1 / 3])
    np.testing.assert_allclose(sd / r, 2 * (2 - 1) / (math.sqrt(12) * (2 + 1)))  # C_R, the same for each filter
    _, _, w_uniform = range_subintervals(100.0, 800.0, 3, prior="uniform")
    np.testing.assert_allclose(w_uniform, [1 / 7, 2 / 7, 4 / 7])  # proportional to the widths 100, 200, 400


def test_number_of_filters_for_a_coefficient_of_variation():
    """rho = 2 gives C_R = 1 / (3 sqrt(3)) = 0.19245; [100, 800] m needs 3 such filters, 4 for any smaller C_R."""
    cv_rho2 = 1.0 / (3.0 * math.sqrt(3.0))
    assert filters_for_cv(100.0, 800.0, cv_rho2) == 3
    assert filters_for_cv(100.0, 800.0, cv_rho2 * 0.99) == 4
    assert filters_for_cv(100.0, 150.0, 0.5) == 1


@pytest.mark.parametrize("bad", [dict(r_min_m=0.0), dict(r_max_m=50.0), dict(n_filters=0), dict(prior="flat")])
def test_bad_range_settings_are_input_errors(bad):
    args = dict(r_min_m=100.0, r_max_m=800.0, n_filters=3) | bad
    with pytest.raises(InputError):
        range_subintervals(**args)
    with pytest.raises(InputError, match="range_cv"):
        filters_for_cv(100.0, 800.0, 0.6)


def test_components_lie_on_the_bearing_with_range_and_cross_range_variances():
    """2-D, no rotation: p_i = o + r_i (cos phi, sin phi); variance sd_i^2 along the bearing, r_i^2 var_phi across."""
    offset, phi, var_phi = np.array([10.0, -5.0]), math.radians(30.0), 1e-4
    mean, covar = component_positions(np.array([phi]), np.array([var_phi]), np.array([150.0, 600.0]),
                                      np.array([20.0, 80.0]), offset, np.eye(3))
    along, across = np.array([math.cos(phi), math.sin(phi)]), np.array([-math.sin(phi), math.cos(phi)])
    np.testing.assert_allclose(mean, offset + np.outer([150.0, 600.0], along))
    np.testing.assert_allclose(covar @ along, np.outer([20.0**2, 80.0**2], along), atol=1e-12)
    np.testing.assert_allclose(covar @ across, np.outer([150.0**2 * var_phi, 600.0**2 * var_phi], across), atol=1e-12)


def _stonesoup_models():
    yaw = np.array([[0.0], [0.0], [0.7]])
    tilted = np.array([[0.1], [-0.2], [2.5]])
    return [Cartesian2DToBearing(ndim_state=4, mapping=(0, 2), noise_covar=np.array([[1e-4]]),
                                 translation_offset=np.array([[30.0], [-40.0]]), rotation_offset=yaw),
            CartesianToElevationBearing(ndim_state=6, mapping=(0, 2, 4), noise_covar=np.diag([4e-4, 1e-4]),
                                        translation_offset=np.array([[30.0], [-40.0], [-15.0]]),
                                        rotation_offset=tilted)]


@pytest.mark.parametrize("model", _stonesoup_models(), ids=["bearing-2d", "elevation-bearing-3d"])
def test_geometry_agrees_with_stonesoup_models(model):
    """Components built from a measurement give that measurement back through Stone Soup's own model function,
    at the intended range; our analytic Jacobian equals Stone Soup's numerical one."""
    d = len(model.mapping)
    offset = np.asarray(model.translation_offset, float).ravel()
    z = np.array([0.3, -2.0]) if d == 3 else np.array([-2.0])  # [theta, phi] or [phi], rad
    ranges = np.array([80.0, 900.0])
    mean, _ = component_positions(z, np.ones(d - 1) * 1e-4, ranges, ranges / 10, offset, model.rotation_matrix)
    h, jac = angles_and_jacobian(mean, offset, model.rotation_matrix)
    for p, r, h_i, jac_i in zip(mean, ranges, h, jac, strict=True):
        x = np.zeros(model.ndim_state)
        x[list(model.mapping)] = p
        state = State(x.reshape(-1, 1))
        np.testing.assert_allclose(np.asarray(model.function(state), float).ravel(), z, atol=1e-12)
        np.testing.assert_allclose(h_i, z, atol=1e-12)
        assert np.linalg.norm(p - offset) == pytest.approx(r)
        ss_jac = np.asarray(model.jacobian(state), float)[:, list(model.mapping)]
        np.testing.assert_allclose(jac_i, ss_jac, rtol=1e-4, atol=1e-9)  # theirs: forward differences


def test_collapse_moment_matches_two_components():
    """1-D: means 0 and 2, variances 1; weights 1/4, 3/4: mean 1.5, variance 1 + 1/4 * 1.5^2 + 3/4 * 0.5^2 = 1.75."""
    mean, covar = collapse(np.array([[0.0], [2.0]]), np.ones((2, 1, 1)), np.log([0.25, 0.75]))
    assert mean[0] == pytest.approx(1.5)
    assert covar[0, 0] == pytest.approx(1.75)
    mean, covar = collapse(np.array([[0.0], [2.0]]), np.ones((2, 1, 1)), np.log([3.0, 3.0]))  # unnormalised
    assert (mean[0], covar[0, 0]) == pytest.approx((1.0, 2.0))


def test_weights_follow_the_measurement_likelihoods():
    """Equal S = H P H^T + R = 2, innovations 0 and -2: w1 / w2 = exp(-(0 - 4) / (2 * 2)) = e (from equal weights);
    the predictive density is 1/2 N(0; 0, 2) + 1/2 N(0; 2, 2)."""
    x, P = np.array([[0.0], [2.0]]), np.ones((2, 1, 1))
    H = np.ones((2, 1, 1))
    x_new, P_new, log_w, log_lik, d2 = mixture_update(x, P, np.log([0.5, 0.5]), np.array([0.0]), x, H,
                                                      np.eye(1))
    assert math.exp(log_w[0] - log_w[1]) == pytest.approx(math.e)
    assert np.exp(log_w).sum() == pytest.approx(1.0)
    density = 0.5 * (1 + math.exp(-1.0)) / math.sqrt(2 * math.pi * 2)
    assert log_lik == pytest.approx(math.log(density))
    np.testing.assert_allclose(d2, [0.0, 2.0])
    np.testing.assert_allclose(x_new.ravel(), [0.0, 1.0])  # K = 1/2 pulls each mean half way to z = 0
    np.testing.assert_allclose(P_new.ravel(), [0.5, 0.5])


def test_range_cv_is_the_sd_along_the_line_of_sight_over_the_range():
    """At (3, 4) m from the sensor with covariance diag(4, 1): l = (0.6, 0.8), sd^2 = 0.36 * 4 + 0.64 * 1 = 2.08."""
    r, cv = range_cv(np.array([13.0, 4.0]), np.diag([4.0, 1.0]), np.array([10.0, 0.0]))
    assert r == pytest.approx(5.0)
    assert cv == pytest.approx(math.sqrt(2.08) / 5.0)
