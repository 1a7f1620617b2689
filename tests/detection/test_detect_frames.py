"""detect_frames (the library behind ``sonartrack detect``): normalisation, threshold, decision, best track."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.detection.detect import DetectSettings, detect_frames
from sonartrack.detection.mftd import MftdDetector, MftdSettings
from sonartrack.detection.normalise import NOISE_MEDIAN, normalise_frames, normalise_to_noise_median
from sonartrack.detection.threshold import ThresholdSettings, calibrate_threshold, decision_threshold
from sonartrack.models.range_doppler import CwPlaneSettings, RangeDopplerGrid
from sonartrack.sim.range_doppler import simulate_frames, simulate_target

GRID = RangeDopplerGrid.cw(8, 24, 0.125, 30e3, 1500.0)


def test_median_normalisation_hits_the_noise_median_and_removes_the_gain():
    rng = np.random.default_rng(1)
    y = simulate_frames(rng, GRID, 4)
    z = normalise_to_noise_median(y * 37.0)
    assert np.median(z) == pytest.approx(2.0 * np.log(2.0), rel=1e-12) == NOISE_MEDIAN
    np.testing.assert_allclose(z, normalise_to_noise_median(y), rtol=1e-12)
    np.testing.assert_array_equal(normalise_frames(y, "none"), y)
    with pytest.raises(InputError, match="median cell value is 0"):
        normalise_to_noise_median(np.zeros((2, 3, 3)))
    with pytest.raises(InputError, match="normalisation must be one of"):
        normalise_frames(y, "mean")


def test_calibrated_threshold_keeps_the_false_alarm_budget_on_fresh_noise():
    det = MftdDetector(GRID, MftdSettings(n_tracks=3))
    shape = (3, GRID.n_range, GRID.n_doppler)
    t = calibrate_threshold(det, shape, 0.1, 200, seed=5)
    assert t == calibrate_threshold(det, shape, 0.1, 200, seed=5)  # seeded: reproducible
    rng = np.random.default_rng(99)
    fresh = np.array([det.detect(simulate_frames(rng, GRID, 3)).statistic for _ in range(300)])
    # true Pfa ~ 0.1; 300 fresh stacks: the exceedance rate lies well inside (0.03, 0.2)
    assert 0.03 < np.mean(fresh > t) < 0.2
    assert decision_threshold(det, shape, ThresholdSettings(threshold=1.5)) == (1.5, "given")
    with pytest.raises(InputError, match="calibration trials"):
        calibrate_threshold(det, shape, 1e-3, 100, seed=0)


def test_detect_frames_is_the_detector_plus_a_threshold():
    rng = np.random.default_rng(3)
    track = simulate_target(rng, GRID, 2.0, 0.5, 5)
    y = simulate_frames(rng, GRID, 5, 30.0, track.cells) * 4.0
    s = DetectSettings(detector=MftdSettings(sigma_a_mps2=0.5), decision=ThresholdSettings(threshold=0.0))
    det = detect_frames(y, s)
    direct = MftdDetector(GRID, s.detector).detect(normalise_to_noise_median(y))
    assert det.statistic == direct.statistic and det.present == (direct.statistic > 0.0)
    assert det.grid == GRID and det.threshold_source == "given"
    np.testing.assert_array_equal(det.best_track, direct.tracks[0])
    table = det.best_track_table()
    assert list(table["frame"]) == [1, 2, 3, 4, 5]
    np.testing.assert_array_equal(table["cell_value"], det.frames[np.arange(5), det.best_track[:, 0],
                                                                 det.best_track[:, 1]])
    np.testing.assert_allclose(table["range_m"], GRID.range_centres_m()[det.best_track[:, 0]])
    assert (det.best_track == track.cells).all(axis=1).sum() >= 4  # 15 dB echoes: the target's track


def test_plane_settings_build_the_cw_grid():
    p = CwPlaneSettings(range_min_m=100.0)
    g = p.grid(5, 6)
    assert g == RangeDopplerGrid.cw(5, 6, 0.125, 30e3, 1500.0, 100.0)
    assert g.range_rate_min_mps == pytest.approx(-3 * g.range_rate_cell_mps)  # centred on zero range-rate
    assert CwPlaneSettings(range_rate_min_mps=0.0).grid(5, 6).range_rate_min_mps == 0.0
