"""The live chain on a stream of odd blocks gives the file chain's tracks and targets (issue 31 item 2)."""

import numpy as np
import pytest

from sonartrack.io.navigation import read_navigation
from sonartrack.io.stream.types import SampleBlock, StreamHeader
from sonartrack.systems.live import LivePassive
from sonartrack.systems.passive import PassiveSettings
from sonartrack.systems.passive.files import run_passive_recording

from .conftest import START

SETTINGS = PassiveSettings(spacing_m=2.5, min_track_s=60.0)


def _stream(live, x, seed, first=0):
    """Feed x in blocks of 37..7000 samples (never a window's 4000), from sample ``first``; the updates."""
    rng = np.random.default_rng(seed)
    i, ups = first, []
    while i < len(x):
        n = int(rng.integers(37, 7000))
        ups += live.push_block(SampleBlock(i, x[i:i + n]))
        i += n
    return ups


@pytest.fixture(scope="module")
def runs(scene):
    out, x, fs = scene
    ref = run_passive_recording(out / "recording.wav", out / "nav.csv", SETTINGS).result
    live = LivePassive(SETTINGS, StreamHeader(x.shape[1], fs, "float32", START), nav=read_navigation(out / "nav.csv"))
    ups = _stream(live, x, 7)
    result = live.finish()
    live.close()
    return ref, result, ups


def test_tracks_equal_the_file_runs(runs):
    ref, live, _ = runs
    assert len(ref.tracks) > 100
    np.testing.assert_array_equal(live.tracks.track_id, ref.tracks.track_id)
    np.testing.assert_array_equal(live.tracks.confirmed, ref.tracks.confirmed)
    np.testing.assert_array_equal(live.tracks.time_s, ref.tracks.time_s)
    # the front end transforms one window at a time live and 32 at once in the file: rounding only
    np.testing.assert_allclose(live.tracks.bearing_deg, ref.tracks.bearing_deg, rtol=0, atol=1e-9)
    np.testing.assert_allclose(live.record.level, ref.record.level, rtol=0, atol=1e-5)
    np.testing.assert_array_equal(live.record.time_s, ref.record.time_s)


def test_targets_equal_the_file_runs(runs):
    ref, live, _ = runs
    assert len(ref.targets) >= 2
    assert len(live.targets) == len(ref.targets)
    for a, b in zip(live.targets, ref.targets, strict=True):
        assert (a.target_id, a.track.track_id, a.side.side) == (b.target_id, b.track.track_id, b.side.side)
        np.testing.assert_allclose(a.ml.solution.state, b.ml.solution.state, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(a.sequential.solution.state, b.sequential.solution.state, rtol=1e-9, atol=1e-6)
        assert (a.tonal is None) == (b.tonal is None)
        if a.tonal is not None:
            assert a.tonal.line_hz == pytest.approx(b.tonal.line_hz, abs=1e-9)
    assert live.duration_s == ref.duration_s


def test_the_display_updates_come_per_window(runs):
    ref, _, ups = runs
    btr = [u for u in ups if u["type"] == "btr"]
    assert len(btr) == len(ref.record.time_s)  # one row per whole window (the last part-window none, as the file)
    assert [u["t_s"] for u in btr] == list(ref.record.time_s)
    tracks = [u for u in ups if u["type"] == "tracks"]
    confirmed = {t["id"] for u in tracks for t in u["tracks"] if t["status"] == "confirmed"}
    assert confirmed == set(ref.tracks.track_id[ref.tracks.confirmed].tolist())
    assert all(u["type"] in {"btr", "tracks", "health", "lofar"} for u in ups)
