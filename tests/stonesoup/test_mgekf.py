"""Paper P2 in Stone Soup: the bearing + frequency model, the MGEKF updater and the IMM-MGEKF built from them.

Stone Soup's own ExtendedKalmanUpdater with our model equals our filters/ekf.py (1e-12); our MGEKFUpdater equals
filters/mgekf.py (1e-12); the Stone Soup IMM-EKF / IMM-MGEKF (stonesoup/imm.py + these) equals
tma/imm_mgekf.py's reference step over a whole manoeuvring record (1e-9)."""

import datetime

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")

from stonesoup.functions import jacobian as numerical_jacobian  # noqa: E402
from stonesoup.models.measurement.linear import LinearGaussian  # noqa: E402
from stonesoup.predictor.kalman import KalmanPredictor  # noqa: E402
from stonesoup.types.angle import Bearing  # noqa: E402
from stonesoup.types.detection import Detection  # noqa: E402
from stonesoup.types.hypothesis import SingleHypothesis  # noqa: E402
from stonesoup.types.prediction import GaussianStatePrediction  # noqa: E402
from stonesoup.types.state import GaussianState, State  # noqa: E402
from stonesoup.updater.kalman import ExtendedKalmanUpdater  # noqa: E402

from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.filters.ekf import ekf_update  # noqa: E402
from sonartrack.filters.mgekf import mgekf_update_bf  # noqa: E402
from sonartrack.models.passive import bf_jacobian, bf_measurement  # noqa: E402
from sonartrack.models.relative_motion import observer_inputs, relative_process_noise, relative_transition  # noqa: E402
from sonartrack.sim.platforms import ManeuveringTrack  # noqa: E402
from sonartrack.stonesoup.imm import IMMPredictor, IMMState, IMMUpdater  # noqa: E402
from sonartrack.stonesoup.mgekf import MGEKFUpdater  # noqa: E402
from sonartrack.stonesoup.models import BearingFrequency, RelativeConstantVelocity, observer_control_model  # noqa: E402
from sonartrack.tma.imm_mgekf import imm_bf_step_reference, transition_matrix  # noqa: E402
from sonartrack.tma.sequential_bf import initial_estimate  # noqa: E402

SB, SF = np.deg2rad(1.0), 0.1
R2 = np.diag([SB**2, SF**2])
T0 = datetime.datetime(2026, 1, 1)


