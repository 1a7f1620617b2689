"""The simulate system from Python: typed records of the scene's data, and the files are exactly those records."""

import numpy as np
import pandas as pd
import pytest
from scipy.io import wavfile

from sonartrack.core.random import trial_rng
from sonartrack.sim.array_signals import simulate_recording
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.run import (
    STREAMS,
    PassiveSimulation,
    SampleInputs,
    simulate_passive,
    simulate_samples,
    table_times,
)
from sonartrack.systems.simulate.settings import PassiveSceneSettings

SCENE = PassiveSceneSettings(duration_s=12.5, sample_rate_hz=2000.0, seed=4)


def test_table_times_cover_the_recording():
    assert table_times(5.0).tolist() == [0, 1, 2, 3, 4, 5]
    assert table_times(5.5).tolist() == [0, 1, 2, 3, 4, 5, 5.5]


def test_passive_record_holds_the_recording_and_tables():
    sim = simulate_passive(SCENE)
    assert isinstance(sim, PassiveSimulation) and sim.plan.n_blocks == 13
    blocks = list(sim.recording_blocks())
    assert [b.shape for b in blocks] == [(16, 2000)] * 12 + [(16, 1000)]
    # the blocks are the recording the scene's own stream draws in one piece
    direct = simulate_recording(SCENE, trial_rng(SCENE.seed, STREAMS["recording"]))
    np.testing.assert_array_equal(np.concatenate(blocks, axis=1), direct)
    assert sim.nav["time_s"].tolist() == table_times(12.5).tolist()
    assert len(sim.truth["time_s"]) == len(SCENE.ships) * 14


def test_the_files_are_the_records(tmp_path):
    files = write_scene(SCENE, tmp_path)
    assert {p.name for p in files.paths} >= {"recording.wav", "nav.csv", "contacts.csv", "frames.npy", "brg.csv"}
    sim, samples = simulate_passive(SCENE), simulate_samples(SCENE)
    assert isinstance(samples, SampleInputs)
    fs, data = wavfile.read(tmp_path / "recording.wav")
    assert fs == 2000 and data.shape == (25000, 16)
    np.testing.assert_array_equal(data.T, np.concatenate(list(sim.recording_blocks()), axis=1).astype(np.float32))
    np.testing.assert_array_equal(np.load(tmp_path / "frames.npy"), samples.frames)
    nav = pd.read_csv(tmp_path / "nav.csv")
    np.testing.assert_allclose(nav["x_m"], sim.nav["x_m"], rtol=1e-6, atol=1e-3)  # written to 7 digits
    brg = pd.read_csv(tmp_path / "brg.csv")
    np.testing.assert_allclose(brg["bearing_deg"], samples.bearings["bearing_deg"], rtol=1e-6)
    contacts = pd.read_csv(tmp_path / "contacts.csv")
    assert len(contacts) == len(samples.contacts["cartesian"]["time_s"])


def test_samples_do_not_depend_on_the_recording():
    """Each output has its own child stream: the samples are the same whether or not the recording is drawn."""
    a = simulate_samples(SCENE)
    list(simulate_passive(SCENE).recording_blocks())
    b = simulate_samples(SCENE)
    np.testing.assert_array_equal(a.frames, b.frames)
    np.testing.assert_array_equal(a.bearings["bearing_deg"], b.bearings["bearing_deg"])
    c = simulate_samples(SCENE.model_copy(update={"seed": 5}))
    assert not np.array_equal(a.frames, c.frames)


@pytest.mark.parametrize("only, present, absent", [("passive", "nav.csv", "frames.npy"),
                                                   ("samples", "frames.npy", "recording.wav")])
def test_only_writes_its_part(tmp_path, only, present, absent):
    write_scene(SCENE, tmp_path, only=only)
    assert (tmp_path / present).exists() and not (tmp_path / absent).exists()
