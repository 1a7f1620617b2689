"""Hostile calibrations (io/calibration.py): values no recorder has are refused in one line naming the range and
the unit, and levels outside any sea are flagged with the likely cause.

Before: a full scale of 1e-300 V gave pressures whose squares underflow (levels -inf, beam powers 0, "no target"),
1e300 V squares that overflow (NaN), and 1000 V (millivolts given as volts) levels 60 dB high without a word."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.calibration import (
    FULL_SCALE_RANGE_V,
    PLAUSIBLE_LEVEL_DB,
    Calibration,
    level_warnings,
    read_calibration,
    rms_level_db,
)


@pytest.mark.parametrize("value", ["1e-300", "1e300", "1000", "inf", "nan", "-2.5", "0"])
@pytest.mark.parametrize("form", ["toml", "csv"])
def test_implausible_full_scales_are_refused(tmp_path, value, form):
    if form == "toml":
        (tmp_path / "c.toml").write_text(f"sensitivity_db = -165.0\ngain_db = 20.0\nfull_scale_v = {value}\n")
    else:
        rows = f"0,-165,20,{value}\n1,-165,20,1\n"
        (tmp_path / "c.csv").write_text("channel,sensitivity_db,gain_db,full_scale_v\n" + rows)
    with pytest.raises(InputError) as e:
        read_calibration(tmp_path / f"c.{form}")
    msg = str(e.value)
    assert "\n" not in msg and f"c.{form}" in msg
    assert "full_scale_v" in msg or "NaN/inf" in msg, msg
    if value in ("1e-300", "1e300", "1000"):
        assert f"{FULL_SCALE_RANGE_V[0]:g}..{FULL_SCALE_RANGE_V[1]:g} V" in msg, msg


def test_plausible_full_scales_are_taken(tmp_path):
    """A recorder's 2.5 V, a DAQ's 10 V, float samples in mV (1e-3) and in uV (1e-6): sample 1.0 is that voltage."""
    for v in (2.5, 10.0, 1e-3, 1e-6, 100.0):
        (tmp_path / "c.toml").write_text(f"sensitivity_db = -180.0\nfull_scale_v = {v}\n")
        # S = -180 dB re 1 V/uPa is 1 mV/Pa: sample 1.0 = v volts = 1000 v pascals
        assert read_calibration(tmp_path / "c.toml").pa_per_unit(1)[0] == pytest.approx(1000.0 * v, rel=1e-12)


def _levels(pressure_rms_pa: float, windows: int = 50) -> np.ndarray:
    """Window levels (dB re 1 uPa) of white noise of the given rms pressure, as the chain measures them."""
    x = np.random.default_rng(3).standard_normal((windows, 4, 400)) * pressure_rms_pa
    return np.array([rms_level_db(b).mean() for b in x])


def _calibration(tmp_path, text: str) -> Calibration:
    (tmp_path / "c.toml").write_text(text)
    return read_calibration(tmp_path / "c.toml")


def test_levels_outside_any_sea_are_flagged_with_the_likely_cause(tmp_path):
    """A recorder storing 1e-3 full scale rms of sea noise behind S = -170 dB re 1 V/uPa, G = 20 dB, V_fs = 2.5 V:
    p = 1e-3 x 2.5 V / 10^(-150/20) V/uPa = 7.9e4 uPa, 98 dB. A sensitivity entered 100 dB too low (-270 is out
    of range; -250 with the gain left out is not) puts the same samples at 218 dB."""
    samples = _levels(1e-3)
    right = _calibration(tmp_path, "sensitivity_db = -170.0\ngain_db = 20.0\nfull_scale_v = 2.5\n")
    level = right.pa_per_unit(1)[0] * 1e-3
    assert 20 * np.log10(level / 1e-6) == pytest.approx(98.0, abs=0.1)
    assert level_warnings(samples + 20 * np.log10(right.pa_per_unit(1)[0]), right, "rec.wav") == []

    wrong = _calibration(tmp_path, "sensitivity_db = -250.0\nfull_scale_v = 2.5\n")
    db = samples + 20 * np.log10(wrong.pa_per_unit(1)[0])
    assert np.median(db) > PLAUSIBLE_LEVEL_DB[1]
    [line] = level_warnings(db, wrong, "rec.wav")
    assert line.startswith("warning: rec.wav") and "above any sea" in line and "calibration" in line, line
    assert f"{np.median(db):.1f} dB re 1 uPa" in line

    low = _calibration(tmp_path, "sensitivity_db = -100.0\ngain_db = 100.0\nfull_scale_v = 1e-5\n")
    [line] = level_warnings(samples + 20 * np.log10(low.pa_per_unit(1)[0]), low, "rec.wav")
    assert "below any sea" in line and "full_scale_v" in line, line


def test_uncalibrated_samples_outside_any_sea_name_the_missing_calibration():
    """Samples stored in micropascals read as pascals: 120 dB too high."""
    upa = _levels(1e-3) + 120.0
    [line] = level_warnings(upa, Calibration.identity(), "rec.wav")
    assert "no calibration was given" in line and "--calibration" in line, line
    assert level_warnings(_levels(1e-3), Calibration.identity(), "rec.wav") == []  # 60 dB: a pascal recording


def test_gaps_and_silence_are_left_out_of_the_median():
    """NaN (a gap) and -inf (digital silence) are no level: the median is of the windows with one."""
    level = np.r_[np.full(30, np.nan), np.full(30, -np.inf), np.full(10, 100.0)]
    assert level_warnings(level, Calibration.identity(), "rec.wav") == []
    assert level_warnings(np.full(5, np.nan), Calibration.identity(), "rec.wav") == []
    assert len(level_warnings(np.r_[np.full(30, -np.inf), np.full(10, 300.0)], Calibration.identity(), "r")) == 1
