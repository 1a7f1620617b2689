"""IMM-EKF / IMM-MGEKF: numba kernel vs the NumPy reference, IMM identities, noise-free tracking."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.filters.imm_ekf import imm_bf_step, imm_bf_step_reference, run_imm_bf, transition_matrix
from sonartrack.models.passive import bf_measurement
from sonartrack.models.relative_motion import observer_inputs
from sonartrack.sim.platforms import ManeuveringTrack
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
    fast = imm_bf_step(x, P, mu, z, u, dt, qs, Pi, SB**2, SF**2, modified=modified, q_f0=1e-6)
    for a, b in zip(ref, fast):
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
    kw = dict(qs=[1e-5, 1e-3, 1e-1], Pi=transition_matrix(3, 0.98), sigma_bearing_rad=SB, sigma_freq_hz=SF,
              modified=True, q_f0=1e-8)
    a = run_imm_bf(t, z[:, 0], zf, u, x0, P0, engine="numba", **kw)
    b = run_imm_bf(t, z[:, 0], zf, u, x0, P0, engine="reference", **kw)
    assert a[3] == b[3] == -1
    for p, q in zip(a[:3], b[:3]):
        np.testing.assert_allclose(p, q, rtol=1e-7, atol=1e-7 * np.abs(q).max())
    np.testing.assert_allclose(a[2].sum(axis=1), 1.0)


def test_imm_with_identical_modes_is_the_single_filter():
    t, po, vo, rel = scenario(T=8.0, duration=800.0)
    rng = np.random.default_rng(2)
    z = bf_measurement(rel) + rng.normal(0, 1, (len(t), 2)) * [SB, SF]
    x0, P0 = initial_estimate(z[0, 0], z[0, 1], vo[0], range_m=8000.0, sigma_range_m=3000.0, sigma_bearing_rad=SB,
                              sigma_f0_hz=1.0)
    u = observer_inputs(t, po, vo)
    single = run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, qs=[1e-3], sigma_bearing_rad=SB, sigma_freq_hz=SF)
    imm = run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, qs=[1e-3] * 3, Pi=transition_matrix(3, 0.9),
                     sigma_bearing_rad=SB, sigma_freq_hz=SF)
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
    x, P, mu, failed = run_imm_bf(t, z[:, 0], z[:, 1] if with_freq else None, u, x0, P0, qs=qs,
                                  Pi=transition_matrix(len(qs), 0.99), sigma_bearing_rad=SB, sigma_freq_hz=SF,
                                  modified=method != "ekf", q_f0=0.0)
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
                                  qs=[1e-3], sigma_bearing_rad=0.01, engine=engine)
    assert failed == 1
    assert np.all(np.isfinite(x[0])) and np.all(np.isnan(x[1:]))
