"""Lobe images (detection/lobes.py) against hand-worked grating lobes and sidelobe envelopes."""

import numpy as np
import pytest

from sonartrack.acoustics.active_beams import cone_grid_deg
from sonartrack.detection.cells import PingCells, detect_ping
from sonartrack.detection.lobes import LobeBand, lobe_images


def _band(spacing_m: float, n: int = 8) -> LobeBand:
    # one frequency (2400 Hz, lambda 0.625 m), c 1500 m/s, images within 10 ms, 3 dB margin
    return LobeBand(n, spacing_m, 2400.0, 2400.0, 1500.0, 0.01, 3.0)


def _cone(u: float) -> float:
    return float(np.rad2deg(np.arccos(u)))


def test_grating_lobe_gain_is_one_and_sidelobe_follows_the_envelope():
    b = _band(0.5)  # lambda / d = 1.25: an echo at u = 0.8 has a grating lobe at u = 0.8 - 1.25 = -0.45
    assert b.gain(np.array(-0.45), np.array(0.8)) == pytest.approx(1.0)
    # u = 0.3: x = pi 0.5 2400 (0.3 - 0.8) / 1500 = -0.4 pi, envelope 1 / (8 sin(0.4 pi))^2
    assert b.gain(np.array(0.3), np.array(0.8)) == pytest.approx(1.0 / (8.0 * np.sin(0.4 * np.pi)) ** 2)
    # at d = 0.25 m (lambda / d = 2.5) u = -0.45 is a sidelobe: x = -pi / 2, envelope 1 / 64
    assert _band(0.25).gain(np.array(-0.45), np.array(0.8)) == pytest.approx(1.0 / 64.0)


def test_weaker_detection_at_a_grating_lobe_is_an_image_only_there():
    cone = [_cone(0.8), _cone(-0.45), _cone(0.3)]
    t, j = [5.0, 5.003, 5.0], [0, 0, 0]
    p = [100.0, 90.0, 50.0]
    assert lobe_images(cone, t, j, p, _band(0.5)).tolist() == [False, True, False]
    # below half a wavelength the same detection is no image (its power is far above the 1 / 64 sidelobe)
    assert lobe_images(cone, t, j, p, _band(0.25)).tolist() == [False, False, False]
    # another travel time or another Doppler: not the stronger echo's image
    assert not lobe_images(cone, [5.0, 5.5, 5.0], j, p, _band(0.5)).any()
    assert not lobe_images(cone, t, [0, 3, 0], p, _band(0.5)).any()
    # a weak detection in a sidelobe, below the envelope's prediction (100 x 0.0173 x 2): an image
    assert lobe_images(cone, t, j, [100.0, 0.5, 3.0], _band(0.5))[2]


def test_detect_ping_drops_the_grating_lobe_image_when_told_the_array():
    cone = cone_grid_deg(61)
    u = np.cos(np.deg2rad(cone))
    b0 = int(np.argmin(np.abs(u - 0.8)))
    b1 = int(np.argmin(np.abs(u - (u[b0] - 1.25))))  # the grating lobe of beam b0 at 0.5 m, 2400 Hz
    stat = np.ones((61, 40, 1), np.float32)
    stat[b0, 20, 0], stat[b1, 20, 0] = 400.0, 300.0
    args = (1, 0.0, cone, 1.0 + 0.01 * np.arange(40), np.zeros(1), np.full(1, np.nan), stat, False, None)
    assert len(detect_ping(PingCells(*args), 20.0)) == 2
    det = detect_ping(PingCells(*args, _band(0.5)), 20.0)
    assert det.beam.tolist() == [b0]
    assert len(detect_ping(PingCells(*args, _band(0.25)), 20.0)) == 2


def test_mftd_detections_lose_their_lobe_images_by_the_pings_power():
    from sonartrack.detection.cells import Detections
    from sonartrack.detection.ping_mftd import drop_lobe_images

    cone = cone_grid_deg(61)
    u = np.cos(np.deg2rad(cone))
    b0 = int(np.argmin(np.abs(u - 0.8)))
    b1 = int(np.argmin(np.abs(u - (u[b0] - 1.25))))
    stat = np.ones((61, 40, 1), np.float32)
    stat[b0, 20, 0], stat[b1, 20, 0] = 400.0, 300.0
    # the MFTD's statistic S ranks them the other way: the ping's power decides which is the image
    det = Detections(np.ones(2, np.int64), np.zeros(2), cone[[b0, b1]], np.array([1.2, 1.2]), np.full(2, np.nan),
                     np.full(2, np.nan), np.array([5.0, 9.0]), np.array([b0, b1]), np.array([20, 20]), np.zeros(2, int))
    args = (1, 0.0, cone, 1.0 + 0.01 * np.arange(40), np.zeros(1), np.full(1, np.nan), stat, False, None)
    assert drop_lobe_images(det, PingCells(*args, _band(0.5))).beam.tolist() == [b0]
    assert len(drop_lobe_images(det, PingCells(*args))) == 2
