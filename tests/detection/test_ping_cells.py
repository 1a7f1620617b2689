"""Single-ping detections of the active front end: the cone angle from the beams' power, not the normalised s."""

from dataclasses import replace

import numpy as np
import pytest

from sonartrack.acoustics.active_beams import beam_pattern, cone_grid_deg
from sonartrack.detection.cells import PingCells, detect_ping, power_cone_deg


def _cells(power, level):
    """One delay x one Doppler cell per beam in the middle of a quiet delay axis (s = power / level)."""
    n_b = len(power)
    stat = np.ones((n_b, 21, 1), np.float32) * 0.5
    lev = np.ones((n_b, 21, 1), np.float32)
    stat[:, 10, 0], lev[:, 10, 0] = power / level, level
    return PingCells(1, 0.0, cone_grid_deg(n_b), np.arange(21) * 0.01, np.zeros(1), np.full(1, np.nan), stat, False,
                     lev)


@pytest.mark.parametrize("true_cone", [150.0, 160.0, 170.0])
def test_cone_comes_from_the_power_when_the_cfar_level_differs_across_beams(true_cone):
    cone = cone_grid_deg(61)
    # the beams' response to a plane wave from true_cone (16 elements, half a wavelength): the power across beams
    power = 1e3 * np.abs(beam_pattern(cone, true_cone, 16, 0.5, 1500.0, 1500.0)) ** 2 + 1.0
    # a CFAR level that tracks the echo's own leakage (range sidelobes in the reference cells), more of it in the
    # wider beams towards endfire (180 deg): s = power / level peaks 1-3 beams away from the echo, towards broadside
    # (at 170 deg: 162, as measured on the default scene)
    level = 1.0 + 0.01 * power * np.exp(cone / 180.0)
    cells = _cells(power, level)
    lobe = np.abs(cone - true_cone) <= 15.0
    s_peak = cone[lobe][np.argmax((power / level)[lobe])]
    b_s = int(np.nonzero(cone == s_peak)[0][0])
    assert abs(s_peak - true_cone) >= 3.0  # the normalised statistic alone would be a beam or more off
    assert power_cone_deg(cells, [b_s], [10], [0])[0] == pytest.approx(true_cone, abs=1.5)
    det = detect_ping(cells, 2.0)
    assert np.min(np.abs(det.cone_deg - true_cone)) <= 1.5
    # the same cells without the level: the cone of s's peak (what the chain reported before)
    no_level = replace(cells, level=None)
    assert power_cone_deg(no_level, [b_s], [10], [0])[0] == pytest.approx(s_peak, abs=1.5)


def test_search_stays_within_the_main_lobe():
    # two echoes at one delay, 40 deg apart: each detection keeps its own beam's power peak
    cone = cone_grid_deg(61)
    power = np.ones(61)
    power[20], power[33] = 100.0, 1000.0  # 60 and 99 deg
    cells = _cells(power, np.ones(61))
    out = power_cone_deg(cells, [20, 33], [10, 10], [0, 0])
    np.testing.assert_allclose(out, [cone[20], cone[33]], atol=1.6)