def rel_diff(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


def random_case(rng, m):
    """A predicted relative state and covariance (TMA-like scales) and a noisy measurement of m entries."""
    r, b = rng.uniform(3000, 20000), rng.uniform(-np.pi, np.pi)
    x = np.array([r * np.sin(b), r * np.cos(b), *rng.normal(0, 5, 2), 300.0])
    A = rng.normal(size=(5, 5))
    d = np.sqrt([1e6, 1e6, 4.0, 4.0, 0.5])
    P = d[:, None] * (A @ A.T / 5 + 0.05 * np.eye(5)) * d[None, :]
    z = bf_measurement(x)[:m] + np.array([rng.normal(0, 0.05), rng.normal(0, 0.5)])[:m]
    return x, P, z


def stonesoup_pair(x, P, z, model):
    prediction = GaussianStatePrediction(x.reshape(-1, 1), P, timestamp=T0)
    return prediction, Detection(z.reshape(-1, 1), timestamp=T0, measurement_model=model)


def test_model_function_jacobian_and_noise():
    model = BearingFrequency(R2, seed=3)
    x = np.array([4000.0, 9000.0, -3.0, 1.0, 310.0])
    h = model.function(State(x.reshape(-1, 1)))
    assert isinstance(h[0, 0], Bearing)
    np.testing.assert_allclose(np.asarray(h, float)[:, 0], bf_measurement(x), rtol=1e-15)  # Bearing re-wraps: 1 ulp
    np.testing.assert_array_equal(model.jacobian(State(x.reshape(-1, 1))), bf_jacobian(x))
    num = numerical_jacobian(lambda s, **kw: np.asarray(model.function(s), float), State(x.reshape(-1, 1)))
    np.testing.assert_allclose(model.jacobian(State(x.reshape(-1, 1))), num, rtol=1e-5, atol=1e-9)
    samples = np.asarray(model.rvs(4000), dtype=float)
    C = np.cov(samples)
    np.testing.assert_allclose(np.diag(C), np.diag(R2), rtol=0.1)
    assert abs(C[0, 1]) / np.sqrt(C[0, 0] * C[1, 1]) < 0.1
    assert BearingFrequency(R2[:1, :1]).ndim_meas == 1
    with pytest.raises(InputError, match="noise_covar"):
        BearingFrequency(np.eye(3))


def test_logpdf_wraps_the_bearing():
    model = BearingFrequency(R2)
    x = np.array([-1.0, -5000.0, 0.0, 0.0, 300.0])  # bearing just below +pi / above -pi
    b = float(bf_measurement(x)[0])
    near = State(np.array([[-b], [300.0]]))  # the other side of the +-pi cut, 2 pi - 2|b| ~ 4e-4 rad away
    far = State(np.array([[b + 0.5], [300.0]]))
    assert model.logpdf(near, State(x.reshape(-1, 1))) > model.logpdf(far, State(x.reshape(-1, 1))) + 100


@pytest.mark.parametrize("m", [1, 2])
def test_stonesoup_ekf_with_our_model_equals_filters_ekf(m):
    rng = np.random.default_rng(m)
    model = BearingFrequency(R2[:m, :m])
    for joseph in (True, False):
        updater = ExtendedKalmanUpdater(model, use_joseph_cov=joseph)
        worst = 0.0
        for _ in range(20):
            x, P, z = random_case(rng, m)
            post = updater.update(SingleHypothesis(*stonesoup_pair(x, P, z, model)))
            xe, Pe, *_ = ekf_update(x, P, z, bf_measurement(x)[:m], bf_jacobian(x)[:m], R2[:m, :m])
            worst = max(worst, rel_diff(post.state_vector[:, 0], xe), rel_diff(post.covar, Pe))
        assert worst < 1e-12  # measured: 4e-16 (Joseph), 2e-15 (P - K S K^T)


@pytest.mark.parametrize(("m", "exact"), [(1, False), (2, False), (2, True)])
def test_mgekf_updater_equals_filters_mgekf(m, exact):
    rng = np.random.default_rng(10 + m)
    model = BearingFrequency(R2[:m, :m])
    updater = MGEKFUpdater(model, exact=exact)
    ekf = ExtendedKalmanUpdater(model, use_joseph_cov=True)
    for _ in range(20):
        x, P, z = random_case(rng, m)
        post = updater.update(SingleHypothesis(*stonesoup_pair(x, P, z, model)))
        xm, Pm, *_ = mgekf_update_bf(x, P, z, bf_measurement(x)[:m], bf_jacobian(x)[:m], R2[:m, :m], exact=exact)
        assert rel_diff(post.state_vector[:, 0], xm) < 1e-12 and rel_diff(post.covar, Pm) < 1e-12
        e = ekf.update(SingleHypothesis(*stonesoup_pair(x, P, z, model)))
        assert rel_diff(post.state_vector, e.state_vector) < 1e-12  # same gain, same state update
        assert rel_diff(post.covar, e.covar) > 1e-6  # but the modified covariance


def test_mgekf_innovation_is_wrapped_across_the_cut():
    model = BearingFrequency(R2)
    x = np.array([-50.0, -8000.0, 1.0, 2.0, 300.0])  # predicted bearing ~ -179.6 deg
    P = np.diag([4e6, 4e6, 4.0, 4.0, 0.5])
    z = np.array([np.pi - 0.001, 300.1])  # measured ~ +179.9 deg: 0.5 deg away, not 359.5
    post = MGEKFUpdater(model).update(SingleHypothesis(*stonesoup_pair(x, P, z, model)))
    xm, Pm, nu, *_ = mgekf_update_bf(x, P, z, bf_measurement(x), bf_jacobian(x), R2)
    assert abs(nu[0]) < 0.01
    assert rel_diff(post.state_vector[:, 0], xm) < 1e-12 and rel_diff(post.covar, Pm) < 1e-12


def test_mgekf_refuses_a_model_without_modified_jacobian():
    mm = LinearGaussian(5, (0, 1), np.eye(2))
    pred, det = stonesoup_pair(np.array([1.0, 2, 0, 0, 300]), np.eye(5), np.array([1.0, 2.0]), mm)
    with pytest.raises(InputError, match="modified_jacobian"):
        MGEKFUpdater(mm).update(SingleHypothesis(pred, det))


def test_relative_motion_model_matches_sonartrack():
    model = RelativeConstantVelocity(noise_diff_coeff=0.02, f0_noise_diff_coeff=1e-6)
    dt = datetime.timedelta(seconds=4)
    np.testing.assert_array_equal(model.matrix(time_interval=dt), relative_transition(4.0))
    np.testing.assert_array_equal(model.covar(time_interval=dt), relative_process_noise(4.0, 0.02, 1e-6))
    assert model.ndim_state == 5


def record(n=150, dt=4.0, seed=9):
    """Paper P2-like record: observer 5 kn with a leg change, target ~10 km at 10 kn turning mid-run."""
    t = np.arange(n) * dt
    obs = ManeuveringTrack(0.0, 0.0, 2.5, np.deg2rad(45), ((200.0, 240.0, np.deg2rad(-2.25)),))
    tgt = ManeuveringTrack(-3000.0, 9500.0, 5.0, np.deg2rad(100), ((330.0, 390.0, np.deg2rad(1.0)),))
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    rel = np.column_stack([pt - po, vt - vo, np.full(n, 300.0)])
    z = bf_measurement(rel) + np.random.default_rng(seed).normal(0, 1, (n, 2)) * [SB, SF]
    x0, P0 = initial_estimate(z[0, 0], z[0, 1], vo[0], range_m=7000.0, sigma_range_m=4000.0, sigma_bearing_rad=SB,
                              sigma_f0_hz=1.0)
    return t, z, observer_inputs(t, po, vo), x0, P0


@pytest.mark.parametrize("modified", [True, False])
def test_stonesoup_imm_mgekf_equals_tma_reference_over_a_record(modified):
    qs, q_f0 = np.array([1e-4, 1e-2, 0.3]), 1e-8
    Pi = transition_matrix(3, 0.95)
    t, z, u, x0, P0 = record()
    model = BearingFrequency(R2)
    predictor = IMMPredictor(
        predictors=[KalmanPredictor(RelativeConstantVelocity(noise_diff_coeff=q, f0_noise_diff_coeff=q_f0),
                                    control_model=observer_control_model()) for q in qs],
        transition_probabilities=Pi)
    updater = IMMUpdater(updater=MGEKFUpdater(model) if modified else ExtendedKalmanUpdater(model, use_joseph_cov=True))
    x, P, mu = np.repeat(x0[None], 3, 0), np.repeat(P0[None], 3, 0), np.full(3, 1 / 3)
    state = IMMState.from_modes(x, P, mu, timestamp=T0)
    worst = 0.0
    for k in range(1, len(t)):
        time = T0 + datetime.timedelta(seconds=t[k])
        pred = predictor.predict(state, timestamp=time, control_input=State(u[k - 1].reshape(-1, 1)))
        state = updater.update(SingleHypothesis(pred, Detection(z[k].reshape(-1, 1), timestamp=time,
                                                                measurement_model=model)))
        x, P, mu, xc, Pc, _ = imm_bf_step_reference(x, P, mu, z[k], u[k - 1], t[k] - t[k - 1], qs, Pi, R2,
                                                    modified=modified, q_f0=q_f0)
        worst = max(worst, rel_diff(state.mode_means, x), rel_diff(state.mode_covars, P),
                    rel_diff(state.mode_probabilities, mu), rel_diff(state.state_vector[:, 0], xc),
                    rel_diff(state.covar, Pc))
    assert worst < 1e-9
    assert np.max(mu) > 0.5  # a real run: the modes separated


def test_one_mode_mgekf_is_the_plain_stonesoup_filter():
    """IMM with one mode around MGEKFUpdater == MGEKFUpdater with Stone Soup's KalmanPredictor (exactly)."""
    t, z, u, x0, P0 = record(n=40)
    model = BearingFrequency(R2)
    kp = KalmanPredictor(RelativeConstantVelocity(noise_diff_coeff=1e-3), control_model=observer_control_model())
    mg = MGEKFUpdater(model)
    ip, iu = IMMPredictor(predictors=[kp], transition_probabilities=[[1.0]]), IMMUpdater(updater=mg)
    s = GaussianState(x0.reshape(-1, 1), P0, timestamp=T0)
    si = IMMState(s.state_vector, s.covar, timestamp=T0)
    for k in range(1, len(t)):
        time = T0 + datetime.timedelta(seconds=t[k])
        det = Detection(z[k].reshape(-1, 1), timestamp=time, measurement_model=model)
        ctrl = State(u[k - 1].reshape(-1, 1))
        s = mg.update(SingleHypothesis(kp.predict(s, timestamp=time, control_input=ctrl), det))
        si = iu.update(SingleHypothesis(ip.predict(si, timestamp=time, control_input=ctrl), det))
    assert rel_diff(si.state_vector, s.state_vector) < 1e-12 and rel_diff(si.covar, s.covar) < 1e-12
