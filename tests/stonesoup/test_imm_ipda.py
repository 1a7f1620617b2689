"""IMM-IPDA (paper P4) as Stone Soup components: on the same scans it gives the same tracks, states, mode
probabilities, existence and confirmations as sonartrack's tracking ``position_tracker`` (1e-9), and the
example script runs."""

import datetime
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")

from stonesoup.models.measurement.linear import LinearGaussian  # noqa: E402
from stonesoup.models.transition.linear import (  # noqa: E402
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor  # noqa: E402
from stonesoup.types.detection import Detection  # noqa: E402
from stonesoup.types.state import GaussianState  # noqa: E402
from stonesoup.types.track import Track  # noqa: E402
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater  # noqa: E402

from sonartrack.association.gating import gate_threshold  # noqa: E402
from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.stonesoup.imm import IMMPredictor, IMMState  # noqa: E402
from sonartrack.stonesoup.imm_ipda import (  # noqa: E402
    IMMIPDAHypothesiser,
    IMMIPDATracker,
    IMMIPDAUpdater,
    imm_ipda_tracker,
)
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE  # noqa: E402
from sonartrack.tracking.configurations import position_tracker  # noqa: E402
from sonartrack.tracking.settings import PositionTrackerSettings as Settings  # noqa: E402

T0 = datetime.datetime(2026, 1, 1)
PERM = [0, 2, 1, 3]  # Stone Soup's [x, vx, y, vy] -> sonartrack's [x, y, vx, vy]
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "stonesoup_tracker.py"


def cv(q):
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


def scans(n=30, T=30.0, seed=0, clutter=10, region=3000.0):
    """One target (P_D 0.8) in uniform clutter; every measurement with its own covariance (bistatic-like)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        truth = np.array([1000 + 3 * T * k, 2000 - 2 * T * k])
        z = [truth + rng.normal(0, 40, 2)] if rng.random() < 0.8 else []
        z += list(rng.uniform(-region, region, (rng.poisson(clutter), 2)))
        A = rng.normal(size=(len(z), 2, 2))
        R = A @ np.swapaxes(A, 1, 2) * 200 + np.eye(2) * 1600
        out.append((T * k, np.array(z).reshape(-1, 2), R))
    return out


def stonesoup_tracker(s: Settings, updater_cls=KalmanUpdater) -> IMMIPDATracker:
    """The IMM-IPDA tracker built part by part (as imm_ipda_tracker does), with a chosen mode updater."""
    predictor = IMMPredictor(predictors=[KalmanPredictor(cv(q)) for q in s.q],
                             transition_probabilities=s.transition_matrix())
    updater = IMMIPDAUpdater(updater=updater_cls(None))
    hypothesiser = IMMIPDAHypothesiser(predictor=predictor, updater=updater,
                                       clutter_spatial_density=s.clutter_density_per_m2, prob_detect=s.pd,
                                       prob_gate=s.gate_probability, prob_survive=s.p_survive, prob_birth=s.p_birth)
    return IMMIPDATracker(hypothesiser=hypothesiser, updater=updater, velocity_std=s.init_velocity_std_mps,
                          initial_existence=s.initial_existence, confirm_threshold=s.confirm_threshold,
                          terminate_threshold=s.terminate_threshold, max_tracks=s.max_tracks)


def detections(t, z, R):
    when = T0 + datetime.timedelta(seconds=t)
    return when, [Detection(zi.reshape(2, 1), timestamp=when, measurement_model=LinearGaussian(4, (0, 2), Ri))
                  for zi, Ri in zip(z, R, strict=True)]


def rel_diff(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


@pytest.mark.parametrize("q", [[1e-4, 0.05], [0.01], [1e-4, 0.01, 0.1]])
def test_equals_sonartrack_position_tracker(q):
    s = Settings(q=q, clutter_density_per_m2=1e-6)
    ours, theirs = position_tracker(s), imm_ipda_tracker(s)
    worst, confirmed = 0.0, 0
    for t, z, R in scans():
        snap = ours.step(t, z, R)
        theirs.update_tracker(*detections(t, z, R))
        live = theirs.live_tracks
        assert [int(track.id) for track in live] == list(snap.track_id)
        for i, track in enumerate(live):
            st = track.state
            worst = max(worst, rel_diff(np.asarray(st.state_vector, float)[PERM, 0], snap.x[i]),
                        rel_diff(np.asarray(st.covar)[np.ix_(PERM, PERM)], snap.P[i]),
                        abs(track.metadata[EXISTENCE] - snap.existence[i]),
                        rel_diff(st.mode_probabilities, snap.mu[i]))
            assert track.metadata[CONFIRMED] == bool(snap.confirmed[i])
        confirmed = max(confirmed, int(snap.confirmed.sum()))
    assert worst < 1e-9
    assert confirmed >= 1 and len(snap.track_id) > 3  # the target was confirmed; clutter made tentative tracks


def test_per_mode_path_equals_array_path():
    """A Kalman updater the IMM does not recognise goes through Stone Soup's predict_measurement per mode and
    detection: the same tracks as the array path."""

    class PerMode(ExtendedKalmanUpdater):
        pass

    s = Settings(clutter_density_per_m2=1e-6)
    fast, slow = stonesoup_tracker(s), stonesoup_tracker(s, PerMode)
    for t, z, R in scans(n=12, clutter=6):
        fast.update_tracker(*detections(t, z, R))
        slow.update_tracker(*detections(t, z, R))
        for a, b in zip(fast.live_tracks, slow.live_tracks, strict=True):
            assert rel_diff(a.state.mode_covars, b.state.mode_covars) < 1e-12
            assert rel_diff(a.state.mode_means, b.state.mode_means) < 1e-12
            assert abs(a.metadata[EXISTENCE] - b.metadata[EXISTENCE]) < 1e-12


def test_tracker_iterates_a_detector_like_stonesoup_trackers():
    s = Settings(clutter_density_per_m2=1e-6)
    data = scans(n=10, clutter=5)
    stepped = imm_ipda_tracker(s)
    for t, z, R in data:
        stepped.update_tracker(*detections(t, z, R))
    iterated = imm_ipda_tracker(s, detector=[detections(t, z, R) for t, z, R in data])
    outputs = list(iterated)
    assert len(outputs) == 10 and outputs[-1][1] == iterated.tracks
    assert [t.id for t in iterated.live_tracks] == [t.id for t in stepped.live_tracks]
    for a, b in zip(iterated.live_tracks, stepped.live_tracks, strict=True):
        np.testing.assert_array_equal(a.state.covar, b.state.covar)
    with pytest.raises(InputError, match="detector"):
        iter(imm_ipda_tracker(s))


def one_track_parts(s: Settings):
    trk = stonesoup_tracker(s)
    x = IMMState.from_modes(np.repeat([[0.0, 3.0, 0.0, -2.0]], len(s.q), 0),
                            np.repeat(np.diag([400.0, 4.0, 400.0, 4.0])[None], len(s.q), 0),
                            np.full(len(s.q), 1 / len(s.q)), timestamp=T0)
    return trk.hypothesiser, trk.updater, Track([x], init_metadata={EXISTENCE: 0.6})


def test_empty_scan_lowers_existence_by_the_ipda_formula():
    s = Settings()
    hyp, upd, track = one_track_parts(s)
    multi = hyp.hypothesise(track, [], T0 + datetime.timedelta(seconds=30))
    post = upd.update(multi)
    e_pred = s.p_survive * 0.6
    d = s.pd * s.gate_probability
    assert post.existence_probability == pytest.approx((1 - d) * e_pred / (1 - d * e_pred), rel=1e-12)
    np.testing.assert_allclose(post.mode_means, multi[0].prediction.mode_means, rtol=1e-15)
    assert len(multi) == 1 and float(multi[0].probability) == pytest.approx(1.0)


def test_hypotheses_weights_and_gate():
    s = Settings(clutter_density_per_m2=1e-6)
    hyp, upd, track = one_track_parts(s)
    when = T0 + datetime.timedelta(seconds=30)
    model = LinearGaussian(4, (0, 2), np.eye(2) * 400)
    near = Detection(np.array([[95.0], [-55.0]]), timestamp=when, measurement_model=model)
    far = Detection(np.array([[5000.0], [5000.0]]), timestamp=when, measurement_model=model)
    multi = hyp.hypothesise(track, [far, near], when)
    assert [h.measurement for h in multi][1:] == [near]  # the far one is outside every mode's gate
    np.testing.assert_allclose(multi.mode_weights.sum(axis=1), 1.0, rtol=1e-12)
    assert sum(float(h.probability) for h in multi) == pytest.approx(1.0, rel=1e-12)
    nu, S = multi.innovations[:, 0], multi.innovation_covars[:, 0]
    assert np.all(np.einsum("ri,rij,rj->r", nu, np.linalg.inv(S), nu) < gate_threshold(s.gate_probability, 2))
    post = upd.update(multi)
    assert post.existence_probability > 0.6 * s.p_survive  # a detection where the track expects one
    assert post.log_likelihood == pytest.approx(np.log(post.existence_probability / (1 - post.existence_probability)
                                                       / (multi.existence_prediction
                                                          / (1 - multi.existence_prediction))), rel=1e-9)


def test_track_without_existence_is_refused():
    hyp, _, _ = one_track_parts(Settings())
    bare = Track([GaussianState([0, 1, 0, 1.0], np.eye(4), timestamp=T0)])
    with pytest.raises(InputError, match="existence"):
        hyp.hypothesise(bare, [], T0 + datetime.timedelta(seconds=30))


def test_example_script_runs():
    res = subprocess.run([sys.executable, str(EXAMPLE)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.strip().splitlines()
    assert len(lines) == 1 and "IMM-IPDA: 2/2 targets held" in lines[0] and "JPDA: 2/2" in lines[0]
