"""The weighted bearings-only ML's sigma_u floor (systems/passive/targets.py :data:`SIGMA_U_FLOOR_RAD`, 0.02 deg):
a floor in u below the chain's measured 0.021-0.041 deg, so the stated covariance is the measured noise's."""

import sys
from pathlib import Path

import numpy as np
import pytest

from sonartrack.systems.passive.targets import SIGMA_U_FLOOR_RAD, line_array_relative_sigma, u_weighted_fit
from sonartrack.tma.sides import SIGMA_FLOOR_RAD, fit_cv_target

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import bearings, leg_turn_leg  # noqa: E402


def _record(sigma_u, seed):
    """A target 1.5 km off a leg-turn-leg ownship, 400 bearings a second apart, its cone angle from the ownship's
    north axis; noise white in u: sigma_theta_n = sigma_u / max(|sin theta_n|, 0.05)."""
    t = np.arange(0.0, 400.0, 1.0)
    own = leg_turn_leg(t)
    truth = bearings(t, own, (300.0, 1500.0), (1.0, -3.0), 0.0, seed)
    rel = line_array_relative_sigma(truth)
    return t, own, truth + sigma_u * rel * np.random.default_rng(seed).standard_normal(t.size), rel


@pytest.mark.parametrize("seed", range(3))
def test_sigma_u_below_the_side_decision_s_floor_is_measured_not_floored(seed):
    # sigma_u = 0.03 deg = 5.24e-4 rad, the chain's measured noise at broadside: J_w / (n - 4) gives it within 10 %
    # (396 degrees of freedom: sd 3.6 %); floored at the side decision's 0.1 deg it would be 1.745e-3, 3.3 times
    # larger, and the covariance 11 times
    sigma_u = float(np.deg2rad(0.03))
    t, own, z, rel = _record(sigma_u, seed)
    est, measured = u_weighted_fit(z, t, own, rel, fit_cv_target(z, t, own))
    assert measured == pytest.approx(sigma_u, rel=0.1)
    assert measured < 0.5 * SIGMA_FLOOR_RAD
    # the stated covariance is (H^T W H)^-1 at the measured sigma_u: its scale is the objective over n - 4
    np.testing.assert_allclose(est.covariance[0, 0] * (len(t) - 4) / est.objective,
                               est.covariance[0, 0] / measured**2, rtol=1e-9)


def test_a_noise_free_record_takes_the_floor():
    # J_w = 0 (the fit is the truth): sigma_u is the floor, 0.02 deg = 3.4907e-4 rad
    t, own, z, rel = _record(0.0, 0)
    _, measured = u_weighted_fit(z, t, own, rel, fit_cv_target(z, t, own))
    assert measured == pytest.approx(3.4907e-4, rel=1e-4) and measured == SIGMA_U_FLOOR_RAD
