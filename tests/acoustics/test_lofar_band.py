"""The narrowband pass's default band (acoustics/lofar.py ``lofar_band``): low = max(floor, k c / L), L = (N - 1) d,
high = f_a = min(c / (2 d), fs / 2), hand-worked per array (k = 1.5)."""

import pytest

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.lofar import LofarSettings, lofar_band


@pytest.mark.parametrize(("elements", "spacing_m", "fs_hz", "want_hz"), [
    (64, 0.5, 16000.0, (2250 / 31.5, 1500.0)),  # 31.5 m aperture: 71.43 Hz, not f_a / 4 = 375 Hz
    (16, 2.5, 4000.0, (60.0, 300.0)),           # 37.5 m: 60 Hz (f_a / 4 would be 75 Hz)
    (8, 5.0, 2000.0, (2250 / 35, 150.0)),       # 35 m: 64.3 Hz, not 37.5 Hz (about one wavelength)
    (64, 5.0, 2000.0, (50.0, 150.0)),           # 315 m: k c / L = 7.1 Hz, the floor holds
    (32, 1.0, 1000.0, (2250 / 31, 500.0)),      # f_a = fs / 2 below c / (2 d) = 750 Hz
    (4, 0.5, 16000.0, (375.0, 1500.0)),         # 1.5 m: k c / L = 1500 Hz = f_a: the old [f_a / 4, f_a]
    (3, 0.5, 16000.0, (375.0, 1500.0)),         # 1.0 m: k c / L = 2250 Hz > f_a: the same fallback
])
def test_default_band_follows_aperture(elements, spacing_m, fs_hz, want_hz):
    got = lofar_band(LineArray(elements, spacing_m), fs_hz, LofarSettings())
    assert got == pytest.approx(want_hz, rel=1e-12)


def test_wavelengths_setting_scales_low_edge():
    s = LofarSettings(aperture_wavelengths=2.0)
    assert lofar_band(LineArray(64, 0.5), 16000.0, s) == pytest.approx((2.0 * 1500 / 31.5, 1500.0))


def test_set_band_is_kept():
    s = LofarSettings(band_hz=[120.0, 330.0])
    assert lofar_band(LineArray(16, 2.5), 4000.0, s) == (120.0, 330.0)
