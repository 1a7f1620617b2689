"""IPDA / JIPDA for Stone Soup: hand-worked IPDA, JIPDA against enumeration of its joint events, limits
(one track: IPDA; existence 1: JPDA), existence on the tracks, initiation/deletion, a whole tracker run."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

from scipy.stats import chi2, multivariate_normal  # noqa: E402
from stonesoup.initiator.simple import SimpleMeasurementInitiator  # noqa: E402
from stonesoup.tracker.simple import MultiTargetMixtureTracker  # noqa: E402
from stonesoup.types.state import GaussianState  # noqa: E402
from stonesoup.types.track import Track  # noqa: E402
from stonesoup.updater.kalman import KalmanUpdater  # noqa: E402

from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.stonesoup import (  # noqa: E402
    EXISTENCE,
    IPDA,
    JIPDA,
    JPDA,
    ExistenceDeleter,
    ExistenceInitiator,
    ExistenceTrack,
    IPDAHypothesiser,
    confirmed_tracks,
    existence_of,
)
from sonartrack.stonesoup.hypotheses import tabulate  # noqa: E402

P_SURVIVE = 0.95


def _tracks(scene, existences):
    return [ExistenceTrack([prior], init_metadata={EXISTENCE: p}) for prior, p in zip(scene["priors"], existences,
                                                                                      strict=True)]


def _hypothesiser(scene, tools, **options):
    return tools["pda_hypothesiser"](scene, IPDAHypothesiser, **{"prob_survive": P_SURVIVE, **options})


def _by_detection(multi) -> dict:
    return {id(h.measurement) if h else None: float(h.probability) for h in multi}


def test_ipda_by_hand(tutorial_scene, scene_tools):
    # Lambda = 1 - P_D P_G + sum_j P_D N(z_j; z_hat, S) / lambda;  P(E)+ = Lambda P- / (1 - P- + Lambda P-)
    (track,) = _tracks({"priors": tutorial_scene["priors"][:1]}, [0.4])
    timestamp, detections = tutorial_scene["scans"][2]
    hypothesiser = _hypothesiser(tutorial_scene, scene_tools)
    out = IPDA(hypothesiser).associate({track}, detections, timestamp)[track]
    prediction = hypothesiser.predictor.predict(track, timestamp=timestamp)
    z_hat = (tutorial_scene["measurement"].matrix() @ prediction.state_vector).ravel()
    H = tutorial_scene["measurement"].matrix()
    S = H @ prediction.covar @ H.T + tutorial_scene["measurement"].covar()
    w = {}
    for d in detections:
        nu = d.state_vector.ravel() - z_hat
        if nu @ np.linalg.solve(S, nu) <= chi2.ppf(0.95, 2):
            w[id(d)] = 0.9 * multivariate_normal(z_hat, S).pdf(d.state_vector.ravel()) / 0.125
    w[None] = 1 - 0.9 * 0.95
    lam = sum(w.values())
    p_pred = P_SURVIVE * 0.4
    assert len(w) >= 2
    assert _by_detection(out) == pytest.approx({k: v / lam for k, v in w.items()}, rel=1e-10)
    assert float(out.existence_prediction) == pytest.approx(p_pred, rel=1e-12)
    assert float(out.existence_probability) == pytest.approx(lam * p_pred / (1 - p_pred + lam * p_pred), rel=1e-10)


def jipda_by_enumeration(log_lik, log_miss, p_pred):
    """Musicki & Evans 2004 from the definition: each track is absent (1 - P), present and missed (P w_0) or
    present with detection j (P w_j), no detection twice. Returns (beta given existence, P(E | Z))."""
    n, m = log_lik.shape
    options = [["absent", "missed"] + [j for j in range(m) if np.isfinite(log_lik[t, j])] for t in range(n)]
    total, exist, beta = 0.0, np.zeros(n), np.zeros((n, m + 1))
    for event in itertools.product(*options):
        used = [j for j in event if not isinstance(j, str)]
        if len(used) != len(set(used)):
            continue
        weight = np.prod([1 - p_pred[t] if s == "absent" else p_pred[t] * np.exp(log_miss[t] if s == "missed"
                          else log_lik[t, s]) for t, s in enumerate(event)])
        total += weight
        for t, s in enumerate(event):
            if s != "absent":
                exist[t] += weight
                beta[t, 0 if s == "missed" else s + 1] += weight
    return beta / exist[:, None], exist / total


def test_jipda_equals_enumeration_of_its_joint_events(crowded_scene, scene_tools):
    existences = [0.9, 0.5, 0.2, 0.7, 0.05]
    tracks = _tracks(crowded_scene, existences)
    timestamp, detections = crowded_scene["scans"][4]
    hypothesiser = _hypothesiser(crowded_scene, scene_tools)
    out = JIPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    table = tabulate(tracks, {t: hypothesiser.hypothesise(t, detections, timestamp) for t in tracks})
    assert max(np.isfinite(table.log_lik).sum(axis=0)) >= 2  # detections shared by tracks
    beta, exist = jipda_by_enumeration(table.log_lik, table.log_miss, P_SURVIVE * np.array(existences))
    for t, track in enumerate(tracks):
        expected = {None: beta[t, 0], **{id(d): beta[t, j + 1] for j, d in enumerate(table.detections)
                                         if np.isfinite(table.log_lik[t, j])}}
        assert _by_detection(out[track]) == pytest.approx(expected, rel=1e-9, abs=1e-15)
        assert float(out[track].existence_probability) == pytest.approx(exist[t], rel=1e-10)


def test_jipda_of_one_track_is_ipda(tutorial_scene, scene_tools):
    timestamp, detections = tutorial_scene["scans"][5]
    hypothesiser = _hypothesiser(tutorial_scene, scene_tools)
    (a,) = _tracks({"priors": tutorial_scene["priors"][:1]}, [0.3])
    (b,) = _tracks({"priors": tutorial_scene["priors"][:1]}, [0.3])
    ja = JIPDA(hypothesiser).associate({a}, detections, timestamp)[a]
    ib = IPDA(hypothesiser).associate({b}, detections, timestamp)[b]
    assert [h.measurement for h in ja if h] == [h.measurement for h in ib if h]
    assert [float(h.probability) for h in ja] == pytest.approx([float(h.probability) for h in ib], rel=1e-10)
    assert float(ja.existence_probability) == pytest.approx(float(ib.existence_probability), rel=1e-12)


def test_jipda_with_certain_existence_is_jpda(crowded_scene, scene_tools):
    tracks = _tracks(crowded_scene, [1.0] * 5)
    timestamp, detections = crowded_scene["scans"][6]
    hypothesiser = _hypothesiser(crowded_scene, scene_tools, prob_survive=1.0)
    jipda = JIPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    jpda = JPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    for track in tracks:
        assert _by_detection(jipda[track]) == pytest.approx(_by_detection(jpda[track]), rel=1e-10, abs=1e-15)
        assert float(jipda[track].existence_probability) == pytest.approx(1.0)


def test_existence_is_kept_per_state_and_association_is_repeatable(tutorial_scene, scene_tools):
    track, = _tracks({"priors": tutorial_scene["priors"][:1]}, [0.5])
    hypothesiser = _hypothesiser(tutorial_scene, scene_tools)
    timestamp, detections = tutorial_scene["scans"][1]
    first = JIPDA(hypothesiser).associate({track}, detections, timestamp)[track]
    again = JIPDA(hypothesiser).associate({track}, detections, timestamp)[track]
    assert float(first.existence_probability) == float(again.existence_probability)
    assert existence_of(track) == 0.5  # not yet appended
    track.append(first[0].prediction)  # what MultiTargetMixtureTracker appends when nothing is likely
    assert existence_of(track) == pytest.approx(float(first.existence_probability))
    assert track.metadatas[0][EXISTENCE] == 0.5


def test_plain_tracks_get_existence_in_their_metadata(tutorial_scene, scene_tools):
    track = Track([tutorial_scene["priors"][0]], init_metadata={EXISTENCE: 0.5})
    timestamp, detections = tutorial_scene["scans"][1]
    out = IPDA(_hypothesiser(tutorial_scene, scene_tools)).associate({track}, detections, timestamp)[track]
    assert existence_of(track) == pytest.approx(float(out.existence_probability))


def test_user_mistakes_are_named(tutorial_scene, scene_tools):
    timestamp, detections = tutorial_scene["scans"][1]
    bare = Track([tutorial_scene["priors"][0]])
    with pytest.raises(InputError, match="no existence probability"):
        JIPDA(_hypothesiser(tutorial_scene, scene_tools)).associate({bare}, detections, timestamp)
    with pytest.raises(InputError, match="normalise=False"):
        IPDA(_hypothesiser(tutorial_scene, scene_tools, normalise=True)).associate({bare}, detections, timestamp)
    with pytest.raises(InputError, match="IPDAHypothesiser"):
        JIPDA(scene_tools["pda_hypothesiser"](tutorial_scene, normalise=False)).associate({bare}, detections,
                                                                                          timestamp)


def test_initiator_and_deleter(tutorial_scene):
    timestamp, detections = tutorial_scene["scans"][0]
    prior = GaussianState(np.zeros((4, 1)), np.diag([0.0, 1.0, 0.0, 1.0]))
    tracks = ExistenceInitiator(SimpleMeasurementInitiator(prior, tutorial_scene["measurement"]),
                                initial_existence=0.2).initiate(detections, timestamp)
    assert len(tracks) == len(detections) and all(isinstance(t, ExistenceTrack) for t in tracks)
    assert all(existence_of(t) == 0.2 for t in tracks)
    low, high = sorted(tracks, key=lambda t: t.id)[:2]
    low.metadata[EXISTENCE], high.metadata[EXISTENCE] = 0.005, 0.95
    deleter = ExistenceDeleter(deletion_threshold=0.01, confirmation_threshold=0.9)
    assert deleter.delete_tracks(tracks) == {low}
    assert confirmed_tracks(tracks) == {high}


def test_multi_target_tracker_finds_the_targets(scene_tools):
    # the tutorial scene with its true clutter density (~0.01 /m^2), tracks started by the initiator only
    scene = scene_tools["build_scene"]()
    scene["clutter_density"] = 0.01
    prior = GaussianState(np.zeros((4, 1)), np.diag([0.0, 1.0, 0.0, 1.0]))
    tracker = MultiTargetMixtureTracker(
        initiator=ExistenceInitiator(SimpleMeasurementInitiator(prior, scene["measurement"]), initial_existence=0.05),
        deleter=ExistenceDeleter(deletion_threshold=0.01, confirmation_threshold=0.9), detector=None,
        data_associator=JIPDA(scene_tools["pda_hypothesiser"](scene, IPDAHypothesiser)),
        updater=KalmanUpdater(scene["measurement"]))
    for timestamp, detections in scene["scans"]:
        _, tracks = tracker.update_tracker(timestamp, detections)
    truth_xy = [np.asarray(path[len(scene["scans"]) - 1].state_vector[[0, 2], 0], float) for path in scene["truths"]]
    likely = [(np.asarray(t.state_vector[[0, 2], 0], float), existence_of(t)) for t in tracks if existence_of(t) > 0.5]
    for xy in truth_xy:
        assert any(np.hypot(*(p - xy)) < 3.0 and e > 0.8 for p, e in likely)
    assert sum(min(np.hypot(*(p - xy)) for xy in truth_xy) > 5.0 for p, _ in likely) <= 1
