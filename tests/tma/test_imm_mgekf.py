"""IMM-EKF / IMM-MGEKF: numba kernel (whole and step by step) vs the NumPy reference, IMM identities,
noise-free tracking."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.filters.ekf import ekf_predict, ekf_update, gaussian_loglik
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update
from sonartrack.filters.mgekf import mgekf_update
from sonartrack.models.passive import bf_jacobian, bf_measurement, modified_matrix
from sonartrack.models.relative_motion import observer_inputs, relative_process_noise, relative_transition
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma import imm_mgekf_kernel as kern
from sonartrack.tma.imm_mgekf import ImmBfModel, imm_bf_step, imm_bf_step_reference, run_imm_bf, transition_matrix
from sonartrack.tma.sequential_bf import initial_estimate

SB, SF = np.deg2rad(1.0), 0.1


def mode_states(rng, r):
    base_r, b = rng.uniform(3000, 20000), rng.uniform(-np.pi, np.pi)
    base = np.array([base_r * np.sin(b), base_r * np.cos(b), *rng.normal(0, 4, 2), 300.0])
    x = base + rng.normal(0, 1, (r, 5)) * [200, 200, 0.5, 0.5, 0.05]
    P = np.empty((r, 5, 5))
    d = np.sqrt([2e5, 2e5, 1.0, 1.0, 0.02])
    for j in range(r):
        A = rng.normal(size=(5, 5))
        P[j] = d[:, None] * (A @ A.T / 5 + 0.1 * np.eye(5)) * d[None, :]
    return x, P, base


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 4), st.booleans(), st.booleans())
def test_kernel_equals_numpy_reference(seed, r, with_freq, modified):
    rng = np.random.default_rng(seed)
    x, P, base = mode_states(rng, r)
    mu = rng.dirichlet(np.ones(r))
    Pi = transition_matrix(r, 0.95)
    qs = 10 ** rng.uniform(-6, -1, r)
    z = bf_measurement(base) + rng.normal(0, 1, 2) * [3 * SB, 3 * SF]
    z = z if with_freq else z[:1]
    u = np.r_[rng.normal(0, 1, 4), 0.0]
    dt = rng.uniform(0.5, 8.0)
    R = np.diag([SB**2, SF**2])[: len(z), : len(z)]
    ref = imm_bf_step_reference(x, P, mu, z, u, dt, qs, Pi, R, modified=modified, q_f0=1e-6)
    fast = imm_bf_step(x, P, mu, z, u, dt, ImmBfModel(qs, Pi, SB, SF, q_f0=1e-6, modified=modified))
    for a, b in zip(ref, fast, strict=True):
        a, b = np.asarray(a), np.asarray(b)
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(a).max()))
    assert fast[2].sum() == pytest.approx(1.0) and np.all(fast[2] >= 0)


def scenario(T=4.0, duration=1600.0, target_turn=None):
    t = np.arange(0.0, duration + 1e-9, T)
    obs = ManeuveringTrack(0.0, 0.0, 2.57, np.deg2rad(45), ((500.0, 540.0, np.deg2rad(-2.25)),
                                                            (1100.0, 1140.0, np.deg2rad(2.25))))
    turns = () if target_turn is None else ((target_turn, target_turn + 60.0, np.deg2rad(-1.5)),)
    tgt = ManeuveringTrack(-3000.0, 9500.0, 5.14, np.deg2rad(100), turns)
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    rel = np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)])
    return t, po, vo, rel


def test_record_kernel_equals_reference_with_missing_frequencies():
    t, po, vo, rel = scenario(T=8.0, duration=800.0)
    rng = np.random.default_rng(1)
    z = bf_measurement(rel) + rng.normal(0, 1, (len(t), 2)) * [SB, SF]
    zf = z[:, 1].copy()
    zf[::7] = np.nan  # no frequency at those times: bearing-only updates
    x0, P0 = initial_estimate(z[0, 0], z[0, 1], vo[0], range_m=8000.0, sigma_range_m=3000.0, sigma_bearing_rad=SB,
                              sigma_f0_hz=1.0)
    u = observer_inputs(t, po, vo)
    model = ImmBfModel([1e-5, 1e-3, 1e-1], transition_matrix(3, 0.98), SB, SF, q_f0=1e-8, modified=True)
    a = run_imm_bf(t, z[:, 0], zf, u, x0, P0, model, engine="numba")
    b = run_imm_bf(t, z[:, 0], zf, u, x0, P0, model, engine="reference")
    assert a[3] == b[3] == -1
    for p, q in zip(a[:3], b[:3], strict=True):
        np.testing.assert_allclose(p, q, rtol=1e-7, atol=1e-7 * np.abs(q).max())
    np.testing.assert_allclose(a[2].sum(axis=1), 1.0)


def test_imm_with_identical_modes_is_the_single_filter():
    t, po, vo, rel = scenario(T=8.0, duration=800.0)
    rng = np.random.default_rng(2)
    z = bf_measurement(rel) + rng.normal(0, 1, (len(t), 2)) * [SB, SF]
    x0, P0 = initial_estimate(z[0, 0], z[0, 1], vo[0], range_m=8000.0, sigma_range_m=3000.0, sigma_bearing_rad=SB,
                              sigma_f0_hz=1.0)
    u = observer_inputs(t, po, vo)
    single = run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, ImmBfModel([1e-3], None, SB, SF))
    imm = run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, ImmBfModel([1e-3] * 3, transition_matrix(3, 0.9), SB, SF))
    np.testing.assert_allclose(imm[0], single[0], rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(imm[1], single[1], rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(imm[2], 1.0 / 3.0, rtol=1e-9)


@pytest.mark.parametrize("method", ["ekf", "mgekf", "imm-mgekf"])
@pytest.mark.parametrize("with_freq", [True, False])
def test_noise_free_constant_velocity_target_is_tracked_to_the_truth(method, with_freq):
    """Exact bearings (and frequencies) of a CV target seen from a zig-zagging observer: the estimate
    converges to the truth from a 3 km range error and a zero-velocity prior."""
    t, po, vo, rel = scenario(T=4.0, duration=1600.0)
    z = bf_measurement(rel)
    x0, P0 = initial_estimate(z[0, 0], z[0, 1] if with_freq else None, vo[0], range_m=7000.0, sigma_range_m=4000.0,
                              sigma_bearing_rad=SB, sigma_f0_hz=2.0)
    u = observer_inputs(t, po, vo)
    qs = [1e-8, 1e-6, 1e-4] if method.startswith("imm") else [1e-8]
    model = ImmBfModel(qs, transition_matrix(len(qs), 0.99), SB, SF, q_f0=0.0, modified=method != "ekf")
    x, P, mu, failed = run_imm_bf(t, z[:, 0], z[:, 1] if with_freq else None, u, x0, P0, model)
    assert failed == -1
    assert np.hypot(*(x0[:2] - rel[0, :2])) > 2500
    pos_err = np.hypot(*(x[-1, :2] - rel[-1, :2]))
    vel_err = np.hypot(*(x[-1, 2:4] - rel[-1, 2:4]))
    assert pos_err < 0.005 * np.hypot(*rel[-1, :2])  # < ~40 m at 8 km
    assert vel_err < 0.05
    if with_freq:
        assert abs(x[-1, 4] - 300.0) < 0.01


@pytest.mark.parametrize("engine", ["numba", "reference"])
def test_numerical_failure_is_reported_not_raised(engine):
    """An estimate sitting on the observer (r = 0) cannot be updated: the step is flagged, rows NaN."""
    t = np.arange(6.0)
    x, P, mu, failed = run_imm_bf(t, np.zeros(6), None, np.zeros((5, 5)), np.array([0.0, 0, 0, 0, 300]), np.eye(5),
                                  ImmBfModel([1e-3], None, 0.01), engine=engine)
    assert failed == 1
    assert np.all(np.isfinite(x[0])) and np.all(np.isnan(x[1:]))


# ---- the kernel's named steps, each against the NumPy function of the same equation ----------------------
def one_mode_case(seed, with_freq=True):
    rng = np.random.default_rng(seed)
    x, P, base = mode_states(rng, 3)
    z = bf_measurement(base) + rng.normal(0, 1, 2) * [3 * SB, 3 * SF]
    return rng, x, P, (z if with_freq else z[:1])


@pytest.mark.parametrize("seed", range(5))
def test_mix_step_equals_imm_mix(seed):
    rng, x, P, _ = one_mode_case(seed)
    mu, Pi = rng.dirichlet(np.ones(3)), transition_matrix(3, 0.9)
    c_ref, w = imm_mixing(mu, Pi)
    x0_ref, P0_ref = imm_mix(x, P, w)
    c, wk, x0, P0 = np.zeros(3), np.zeros(3), np.zeros((3, 5)), np.zeros((3, 5, 5))
    kern.mix(x, P, mu, Pi, c, wk, x0, P0)
    np.testing.assert_allclose(c, c_ref, rtol=1e-13)
    np.testing.assert_allclose(x0, x0_ref, rtol=1e-12)
    np.testing.assert_allclose(P0, P0_ref, rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_predict_innovation_gain_update_steps_equal_the_ekf(seed):
    rng, x, P, z = one_mode_case(seed)
    u, dt, q, q_f0 = np.r_[rng.normal(0, 1, 4), 0.0], rng.uniform(0.5, 8.0), 1e-3, 1e-6
    xp_ref, Pp_ref = ekf_predict(x[0], P[0], relative_transition(dt), relative_process_noise(dt, q, q_f0), b=-u)
    xp, Pp = np.zeros(5), np.zeros((5, 5))
    kern.predict(x, P, 0, u, dt, q, q_f0, xp, Pp)
    np.testing.assert_allclose(xp, xp_ref, rtol=1e-13)
    np.testing.assert_allclose(Pp, Pp_ref, rtol=1e-12, atol=1e-9)
    H, nu = np.zeros((2, 5)), np.zeros(2)
    kern.innovation(xp, z, True, 1500.0, H, nu)
    np.testing.assert_allclose(H, bf_jacobian(xp), rtol=1e-12, atol=1e-15)
    R = np.diag([SB**2, SF**2])
    x_ref, P_ref, nu_ref, S, S_inv = ekf_update(xp, Pp, z, bf_measurement(xp), bf_jacobian(xp), R)
    np.testing.assert_allclose(nu, nu_ref, rtol=1e-10, atol=1e-12)
    PHt, K, x_new = np.zeros((5, 2)), np.zeros((5, 2)), np.zeros((1, 5))
    ll = kern.gain(Pp, H, nu, 2, SB**2, SF**2, PHt, K)
    assert ll == pytest.approx(gaussian_loglik(nu_ref, S, S_inv), rel=1e-10)
    kern.update_mean(xp, K, nu, 2, x_new, 0)
    np.testing.assert_allclose(x_new[0], x_ref, rtol=1e-12)
    for modified in (False, True):
        G, A, AP, P_new = np.zeros((2, 5)), np.zeros((5, 5)), np.zeros((5, 5)), np.zeros((1, 5, 5))
        kern.covariance_rows(xp, z[0], H, 2, modified, G)
        kern.joseph_covariance(Pp, K, G, 2, np.array([SB**2, SF**2]), A, AP, P_new, 0)
        G_ref = modified_matrix(z, xp, bf_jacobian(xp)) if modified else bf_jacobian(xp)
        _, P_ref, *_ = mgekf_update(xp, Pp, z, bf_measurement(xp), bf_jacobian(xp), G_ref, R)
        np.testing.assert_allclose(G, G_ref, rtol=1e-12)
        np.testing.assert_allclose(P_new[0], P_ref, rtol=1e-9, atol=1e-9)


def test_gain_reports_a_singular_innovation_covariance():
    H, nu, PHt, K = np.zeros((2, 5)), np.zeros(2), np.zeros((5, 2)), np.zeros((5, 2))
    assert np.isnan(kern.gain(np.zeros((5, 5)), H, nu, 1, 0.0, 0.0, PHt, K))  # S = 0
    assert np.isnan(kern.gain(np.zeros((5, 5)), H, nu, 2, 1.0, 0.0, PHt, K))  # det S = 0


def test_mode_probabilities_and_combine_steps():
    c = np.array([0.2, 0.5, 0.3])
    log_lik = np.array([-1000.0, -1001.0, -990.0])  # would underflow outside log space
    mu, total = np.zeros(3), None
    total = kern.mode_probabilities(c, log_lik, mu)
    mu_ref, total_ref = imm_mode_update(c, log_lik)
    np.testing.assert_allclose(mu, mu_ref, rtol=1e-12)
    assert total == pytest.approx(float(total_ref), rel=1e-14)
    # hand case: equal likelihoods leave the predicted probabilities unchanged
    kern.mode_probabilities(c, np.zeros(3), mu)
    np.testing.assert_allclose(mu, c, rtol=1e-14)
    rng = np.random.default_rng(3)
    x, P, _ = mode_states(rng, 3)
    xc, Pc = np.zeros(5), np.zeros((5, 5))
    kern.combine(mu, x, P, xc, Pc)
    xc_ref, Pc_ref = imm_combine(mu, x, P)
    np.testing.assert_allclose(xc, xc_ref, rtol=1e-13)
    np.testing.assert_allclose(Pc, Pc_ref, rtol=1e-10, atol=1e-9)


def test_a_nan_frequency_is_a_bearing_only_update():
    rng = np.random.default_rng(4)
    x, P, base = mode_states(rng, 2)
    mu, model = np.array([0.5, 0.5]), ImmBfModel([1e-4, 1e-2], transition_matrix(2, 0.95), SB, SF)
    zb = bf_measurement(base)[:1]
    a = imm_bf_step(x, P, mu, np.array([zb[0], np.nan]), np.zeros(5), 2.0, model)
    b = imm_bf_step(x, P, mu, zb, np.zeros(5), 2.0, model)
    for p, q in zip(a, b, strict=True):
        np.testing.assert_array_equal(p, q)


def test_model_refuses_bad_input():
    from sonartrack.core.errors import InputError

    with pytest.raises(InputError, match="Markov matrix must be 2 x 2"):
        ImmBfModel([1e-3, 1e-2], transition_matrix(3, 0.9), SB)
    with pytest.raises(InputError, match="non-negative"):
        ImmBfModel([-1e-3], None, SB)
    with pytest.raises(InputError, match="positive"):
        ImmBfModel([1e-3], None, 0.0)
