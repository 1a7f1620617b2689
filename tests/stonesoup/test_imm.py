"""Gaussian IMM as Stone Soup components: one mode equals Stone Soup's Kalman filter (1e-12), several modes equal
sonartrack's filters/imm.py and FilterPy's IMMEstimator (1e-9), and the IMM drops into a Stone Soup tracker."""

import datetime

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")

from stonesoup.models.measurement.linear import LinearGaussian  # noqa: E402
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange  # noqa: E402
from stonesoup.models.transition.linear import (  # noqa: E402
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import ExtendedKalmanPredictor, KalmanPredictor  # noqa: E402
from stonesoup.types.detection import Detection  # noqa: E402
from stonesoup.types.hypothesis import SingleHypothesis  # noqa: E402
from stonesoup.types.state import GaussianState  # noqa: E402
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater, UnscentedKalmanUpdater  # noqa: E402

from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.filters.imm_kf import imm_kf_step  # noqa: E402
from sonartrack.stonesoup.imm import IMMPredictor, IMMState, IMMStateUpdate, IMMUpdater  # noqa: E402

T0 = datetime.datetime(2026, 1, 1)
DT = datetime.timedelta(seconds=2)


def cv(q):
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


def rel_diff(a, b) -> float:
    """max |a - b| relative to max(1, max |b|)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


class PerModePredictor(KalmanPredictor):
    """A KalmanPredictor the IMM cannot recognise: forces the per-mode (Stone Soup object) path."""


class PerModeUpdater(KalmanUpdater):
    """A KalmanUpdater the IMM cannot recognise: forces the per-mode path."""


def detections(n, seed, model):
    rng = np.random.default_rng(seed)
    return [Detection(np.array([[20.0 * k], [-10.0 * k]]) + rng.normal(0, 8, (2, 1)), timestamp=T0 + k * DT,
                      measurement_model=model) for k in range(1, n + 1)]


@pytest.mark.parametrize("joseph", [False, True])
def test_one_mode_equals_stonesoup_kalman_filter(joseph):
    mm = LinearGaussian(4, (0, 2), np.array([[40.0, 5.0], [5.0, 25.0]]))
    kp, ku = KalmanPredictor(cv(0.3)), KalmanUpdater(mm, use_joseph_cov=joseph)
    ip, iu = IMMPredictor(predictors=[kp], transition_probabilities=[[1.0]]), IMMUpdater(updater=ku)
    s = GaussianState([0.0, 9.0, 0.0, -4.0], np.diag([400.0, 25.0, 300.0, 16.0]), timestamp=T0)
    si = IMMState(s.state_vector, s.covar, timestamp=T0)
    for det in detections(12, 0, mm):
        p, pi = kp.predict(s, timestamp=det.timestamp), ip.predict(si, timestamp=det.timestamp)
        assert rel_diff(pi.state_vector, p.state_vector) < 1e-12 and rel_diff(pi.covar, p.covar) < 1e-12
        mp, mpi = ku.predict_measurement(p), iu.predict_measurement(pi)
        assert rel_diff(mpi.state_vector, mp.state_vector) < 1e-12 and rel_diff(mpi.covar, mp.covar) < 1e-12
        assert rel_diff(mpi.cross_covar, mp.cross_covar) < 1e-12
        s, si = ku.update(SingleHypothesis(p, det)), iu.update(SingleHypothesis(pi, det))
        assert isinstance(si, IMMStateUpdate) and si.mode_probabilities[0] == 1.0
        assert rel_diff(si.state_vector, s.state_vector) < 1e-12 and rel_diff(si.covar, s.covar) < 1e-12


@pytest.mark.parametrize("updater_cls", [ExtendedKalmanUpdater, UnscentedKalmanUpdater])
def test_one_mode_nonlinear_equals_the_stonesoup_updater(updater_cls):
    """The per-mode path (a nonlinear model; an EKF predictor) gives exactly the wrapped components' answer."""
    mm = CartesianToBearingRange(4, (0, 2), np.diag([1e-4, 25.0]))
    kp, ku = ExtendedKalmanPredictor(cv(0.3)), updater_cls(mm)
    ip, iu = IMMPredictor(predictors=[kp], transition_probabilities=[[1.0]]), IMMUpdater(updater=ku)
    s = GaussianState([500.0, 9.0, 800.0, -4.0], np.diag([400.0, 25.0, 300.0, 16.0]), timestamp=T0)
    si = IMMState(s.state_vector, s.covar, timestamp=T0)
    rng = np.random.default_rng(2)
    for k in range(1, 9):
        truth = GaussianState([500.0 + 18 * k, 9.0, 800.0 - 8 * k, -4.0], np.eye(4))
        det = Detection(mm.function(truth) + rng.normal(0, [[0.01], [5.0]]), timestamp=T0 + k * DT,
                        measurement_model=mm)
        p, pi = kp.predict(s, timestamp=det.timestamp), ip.predict(si, timestamp=det.timestamp)
        s, si = ku.update(SingleHypothesis(p, det)), iu.update(SingleHypothesis(pi, det))
        assert rel_diff(si.state_vector, s.state_vector) < 1e-12 and rel_diff(si.covar, s.covar) < 1e-12


def imm_pair(qs, Pi, predictor=KalmanPredictor, updater=KalmanUpdater, mm=None):
    mm = mm or LinearGaussian(4, (0, 2), np.array([[30.0, 4.0], [4.0, 20.0]]))
    return (IMMPredictor(predictors=[predictor(cv(q)) for q in qs], transition_probabilities=Pi),
            IMMUpdater(updater=updater(mm)), mm)


def markov(r, diagonal=0.95):
    Pi = np.full((r, r), (1 - diagonal) / (r - 1))
    np.fill_diagonal(Pi, diagonal)
    return Pi


@pytest.mark.parametrize("qs", [(0.01, 1.0), (1e-3, 0.1, 2.0)])
def test_modes_equal_sonartrack_imm_and_filterpy(qs):
    from filterpy.kalman import IMMEstimator, KalmanFilter

    r, rng = len(qs), np.random.default_rng(len(qs))
    Pi = markov(r)
    ip, iu, mm = imm_pair(qs, Pi)
    x = rng.normal(size=(r, 4)) * 5
    A = rng.normal(size=(r, 4, 4))
    P = A @ np.swapaxes(A, 1, 2) + 20 * np.eye(4)
    mu = rng.dirichlet(np.ones(r))
    F, H, R = cv(1.0).matrix(time_interval=DT), mm.matrix(), mm.covar()
    Q = np.stack([cv(q).covar(time_interval=DT) for q in qs])
    filters = []
    for j in range(r):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x, kf.P, kf.F, kf.Q, kf.H, kf.R = x[j].copy(), P[j].copy(), F, Q[j], H, R
        filters.append(kf)
    fp = IMMEstimator(filters, mu.copy(), Pi)
    state = IMMState.from_modes(x, P, mu, timestamp=T0)
    for det in detections(15, 3, mm):
        state = iu.update(SingleHypothesis(ip.predict(state, timestamp=det.timestamp), det))
        z = np.asarray(det.state_vector, float)[:, 0]
        x, P, mu, xc, Pc = imm_kf_step(x, P, mu, z, F, Q, H, R, Pi)
        fp.predict()
        fp.update(z)
        for ref_mu, ref_x, ref_P, ref_xc, ref_Pc in ((mu, x, P, xc, Pc),
                                                   (fp.mu, [f.x for f in filters], [f.P for f in filters], fp.x,
                                                    fp.P)):
            assert rel_diff(state.mode_probabilities, ref_mu) < 1e-9
            assert rel_diff(state.mode_means, ref_x) < 1e-9 and rel_diff(state.mode_covars, ref_P) < 1e-9
            assert rel_diff(state.state_vector[:, 0], ref_xc) < 1e-9 and rel_diff(state.covar, ref_Pc) < 1e-9


def test_array_path_equals_per_mode_path():
    qs, Pi = (0.02, 0.5, 3.0), markov(3, 0.9)
    fast_p, fast_u, mm = imm_pair(qs, Pi)
    slow_p, slow_u, _ = imm_pair(qs, Pi, PerModePredictor, PerModeUpdater, mm)
    rng = np.random.default_rng(7)
    a = b = IMMState.from_modes(rng.normal(size=(3, 4)), np.stack([np.eye(4) * 50] * 3), [0.2, 0.3, 0.5],
                                timestamp=T0)
    for det in detections(10, 7, mm):
        a = fast_u.update(SingleHypothesis(fast_p.predict(a, timestamp=det.timestamp), det))
        b = slow_u.update(SingleHypothesis(slow_p.predict(b, timestamp=det.timestamp), det))
        assert rel_diff(a.mode_means, b.mode_means) < 1e-12 and rel_diff(a.mode_covars, b.mode_covars) < 1e-12
        assert rel_diff(a.mode_probabilities, b.mode_probabilities) < 1e-12
        assert abs(a.log_likelihood - b.log_likelihood) < 1e-10


def test_measurement_prediction_is_the_moment_matched_mixture():
    ip, iu, mm = imm_pair((0.01, 2.0), markov(2))
    state = IMMState.from_modes([[0, 1, 0, 1], [30, -2, -10, 3.0]], np.stack([np.eye(4) * 40, np.eye(4) * 90]),
                                [0.4, 0.6], timestamp=T0)
    pred = ip.predict(state, timestamp=T0 + DT)
    mp = iu.predict_measurement(pred)
    H, R, c = mm.matrix(), mm.covar(), pred.mode_probabilities
    zj = pred.mode_means @ H.T
    z = c @ zj
    S = sum(cj * (H @ Pj @ H.T + R + np.outer(zjj - z, zjj - z)) for cj, Pj, zjj in zip(c, pred.mode_covars, zj,
                                                                                          strict=True))
    assert rel_diff(mp.state_vector[:, 0], z) < 1e-12 and rel_diff(mp.covar, S) < 1e-12
    assert not np.allclose(mp.covar, H @ pred.mode_covars[0] @ H.T + R)  # the spread of the modes counts


def test_plain_gaussian_prior_goes_to_every_mode_with_equal_probabilities():
    ip, _, _ = imm_pair((0.01, 2.0), markov(2))
    prior = GaussianState([0, 1, 0, 1.0], np.eye(4), timestamp=T0)
    pred = ip.predict(prior, timestamp=T0 + DT)
    np.testing.assert_allclose(pred.mode_probabilities, [0.5, 0.5])
    one = KalmanPredictor(cv(0.01)).predict(prior, timestamp=T0 + DT)
    assert rel_diff(pred.mode_means[0], one.state_vector[:, 0]) < 1e-12


def test_bad_inputs_are_refused():
    with pytest.raises(InputError, match="rows"):
        IMMPredictor(predictors=[KalmanPredictor(cv(1.0))] * 2, transition_probabilities=[[0.9, 0.2], [0.1, 0.9]])
    with pytest.raises(InputError, match="2 x 2"):
        IMMPredictor(predictors=[KalmanPredictor(cv(1.0))] * 2, transition_probabilities=np.eye(3))
    ip, _, _ = imm_pair((0.01, 2.0, 3.0), markov(3))
    with pytest.raises(InputError, match="modes"):
        ip.predict(IMMState.from_modes(np.zeros((2, 4)), np.stack([np.eye(4)] * 2), [0.5, 0.5], timestamp=T0),
                   timestamp=T0 + DT)
    with pytest.raises(InputError, match="sum to 1"):
        IMMState.from_modes(np.zeros((2, 4)), np.stack([np.eye(4)] * 2), [0.5, 0.6])


def test_imm_in_a_stonesoup_single_target_tracker_follows_a_manoeuvre():
    """Drop-in: Stone Soup's own tracker, initiator, hypothesiser and associator, with the IMM inside. The
    target runs straight, then turns hard: the large-q mode must take over after the turn."""
    from stonesoup.dataassociator.neighbour import NearestNeighbour
    from stonesoup.deleter.time import UpdateTimeStepsDeleter
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.initiator.simple import SinglePointInitiator
    from stonesoup.measures import Mahalanobis
    from stonesoup.tracker.simple import SingleTargetTracker

    ip, iu, mm = imm_pair((0.01, 20.0), markov(2, 0.97))
    rng = np.random.default_rng(5)
    pos, vel, scans = np.zeros(2), np.array([20.0, 0.0]), []
    for k in range(1, 61):
        if k > 30:  # 6 deg/s turn (2.1 m/s^2) from scan 30 on
            c, s = np.cos(np.radians(12)), np.sin(np.radians(12))
            vel = np.array([[c, -s], [s, c]]) @ vel
        pos = pos + 2 * vel
        det = Detection((pos + rng.normal(0, 5, 2)).reshape(2, 1), timestamp=T0 + k * DT, measurement_model=mm)
        scans.append((det.timestamp, {det}))
    initiator = SinglePointInitiator(GaussianState([0, 0, 0, 0.0], np.diag([1e4, 400, 1e4, 400])), mm)
    tracker = SingleTargetTracker(initiator, UpdateTimeStepsDeleter(3), scans,
                                  NearestNeighbour(DistanceHypothesiser(ip, iu, Mahalanobis(), 20.0)), iu)
    large_q = []
    for _, tracks in tracker:
        (track,) = tracks
        if isinstance(track.state, IMMStateUpdate):
            large_q.append(track.state.mode_probabilities[1])
    assert len(large_q) >= 55
    assert np.mean(large_q[10:28]) < 0.1 and np.mean(large_q[-25:]) > 0.8  # measured: 0.02, 0.91
    assert np.hypot(*(track.state.state_vector[[0, 2], 0] - pos)) < 30.0
