"""A CW contact's range-rate error (systems/active/cw_tracking.py ``cw_rate_sd_mps``) against hand-worked cases."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.matched_filter import Waveform
from sonartrack.systems.active.cw_tracking import cw_rate_sd_mps


@pytest.mark.parametrize("tau, pad, fc, want", [
    (1.0, 2, 1500.0, 1.0 / np.sqrt(12.0)),  # filters 0.5 Hz apart share the 1 Hz resolution cell: 1 m/s
    (1.0, 1, 1500.0, 1.0 / np.sqrt(12.0)),  # filters 1 Hz apart: the same cell
    (4.0, 2, 1500.0, 0.25 / np.sqrt(12.0)),  # a 4 s pulse resolves 0.25 Hz = 0.25 m/s at c = f_c
    (1.0, 2, 3000.0, 0.5 / np.sqrt(12.0)),  # 1 Hz at 3 kHz is 0.5 m/s
])
def test_cw_rate_error_is_the_resolution_cell_over_root_12(tau, pad, fc, want):
    assert cw_rate_sd_mps(Waveform("cw", tau, fc), 200.0, pad, 1500.0) == pytest.approx(want, rel=1e-9)


def test_an_lfm_measures_no_rate():
    assert cw_rate_sd_mps(Waveform("lfm", 1.0, 1500.0, 100.0), 200.0, 2, 1500.0) == 1.0
