"""`sonartrack detect` on frames synthesised here: decision, best track, outputs, bad input."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.models.range_doppler import RangeDopplerGrid
from sonartrack.sim.range_doppler import simulate_frames, simulate_target


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    d = tmp_path_factory.mktemp("frames")
    rng = np.random.default_rng(42)
    grid = RangeDopplerGrid.cw(12, 40, 0.125, 30e3, 1500.0)
    track = simulate_target(rng, grid, 2.0, 0.3, 6)
    strong = simulate_frames(rng, grid, 6, 100.0, track.cells) * 7.5  # an arbitrary receiver gain
    np.save(d / "strong.npy", strong)
    np.savez(d / "noise.npz", frames=simulate_frames(rng, grid, 6))
    return d, track


def test_strong_target_is_detected_and_its_track_found(frames, tmp_path, capsys):
    d, track = frames
    cfg = tmp_path / "det.toml"
    cfg.write_text("[detector]\nsigma_a_mps2 = 0.3\n[decision]\ncalibration_trials = 300\npfa = 0.05\n")
    code, out, err = run(capsys, "detect", "--frames", d / "strong.npy", "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    assert "TARGET PRESENT" in out and out.count("\n") == 1
    table = pd.read_csv(tmp_path / "o" / "detection.csv")
    assert len(table) == 6
    cells = table[["range_index", "doppler_index"]].to_numpy()
    hits = (cells == track.cells).all(axis=1)
    assert hits.sum() >= 5  # 20 dB echoes: the best track is the target's
    assert (tmp_path / "o" / "detection.png").stat().st_size > 0


def test_noise_only_is_not_detected(frames, tmp_path, capsys):
    d, _ = frames
    code, out, err = run(capsys, "detect", "--frames", d / "noise.npz", "--threshold", "20", "--out", tmp_path / "o")
    assert code == 0, err
    assert "no target" in out


@pytest.mark.parametrize("make, needle", [
    (lambda p: np.save(p, np.ones((4, 5))), "rank 3"),
    (lambda p: np.save(p, -np.ones((2, 4, 5))), "negative"),
    (lambda p: np.save(p, np.full((2, 4, 5), np.nan)), "NaN"),
    (lambda p: np.save(p, np.ones((0, 4, 5))), "K = 0"),
    (lambda p: p.write_text("not numpy"), "cannot read|not a plain"),
])
def test_bad_frames(tmp_path, capsys, make, needle):
    import re

    p = tmp_path / "f.npy"
    make(p)
    code, out, err = run(capsys, "detect", "--frames", p, "--out", tmp_path / "o")
    assert code == 2
    assert re.search(needle, err) and err.strip().count("\n") == 0
    assert not (tmp_path / "o" / "detection.csv").exists()


def test_bad_options(frames, tmp_path, capsys):
    d, _ = frames
    code, _, err = run(capsys, "detect", "--frames", d / "noise.npz", "--pfa", "1e-5", "--out", tmp_path / "o")
    assert code == 2 and "calibration trials" in err
    cfg = tmp_path / "c.toml"
    cfg.write_text("[detector]\nn_trakcs = 3\n")
    code, _, err = run(capsys, "detect", "--frames", d / "noise.npz", "--config", cfg, "--out", tmp_path / "o")
    assert code == 2 and "n_trakcs" in err
    code, _, err = run(capsys, "detect", "--out", tmp_path / "o")
    assert code == 2 and "--frames" in err


def test_print_config_reads_back_and_shows_options(tmp_path, capsys):
    """--print-config shows defaults <- TOML <- options, and the printed TOML reads back to the same settings."""
    from sonartrack.detection.detect import DetectSettings
    from sonartrack.io import toml as toml_io

    cfg = tmp_path / "c.toml"
    cfg.write_text("normalisation = 'none'\n[plane]\npulse_s = 0.25\n[detector]\nn_tracks = 4\n")
    code, out, err = run(capsys, "detect", "--config", cfg, "--n-tracks", "7", "--pfa", "0.05", "--print-config")
    assert code == 0, err
    printed = tmp_path / "printed.toml"
    printed.write_text(out)
    s = toml_io.validate(DetectSettings, toml_io.load(printed))
    assert (s.normalisation, s.plane.pulse_s, s.detector.n_tracks, s.decision.pfa) == ("none", 0.25, 7, 0.05)
    assert s.detector.snr_db == DetectSettings().detector.snr_db and s.decision.threshold is None
    assert "(s)" in out and "(dB)" in out  # units beside the values
