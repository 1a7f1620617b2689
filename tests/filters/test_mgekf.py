"""MGEKF update: same state update as the EKF, covariance with the modified matrix, stays SPD."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.core.linalg import is_spd
from sonartrack.filters.ekf import ekf_update
from sonartrack.filters.mgekf import mgekf_update, mgekf_update_bf
from sonartrack.models.passive import bearing_modified_row, bf_jacobian, bf_measurement, modified_matrix
from sonartrack.models.relative_motion import observer_inputs
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.imm_mgekf import ImmBfModel, run_imm_bf
from sonartrack.tma.sequential_bf import initial_estimate

SB, SF = np.deg2rad(1.0), 0.1
R2 = np.diag([SB**2, SF**2])


def spd_matrix(rng):
    A = rng.normal(size=(5, 5))
    d = np.sqrt([1e6, 1e6, 4.0, 4.0, 0.5])
    return d[:, None] * (A @ A.T / 5 + 0.05 * np.eye(5)) * d[None, :]


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**31), st.floats(2000, 25000), st.floats(-np.pi, np.pi), st.floats(-0.3, 0.3),
       st.booleans())
def test_mgekf_covariance_symmetric_positive_definite(seed, r, b, dz, with_freq):
    rng = np.random.default_rng(seed)
    P = spd_matrix(rng)
    x = np.array([r * np.sin(b), r * np.cos(b), *rng.normal(0, 5, 2), 300.0])
    m = 2 if with_freq else 1
    z = bf_measurement(x)[:m] + np.r_[dz, rng.normal(0, 0.5)][:m]
    H = bf_jacobian(x)[:m]
    xu, Pu, nu, S, _ = mgekf_update_bf(x, P, z, bf_measurement(x)[:m], H, R2[:m, :m])
    assert is_spd(Pu)
    np.testing.assert_array_equal(Pu, Pu.T)
    # the state update is the EKF's (same gain); only P differs
    xe, Pe, *_ = ekf_update(x, P, z, bf_measurement(x)[:m], H, R2[:m, :m])
    np.testing.assert_allclose(xu, xe, rtol=1e-12, atol=1e-9)


def test_mgekf_covariance_hand_formula():
    """P+ = (I - K G) P- (I - K G)^T + K R K^T with K the EKF gain and G = [g; H_f]."""
    rng = np.random.default_rng(4)
    P = spd_matrix(rng)
    x = np.array([4000.0, 9000.0, -3.0, 1.0, 310.0])
    z = bf_measurement(x) + np.array([0.05, 0.3])
    H = bf_jacobian(x)
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R2)
    g = np.array([np.cos(z[0]), -np.sin(z[0]), 0, 0, 0]) / (x[0] * np.sin(z[0]) + x[1] * np.cos(z[0]))
    G = np.vstack([g, H[1]])
    A = np.eye(5) - K @ G
    expected = A @ P @ A.T + K @ R2 @ K.T
    _, Pu, *_ = mgekf_update(x, P, z, bf_measurement(x), H, G, R2)
    np.testing.assert_allclose(Pu, expected, rtol=1e-10, atol=1e-8)
    np.testing.assert_allclose(modified_matrix(z, x, H), G, rtol=1e-14)
    assert not np.allclose(G[0], H[0])  # the measurement is off the predicted bearing: g != H


def test_mgekf_equals_ekf_when_the_measurement_is_predicted_exactly():
    rng = np.random.default_rng(5)
    for _ in range(10):
        P = spd_matrix(rng)
        r, b = rng.uniform(3000, 20000), rng.uniform(-np.pi, np.pi)
        x = np.array([r * np.sin(b), r * np.cos(b), *rng.normal(0, 5, 2), 300.0])
        z = bf_measurement(x)
        H = bf_jacobian(x)
        np.testing.assert_allclose(bearing_modified_row(z[0], x), H[0], rtol=1e-12)
        a = mgekf_update_bf(x, P, z, z, H, R2)
        e = ekf_update(x, P, z, z, H, R2)
        np.testing.assert_allclose(a[1], e[1], rtol=1e-9, atol=1e-9)


def test_mgekf_covariance_stays_spd_over_a_noisy_run():
    """A whole noisy bearings + frequency run (reference NumPy engine): P SPD at every step."""
    t = np.arange(0.0, 1200.0, 4.0)
    obs = ManeuveringTrack(0.0, 0.0, 2.5, np.deg2rad(45), ((400.0, 440.0, np.deg2rad(-2.25)),))
    tgt = ManeuveringTrack(-3000.0, 9500.0, 5.0, np.deg2rad(100))
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    rel = np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)])
    rng = np.random.default_rng(9)
    z = bf_measurement(rel) + rng.normal(0, 1, (len(t), 2)) * [SB, SF]
    x0, P0 = initial_estimate(z[0, 0], z[0, 1], vo[0], range_m=7000.0, sigma_range_m=4000.0, sigma_bearing_rad=SB,
                              sigma_f0_hz=1.0)
    u = observer_inputs(t, po, vo)
    _, P, _, failed = run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, ImmBfModel([1e-4], None, SB, SF, q_f0=1e-8),
                                 engine="reference")
    assert failed == -1
    assert all(is_spd(Pk) for Pk in P)
