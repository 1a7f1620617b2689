"""JPDA_A (paper P0) for Stone Soup: the amplitude-aided weights by hand, exact marginals by enumeration,
the amplitude's effect, and the eq. 9 strength update."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

from scipy.stats import chi2, expon, multivariate_normal, norm  # noqa: E402
from stonesoup.types.detection import Detection  # noqa: E402

from sonartrack.association.jpda import jpda_brute_force  # noqa: E402
from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.stonesoup import (  # noqa: E402
    AMPLITUDE,
    JPDA,
    STRENGTH,
    AmplitudeHypothesiser,
    ExistenceTrack,
    JPDAWithAmplitude,
)
from sonartrack.stonesoup.hypotheses import tabulate  # noqa: E402

TAU, ALPHA, SIGMA_A, Z_HAT = 10.0, 0.5, 3.0, 14.0


def _hypothesiser(scene, tools, **options):
    return tools["pda_hypothesiser"](scene, AmplitudeHypothesiser, amplitude_threshold=TAU, false_amplitude_rate=ALPHA,
                                     amplitude_spread=SIGMA_A, **options)


def _scan(scene, k, amplitudes_seed=0):
    """Scan k with amplitudes: true detections ~ N(Z_HAT, SIGMA_A^2), clutter TAU + Exp(ALPHA), all above TAU."""
    rng = np.random.default_rng(amplitudes_seed + k)
    timestamp, detections = scene["scans"][k]
    out = set()
    for d in sorted(detections, key=lambda d: tuple(np.asarray(d.state_vector, float).ravel())):  # fixed order
        true = hasattr(d, "groundtruth_path")
        a = max(rng.normal(Z_HAT, SIGMA_A), TAU + 0.01) if true else TAU + rng.exponential(1 / ALPHA)
        out.add(Detection(d.state_vector, timestamp=d.timestamp, measurement_model=d.measurement_model,
                          metadata={AMPLITUDE: float(a), "true": true}))
    return timestamp, out


def _tracks(scene):
    return [ExistenceTrack([prior], init_metadata={STRENGTH: Z_HAT}) for prior in scene["priors"]]


def test_weights_by_hand(tutorial_scene, scene_tools):
    # w_j = P_D0 N(z_j; z_hat, S) / lambda * N(a_j; Z_HAT, SIGMA_A^2) / (ALPHA exp(-ALPHA (a_j - TAU)))
    # w_0 = 1 - P_D0 Phi((Z_HAT - TAU) / SIGMA_A) P_G
    track = _tracks(tutorial_scene)[0]
    timestamp, detections = _scan(tutorial_scene, 3)
    hypothesiser = _hypothesiser(tutorial_scene, scene_tools)
    multi = hypothesiser.hypothesise(track, detections, timestamp)
    prediction = hypothesiser.predictor.predict(track, timestamp=timestamp)
    H, R = tutorial_scene["measurement"].matrix(), tutorial_scene["measurement"].covar()
    z_hat, S = (H @ prediction.state_vector).ravel(), H @ prediction.covar @ H.T + R
    expected = {None: 1 - 0.9 * norm.cdf((Z_HAT - TAU) / SIGMA_A) * 0.95}
    for d in detections:
        z, a = d.state_vector.ravel(), d.metadata[AMPLITUDE]
        if (z - z_hat) @ np.linalg.solve(S, z - z_hat) <= chi2.ppf(0.95, 2):
            expected[id(d)] = (0.9 * multivariate_normal(z_hat, S).pdf(z) / 0.125 * norm.pdf(a, Z_HAT, SIGMA_A)
                               / expon.pdf(a - TAU, scale=1 / ALPHA))
    got = {id(h.measurement) if h else None: float(h.probability) for h in multi}
    assert len(got) >= 2
    assert got == pytest.approx(expected, rel=1e-10)


def test_marginals_are_exact_jpda_of_the_amplitude_weights(crowded_scene, scene_tools):
    tracks = _tracks(crowded_scene)
    timestamp, detections = _scan(crowded_scene, 5)
    hypothesiser = _hypothesiser(crowded_scene, scene_tools)
    out = JPDAWithAmplitude(hypothesiser).associate(set(tracks), detections, timestamp)
    table = tabulate(tracks, {t: hypothesiser.hypothesise(t, detections, timestamp) for t in tracks})
    assert max(np.isfinite(table.log_lik).sum(axis=0)) >= 2
    beta = jpda_brute_force(table.log_lik, table.log_miss)
    for t, track in enumerate(tracks):
        got = {id(h.measurement) if h else None: float(h.probability) for h in out[track]}
        expected = {None: beta[t, 0], **{id(d): beta[t, j + 1] for j, d in enumerate(table.detections)
                                         if np.isfinite(table.log_lik[t, j])}}
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_amplitude_moves_weight_to_the_target(tutorial_scene, scene_tools):
    # summed over the scans, the target's detections weigh more with amplitudes than without, the clutter less
    gain = {True: [], False: []}
    for k in range(20):
        tracks = _tracks(tutorial_scene)
        timestamp, detections = _scan(tutorial_scene, k)
        with_a = JPDAWithAmplitude(_hypothesiser(tutorial_scene, scene_tools)).associate(set(tracks), detections,
                                                                                          timestamp)
        without = JPDA(scene_tools["pda_hypothesiser"](tutorial_scene)).associate(set(tracks), detections, timestamp)
        for track in tracks:
            plain = {id(h.measurement): float(h.probability) for h in without[track] if h}
            for h in with_a[track]:
                if h:
                    gain[h.measurement.metadata["true"]].append(float(h.probability) - plain[id(h.measurement)])
    assert np.mean(gain[True]) > 0.01 and np.mean(gain[False]) < -0.001


def test_strength_update_eq9(tutorial_scene, scene_tools):
    tracks = _tracks(tutorial_scene)
    timestamp, detections = _scan(tutorial_scene, 2)
    out = JPDAWithAmplitude(_hypothesiser(tutorial_scene, scene_tools)).associate(set(tracks), detections, timestamp)
    for track in tracks:
        gated = [h.measurement.metadata[AMPLITUDE] for h in out[track] if h]
        track.append(out[track][0].prediction)
        assert track.metadata[STRENGTH] == pytest.approx(0.7 * Z_HAT + 0.3 * max(gated))
        assert track.metadatas[0][STRENGTH] == Z_HAT
    empty = _tracks(tutorial_scene)[0]
    JPDAWithAmplitude(_hypothesiser(tutorial_scene, scene_tools)).associate({empty}, set(), timestamp)
    empty.append(tutorial_scene["priors"][0])
    assert empty.metadata[STRENGTH] == Z_HAT


def test_missing_amplitude_is_named(tutorial_scene, scene_tools):
    timestamp, detections = tutorial_scene["scans"][2]
    with pytest.raises(InputError, match="amplitude"):
        JPDAWithAmplitude(_hypothesiser(tutorial_scene, scene_tools)).associate(set(_tracks(tutorial_scene)),
                                                                                detections, timestamp)
