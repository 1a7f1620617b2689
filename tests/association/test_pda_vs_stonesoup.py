"""PDA weights and update against Stone Soup's PDAHypothesiser + PDA + PDAUpdater on identical inputs.

Stone Soup orders the CV state [x, vx, y, vy]; ours is [x, y, vx, vy]: the test permutes.
With a given clutter density Stone Soup's weights are miss 1 - Pd Pg and detection Pd N(nu; 0, S) / lambda
for measurements inside the chi-square gate: the same parametric PDA as association/pda.py.
"""

import datetime

import numpy as np
import pytest

from sonartrack.association.gating import gate_threshold
from sonartrack.association.pda import pda_update
from sonartrack.filters.kalman import kf_predict
from sonartrack.models.motion import cv_process_noise, cv_transition

stonesoup = pytest.importorskip("stonesoup")

PERM = [0, 2, 1, 3]  # ours [x, y, vx, vy] -> theirs [x, vx, y, vy]


def stone_soup_pda(x0, P0, q, dt, z, R, pd, pg, rho):
    from stonesoup.dataassociator.probability import PDA
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.types.detection import Detection
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track
    from stonesoup.updater.kalman import KalmanUpdater
    from stonesoup.updater.probability import PDAUpdater

    t0 = datetime.datetime(2020, 1, 1)
    t1 = t0 + datetime.timedelta(seconds=dt)
    trans = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
    meas = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=R)
    track = Track([GaussianState(x0[PERM].reshape(-1, 1), P0[np.ix_(PERM, PERM)], timestamp=t0)])
    dets = {Detection(zz.reshape(-1, 1), timestamp=t1, measurement_model=meas) for zz in z}
    hyp = PDAHypothesiser(KalmanPredictor(trans), KalmanUpdater(meas), clutter_spatial_density=rho,
                          prob_detect=pd, prob_gate=pg)
    hypotheses = PDA(hyp).associate({track}, dets, t1)[track]
    weights = {}
    miss = None
    for h in hypotheses:
        p = float(h.probability)
        if not h:
            miss = p
        else:
            weights[tuple(np.asarray(h.measurement.state_vector, float).ravel())] = p
    post = PDAUpdater(meas).update(hypotheses)
    x = np.asarray(post.state_vector, float).ravel()
    P = np.asarray(post.covar, float)
    inv = np.argsort(PERM)
    return miss, weights, x[inv], P[np.ix_(inv, inv)]


@pytest.mark.parametrize("seed", range(6))
def test_pda_equals_stone_soup(seed):
    rng = np.random.default_rng(seed)
    x0 = np.array([100.0, -50.0, 3.0, 1.0]) + rng.normal(0, 5, 4)
    A = rng.normal(size=(4, 4))
    P0 = A @ A.T + np.diag([400.0, 400.0, 4.0, 4.0])
    q, dt, pd, pg = 0.5, 2.0, 0.85, 0.99
    x_pred, P_pred = kf_predict(x0, P0, cv_transition(dt), cv_process_noise(dt, q))
    R = np.array([[90.0, 20.0], [20.0, 60.0]])
    S = P_pred[:2, :2] + R
    # ~40 measurements: some near the prediction (inside the gate), the rest clutter
    near = x_pred[:2] + rng.multivariate_normal(np.zeros(2), S, 6)
    far = x_pred[:2] + rng.uniform(-150, 150, (34, 2))
    z = np.vstack([near, far])
    rho = 2e-4
    miss, weights, x_ss, P_ss = stone_soup_pda(x0, P0, q, dt, z, R, pd, pg, rho)
    x, P, beta0, beta = pda_update(x_pred, P_pred, z, R, pd=pd, pg=pg, gamma=gate_threshold(pg), clutter_density=rho)
    assert beta0 == pytest.approx(miss, rel=1e-9)
    ours = {tuple(zz): b for zz, b in zip(z, beta, strict=True) if b > 0}
    assert ours.keys() == weights.keys()  # the same measurements validated
    for k, b in ours.items():
        assert b == pytest.approx(weights[k], rel=1e-9)
    np.testing.assert_allclose(x, x_ss, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(P, P_ss, rtol=1e-8, atol=1e-8)


def test_no_measurement_in_gate_keeps_the_prediction():
    x = np.array([0.0, 0.0, 1.0, 1.0])
    P = np.eye(4) * 10
    xu, Pu, b0, b = pda_update(x, P, np.array([[1e4, 1e4]]), np.eye(2), pd=0.9, pg=0.99, gamma=9.21,
                               clutter_density=1e-3)
    assert b0 == 1.0 and b.sum() == 0
    np.testing.assert_array_equal(xu, x)
    np.testing.assert_allclose(Pu, P)
