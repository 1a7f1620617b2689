"""Kalman and IMM steps against FilterPy on identical inputs (to 1e-9)."""

import numpy as np
import pytest

from sonartrack.filters.imm_kf import imm_kf_step
from sonartrack.filters.kalman import kf_predict, kf_update
from sonartrack.models.motion import H_POSITION, cv_process_noise, cv_transition

filterpy = pytest.importorskip("filterpy")


def random_spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


@pytest.mark.parametrize("seed", range(5))
def test_kalman_steps_equal_filterpy(seed):
    from filterpy.kalman import KalmanFilter

    rng = np.random.default_rng(seed)
    F, Q, H = cv_transition(3.0), cv_process_noise(3.0, 0.2), H_POSITION
    R = random_spd(rng, 2, 5.0)
    x, P = rng.normal(size=4) * 10, random_spd(rng, 4, 10.0)
    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.x, kf.P, kf.F, kf.Q, kf.H, kf.R = x.copy(), P.copy(), F, Q, H, R
    for _ in range(6):
        z = rng.normal(size=2) * 20
        x, P = kf_predict(x, P, F, Q)
        kf.predict()
        np.testing.assert_allclose(x, kf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P, kf.P, rtol=1e-9, atol=1e-9)
        x, P, nu, S = kf_update(x, P, z, H, R)
        kf.update(z)
        np.testing.assert_allclose(x, kf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P, kf.P, rtol=1e-9, atol=1e-9)  # FilterPy uses the Joseph form too
        np.testing.assert_allclose(nu, kf.y, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(S, kf.S, rtol=1e-9, atol=1e-9)


def test_inputs_are_not_mutated():
    rng = np.random.default_rng(0)
    x, P, R = rng.normal(size=4), random_spd(rng, 4), random_spd(rng, 2)
    x0, P0, R0 = x.copy(), P.copy(), R.copy()
    kf_update(*kf_predict(x, P, cv_transition(1.0), cv_process_noise(1.0, 1.0)), np.ones(2), H_POSITION, R)
    assert np.array_equal(x, x0) and np.array_equal(P, P0) and np.array_equal(R, R0)


@pytest.mark.parametrize("qs", [(0.01, 1.0), (1e-3, 0.1, 2.0)])
def test_imm_step_equals_filterpy_imm_estimator(qs):
    from filterpy.kalman import IMMEstimator, KalmanFilter

    rng = np.random.default_rng(len(qs))
    r = len(qs)
    F, H, R = cv_transition(2.0), H_POSITION, random_spd(rng, 2, 4.0)
    Q = np.stack([cv_process_noise(2.0, q) for q in qs])
    Pi = np.full((r, r), 0.05 / (r - 1))
    np.fill_diagonal(Pi, 0.95)
    mu = rng.dirichlet(np.ones(r))
    x = rng.normal(size=(r, 4)) * 5
    P = np.stack([random_spd(rng, 4, 5.0) for _ in range(r)])
    filters = []
    for j in range(r):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x, kf.P, kf.F, kf.Q, kf.H, kf.R = x[j].copy(), P[j].copy(), F, Q[j], H, R
        filters.append(kf)
    imm = IMMEstimator(filters, mu.copy(), Pi)
    for _ in range(8):
        z = rng.normal(size=2) * 10
        x, P, mu, xc, Pc = imm_kf_step(x, P, mu, z, F, Q, H, R, Pi)
        imm.predict()
        imm.update(z)
        np.testing.assert_allclose(mu, imm.mu, rtol=1e-9, atol=1e-12)
        for j in range(r):
            np.testing.assert_allclose(x[j], filters[j].x, rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(P[j], filters[j].P, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(xc, imm.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(Pc, imm.P, rtol=1e-9, atol=1e-9)
