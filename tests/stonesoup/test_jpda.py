"""sonartrack's JPDA as a Stone Soup data associator: the same hypotheses and weights as Stone Soup's JPDAs."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

from stonesoup.dataassociator.base import DataAssociator  # noqa: E402
from stonesoup.dataassociator.probability import JPDA as StoneSoupJPDA  # noqa: E402
from stonesoup.dataassociator.probability import JPDAwithEHM2  # noqa: E402

from sonartrack.association.jpda import jpda_brute_force  # noqa: E402
from sonartrack.stonesoup import JPDA  # noqa: E402
from sonartrack.stonesoup.hypotheses import tabulate  # noqa: E402
from sonartrack.stonesoup.jpda import exact_log_marginals  # noqa: E402


def _weights(multi) -> dict:
    """{detection id or None: probability} of one track's hypotheses."""
    return {id(h.measurement) if h else None: float(h.probability) for h in multi}


def _scan(scene, k):
    timestamp, detections = scene["scans"][k]
    from stonesoup.types.track import Track

    return [Track([prior]) for prior in scene["priors"]], detections, timestamp


@pytest.mark.parametrize("theirs", [StoneSoupJPDA, JPDAwithEHM2], ids=["JPDA", "JPDAwithEHM2"])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_same_hypotheses_and_weights(crowded_scene, scene_tools, theirs, k):
    tracks, detections, timestamp = _scan(crowded_scene, k)
    hypothesiser = scene_tools["pda_hypothesiser"](crowded_scene)
    ours = JPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    them = theirs(hypothesiser).associate(set(tracks), detections, timestamp)
    assert set(ours) == set(them) == set(tracks)
    for track in tracks:
        w_ours, w_them = _weights(ours[track]), _weights(them[track])
        assert w_ours.keys() == w_them.keys()
        assert max(abs(w_ours[d] - w_them[d]) for d in w_ours) < 1e-12
        assert not ours[track][0] and abs(sum(w_ours.values()) - 1.0) < 1e-12  # missed detection first, sum 1


def test_same_order_and_objects_as_stone_soup_jpda(tutorial_scene, scene_tools):
    tracks, detections, timestamp = _scan(tutorial_scene, 3)
    hypothesiser = scene_tools["pda_hypothesiser"](tutorial_scene)
    ours = JPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    them = StoneSoupJPDA(hypothesiser).associate(set(tracks), detections, timestamp)
    for track in tracks:
        assert [id(h.measurement) if h else None for h in ours[track]] == \
               [id(h.measurement) if h else None for h in them[track]]
        assert all(type(a) is type(b) and a.prediction is b.prediction or not a
                   for a, b in zip(ours[track], them[track], strict=True))


def test_normalised_and_unnormalised_hypothesisers_agree(crowded_scene, scene_tools):
    tracks, detections, timestamp = _scan(crowded_scene, 1)
    a = JPDA(scene_tools["pda_hypothesiser"](crowded_scene, normalise=True)).associate(set(tracks), detections,
                                                                                      timestamp)
    b = JPDA(scene_tools["pda_hypothesiser"](crowded_scene, normalise=False)).associate(set(tracks), detections,
                                                                                       timestamp)
    for track in tracks:
        wa, wb = _weights(a[track]), _weights(b[track])
        assert max(abs(wa[d] - wb[d]) for d in wa) < 1e-12


def test_no_tracks_and_no_detections(tutorial_scene, scene_tools):
    tracks, detections, timestamp = _scan(tutorial_scene, 0)
    associator = JPDA(scene_tools["pda_hypothesiser"](tutorial_scene))
    assert associator.associate(set(), detections, timestamp) == {}
    empty = associator.associate(set(tracks), set(), timestamp)
    assert all(len(m) == 1 and not m[0] and float(m[0].probability) == pytest.approx(1.0) for m in empty.values())


def test_is_a_stone_soup_associator_with_the_same_properties():
    assert issubclass(JPDA, DataAssociator)
    assert list(JPDA.properties) == list(StoneSoupJPDA.properties) == ["hypothesiser"]


def test_tabulate_reads_the_hypotheses(tutorial_scene, scene_tools):
    tracks, detections, timestamp = _scan(tutorial_scene, 2)
    hypothesiser = scene_tools["pda_hypothesiser"](tutorial_scene, normalise=False)
    hypotheses = {t: hypothesiser.hypothesise(t, detections, timestamp) for t in tracks}
    table = tabulate(tracks, hypotheses)
    for t, track in enumerate(tracks):
        for h in hypotheses[track]:
            if not h:
                assert table.log_miss[t] == pytest.approx(np.log(1 - 0.9 * 0.95))
            else:
                j = next(j for j, d in enumerate(table.detections) if d is h.measurement)
                assert table.log_lik[t, j] == pytest.approx(h.probability.log_value)
        assert np.isfinite(table.log_lik[t]).sum() == len(hypotheses[track]) - 1


def test_more_than_62_detections_exact():
    # 3 tracks, 72 detections: 22 private to each track and 6 shared; merging the private ones is exact
    rng = np.random.default_rng(5)
    ll = np.full((3, 72), -np.inf)
    for t in range(3):
        ll[t, 22 * t:22 * (t + 1)] = rng.normal(0, 1, 22)
    ll[:, 66:] = rng.normal(1, 1, (3, 6))
    ll[0, 70] = -np.inf
    log_miss = np.log([0.2, 0.3, 0.15])
    beta = np.exp(exact_log_marginals(ll, log_miss))
    assert np.abs(beta - jpda_brute_force(ll, log_miss)).max() < 1e-12


def test_one_track_many_detections_is_pda():
    rng = np.random.default_rng(2)
    ll = rng.normal(0, 2, (1, 300))
    log_miss = np.array([np.log(0.1)])
    beta = np.exp(exact_log_marginals(ll, log_miss))
    w = np.exp(np.concatenate([log_miss, ll[0]]))
    assert np.abs(beta[0] - w / w.sum()).max() < 1e-14


def test_timestamp_of_missed_detection(tutorial_scene, scene_tools):
    tracks, detections, timestamp = _scan(tutorial_scene, 1)
    ours = JPDA(scene_tools["pda_hypothesiser"](tutorial_scene)).associate(set(tracks), detections, timestamp)
    assert all(m[0].measurement.timestamp == timestamp for m in ours.values())


def test_without_stone_soup_the_import_error_says_what_to_install():
    import subprocess
    import sys

    code = "import sys; sys.modules['stonesoup'] = None; import sonartrack.stonesoup"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode != 0
    assert run.stderr.strip().splitlines()[-1] == \
        "ImportError: sonartrack.stonesoup needs Stone Soup: pip install sonartrack[stonesoup]"


def test_the_core_does_not_import_stone_soup():
    import subprocess
    import sys

    code = ("import sys, sonartrack, sonartrack.association.jpda, sonartrack.tracking.multi_target, "
            "sonartrack.io.contacts; assert not any(m.split('.')[0] == 'stonesoup' for m in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], timeout=120).returncode == 0
