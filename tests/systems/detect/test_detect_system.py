"""The detect system from Python: a frame stack in, a decision out, and the same file as ``sonartrack detect``."""

import numpy as np
import pytest

from sonartrack.cli import main
from sonartrack.detection.detect import FrameDetection
from sonartrack.models.range_doppler import RangeDopplerGrid
from sonartrack.sim.range_doppler import simulate_frames, simulate_target
from sonartrack.systems.detect.files import CSV_NAME, read_frames_file, write_detection
from sonartrack.systems.detect.run import run_detect, verdict
from sonartrack.systems.detect.settings import DetectSettings

GRID = RangeDopplerGrid.cw(12, 40, 0.125, 30e3, 1500.0)


@pytest.fixture(scope="module")
def stacks():
    """A 20 dB target on its AR track over 6 frames, and a noise-only stack."""
    rng = np.random.default_rng(11)
    track = simulate_target(rng, GRID, 2.0, 0.3, 6)
    return simulate_frames(rng, GRID, 6, 100.0, track.cells), simulate_frames(rng, GRID, 6), track


def _settings(threshold: float) -> DetectSettings:
    return DetectSettings(detector={"sigma_a_mps2": 0.3}, decision={"threshold": threshold})


def test_a_strong_target_is_found_on_its_cells(stacks):
    strong, _, track = stacks
    det = run_detect(strong, _settings(20.0))
    assert isinstance(det, FrameDetection) and det.present and det.threshold == 20.0
    assert (det.best_track == track.cells).all(axis=1).sum() >= 5
    line = verdict(det)
    assert line.startswith(f"TARGET PRESENT: statistic {det.statistic:.3f} vs threshold 20.000 (given)")
    assert "6 frames of 12 x 40 cells" in line


def test_noise_alone_is_not_a_target(stacks):
    _, noise, _ = stacks
    det = run_detect(noise, _settings(20.0))
    assert not det.present and verdict(det).startswith("no target")


def test_files_and_run_write_what_the_cli_writes(stacks, tmp_path, capsys):
    strong, _, _ = stacks
    np.save(tmp_path / "f.npy", strong)
    assert main(["detect", "--frames", str(tmp_path / "f.npy"), "--threshold", "20", "--sigma-a", "0.3",
                 "--out", str(tmp_path / "cli")]) == 0
    assert verdict(run_detect(strong, _settings(20.0))) in capsys.readouterr().out
    path = write_detection(run_detect(read_frames_file(tmp_path / "f.npy"), _settings(20.0)), tmp_path)
    assert path.name == CSV_NAME and path.read_bytes() == (tmp_path / "cli" / CSV_NAME).read_bytes()
