"""Stone Soup's JPDA tutorial end to end, once with Stone Soup's JPDA and once with ours: the same tracks.

The scene is the tutorial's (docs/tutorials/08_JPDATutorial.py; tests/stonesoup/conftest.py), and so is the
tracker loop: associate all tracks with the scan, update each track with every hypothesis, reduce the
mixture with the association weights (``gm_reduce_single``) and append a ``GaussianStateUpdate``. Only
the associator changes. The marginals are the same numbers computed in another order, so the tracks agree
to round-off (we ask 1e-9); a second, crowded scene (five targets converging) checks clusters of five.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

from stonesoup.dataassociator.probability import JPDA as StoneSoupJPDA  # noqa: E402
from stonesoup.dataassociator.probability import JPDAwithEHM2  # noqa: E402
from stonesoup.functions import gm_reduce_single  # noqa: E402
from stonesoup.types.array import StateVectors  # noqa: E402
from stonesoup.types.track import Track  # noqa: E402
from stonesoup.types.update import GaussianStateUpdate  # noqa: E402
from stonesoup.updater.kalman import KalmanUpdater  # noqa: E402

from sonartrack.stonesoup import JPDA  # noqa: E402


def run_tutorial_tracker(scene, associator_cls, pda_hypothesiser):
    """The tutorial's tracking loop with ``associator_cls``: the tracks (prior order) and the shared detections
    per scan (detections that the hypotheses of two or more tracks mention)."""
    updater = KalmanUpdater(scene["measurement"])
    associator = associator_cls(hypothesiser=pda_hypothesiser(scene))
    tracks = [Track([prior]) for prior in scene["priors"]]
    shared = []
    for timestamp, detections in scene["scans"]:
        hypotheses = associator.associate(set(tracks), detections, timestamp)
        mentions = [{id(h.measurement) for h in hypotheses[track] if h} for track in tracks]
        shared.append(sum(sum(d in m for m in mentions) > 1 for d in set().union(*mentions)))
        for track in tracks:
            multi = hypotheses[track]
            states = [updater.update(h) if h else h.prediction for h in multi]
            means = StateVectors([s.state_vector for s in states])
            covars = np.stack([s.covar for s in states], axis=2)
            weights = np.asarray([h.probability for h in multi])
            mean, covar = gm_reduce_single(means, covars, weights)
            track.append(GaussianStateUpdate(mean, covar, multi, multi[0].measurement.timestamp))
    return tracks, shared


def max_state_difference(tracks_a, tracks_b) -> float:
    """max |x_a - x_b| and |P_a - P_b| over every state of every track."""
    diff = 0.0
    for a, b in zip(tracks_a, tracks_b, strict=True):
        assert len(a) == len(b)
        for sa, sb in zip(a.states, b.states, strict=True):
            diff = max(diff, float(np.abs(np.asarray(sa.state_vector - sb.state_vector, float)).max()),
                       float(np.abs(np.asarray(sa.covar - sb.covar, float)).max()))
    return diff


@pytest.mark.parametrize("theirs", [StoneSoupJPDA, JPDAwithEHM2], ids=["JPDA", "JPDAwithEHM2"])
def test_tutorial_tracks_identical(tutorial_scene, scene_tools, theirs):
    ours_tracks, shared = run_tutorial_tracker(tutorial_scene, JPDA, scene_tools["pda_hypothesiser"])
    their_tracks, _ = run_tutorial_tracker(tutorial_scene, theirs, scene_tools["pda_hypothesiser"])
    diff = max_state_difference(ours_tracks, their_tracks)
    print(f"tutorial scene, ours vs Stone Soup {theirs.__name__}: max |state diff| {diff:.1e}")
    assert diff <= 1e-9
    assert sum(s > 0 for s in shared) >= 3  # the targets cross: JPDA's mutual exclusion is exercised
    # and the tracker tracks: the final estimates are near the truths
    for track, truth in zip(ours_tracks, tutorial_scene["truths"], strict=True):
        error = track.state_vector[[0, 2], 0] - truth[len(track) - 2].state_vector[[0, 2], 0]
        assert np.hypot(*np.asarray(error, float)) < 3.0


def test_crowded_scene_tracks_identical(crowded_scene, scene_tools):
    ours_tracks, shared = run_tutorial_tracker(crowded_scene, JPDA, scene_tools["pda_hypothesiser"])
    their_tracks, _ = run_tutorial_tracker(crowded_scene, JPDAwithEHM2, scene_tools["pda_hypothesiser"])
    diff = max_state_difference(ours_tracks, their_tracks)
    print(f"crowded scene (5 targets), ours vs Stone Soup JPDAwithEHM2: max |state diff| {diff:.1e}")
    assert diff <= 1e-9
    assert max(shared) >= 3
