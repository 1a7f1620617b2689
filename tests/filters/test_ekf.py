"""EKF steps against FilterPy's ExtendedKalmanFilter on identical inputs."""

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from sonartrack.core.linalg import is_spd
from sonartrack.filters.ekf import ekf_predict, ekf_update, gaussian_loglik
from sonartrack.models.passive import bf_jacobian, bf_measurement, bf_residual
from sonartrack.models.relative_motion import relative_process_noise, relative_transition
from sonartrack.tma.imm_mgekf import ImmBfModel, imm_bf_step, imm_bf_step_reference, transition_matrix

SB, SF = np.deg2rad(1.0), 0.1


def random_case(rng):
    A = rng.normal(size=(5, 5))
    d = np.sqrt([3e5, 3e5, 1.0, 1.0, 0.05])  # scales of position, velocity, f0 uncertainty
    P = d[:, None] * (A @ A.T / 5 + 0.2 * np.eye(5)) * d[None, :]
    r, b = rng.uniform(3000, 20000), rng.uniform(-np.pi, np.pi)
    x = np.array([r * np.sin(b), r * np.cos(b), *rng.normal(0, 5, 2), rng.uniform(100, 1000)])
    u = np.r_[rng.normal(0, 2, 2), rng.normal(0, 0.3, 2), 0.0]
    return x, P, u


def filterpy_step(x, P, z, u, dt, q, q_f0, R):
    m = len(z)
    ekf = ExtendedKalmanFilter(dim_x=5, dim_z=m, dim_u=5)
    ekf.x, ekf.P = x.copy(), P.copy()
    ekf.F = relative_transition(dt)
    ekf.Q = relative_process_noise(dt, q, q_f0)
    ekf.B = -np.eye(5)
    ekf.predict(u=u)
    ekf.update(z, HJacobian=lambda s: bf_jacobian(s)[:m], Hx=lambda s: bf_measurement(s)[:m], R=R,
               residual=bf_residual)
    return ekf.x, ekf.P, ekf.y, ekf.S


@pytest.mark.parametrize("with_freq", [True, False])
def test_ekf_step_equals_filterpy(with_freq):
    rng = np.random.default_rng(11)
    for _ in range(25):
        x, P, u = random_case(rng)
        dt, q, q_f0 = rng.uniform(0.5, 10), 10 ** rng.uniform(-6, -1), 1e-6
        z_true = bf_measurement(x + rng.normal(0, [300, 300, 1, 1, 0.1]))
        z = z_true if with_freq else z_true[:1]
        R = np.diag([SB**2, SF**2])[: len(z), : len(z)]
        F, Q = relative_transition(dt), relative_process_noise(dt, q, q_f0)
        xp, Pp = ekf_predict(x, P, F, Q, b=-u)
        m = len(z)
        xu, Pu, nu, S, S_inv = ekf_update(xp, Pp, z, bf_measurement(xp)[:m], bf_jacobian(xp)[:m], R)
        fx, fP, fy, fS = filterpy_step(x, P, z, u, dt, q, q_f0, R)
        np.testing.assert_allclose(xu, fx, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(Pu, fP, rtol=1e-8, atol=1e-10 * np.abs(fP).max())
        np.testing.assert_allclose(nu, fy, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(S, fS, rtol=1e-10)
        assert is_spd(Pu)
        # the one-mode IMM (NumPy reference and numba kernel) is the same EKF step
        Pi = transition_matrix(1, 1.0)
        ref = imm_bf_step_reference(x[None], P[None], np.ones(1), z, u, dt, [q], Pi, R, modified=False, q_f0=q_f0)
        np.testing.assert_allclose(ref[3], fx, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(ref[4], fP, rtol=1e-8, atol=1e-10 * np.abs(fP).max())
        fast = imm_bf_step(x[None], P[None], np.ones(1), z, u, dt, ImmBfModel([q], Pi, SB, SF, q_f0=q_f0,
                                                                             modified=False))
        np.testing.assert_allclose(fast[3], fx, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(fast[4], fP, rtol=1e-8, atol=1e-10 * np.abs(fP).max())


def test_gaussian_loglik_hand_case():
    nu = np.array([0.01, -0.2])
    S = np.diag([1e-4, 0.04])
    expected = -0.5 * (2 * np.log(2 * np.pi) + np.log(1e-4 * 0.04) + 1.0 + 1.0)
    assert gaussian_loglik(nu, S, np.linalg.inv(S)) == pytest.approx(expected)


def test_update_does_not_mutate_inputs():
    rng = np.random.default_rng(2)
    x, P, u = random_case(rng)
    x0, P0 = x.copy(), P.copy()
    z = bf_measurement(x)
    ekf_update(x, P, z + 0.01, bf_measurement(x), bf_jacobian(x), np.diag([SB**2, SF**2]))
    assert np.array_equal(x, x0) and np.array_equal(P, P0)
