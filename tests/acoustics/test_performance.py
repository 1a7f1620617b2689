"""Performance against range (acoustics/performance.py): hand-worked TL lines, the settings declaration."""

import numpy as np
import pytest

from sonartrack.acoustics.performance import TLSettings, performance_summary, range_performance, tl_performance
from sonartrack.acoustics.transmission_loss import TLField
from sonartrack.core.errors import InputError


def spherical_field(rmax_m=20_000.0, dr_m=50.0):
    """TL = 20 log10 r at every depth: no interference, so the range average changes nothing."""
    r = np.arange(dr_m, rmax_m + dr_m / 2, dr_m)
    z = np.array([0.0, 50.0, 100.0])
    return TLField(r, z, np.tile(20 * np.log10(r), (3, 1)), 100.0, 30.0, "spherical")


def test_detection_range_of_spherical_spreading_by_hand():
    # the mean of 1/x^2 over [a, b] is 1/(a b). The 1 km window holds 20 samples 50 m apart, 10 before r and
    # 9 after, i.e. [r - 525, r + 475] (centred half a step early), so TL_avg = 10 log10((r - 25)^2 - 500^2) and
    # SNR = SL - TL_avg + DI - NL > 0  <=>  r < 25 + sqrt(10^((SL + DI - NL)/10) + 500^2) = 25 + sqrt(10^7.95 + 500^2)
    perf = range_performance(spherical_field(), 50.0, sl_db=140.0, di_db=12.5, nl_db=73.0, threshold_db=0.0)
    r_max = 25.0 + np.sqrt(10**7.95 + 500.0**2)  # 9479 m
    assert len(perf.detection_ranges_m) == 1
    start, end = perf.detection_ranges_m[0]
    assert start == 50.0 and r_max - 50.0 <= end < r_max
    assert perf.convergence_zones_m == []
    mid = slice(40, -40)  # away from the ends, where the window is padded
    r = perf.ranges_m[mid]
    np.testing.assert_allclose(perf.tl_avg_db[mid], 10 * np.log10((r - 25.0) ** 2 - 500.0**2), atol=0.01)
    np.testing.assert_allclose(perf.snr_db, 79.5 - perf.tl_avg_db)
    assert list(perf.columns()) == ["range_m", "tl_db", "tl_avg_db", "snr_db"]


def test_a_higher_threshold_shortens_the_range_by_its_decibels():
    # 6.02 dB more threshold = half the range under 20 log10 r
    a = range_performance(spherical_field(), 50.0, threshold_db=0.0).detection_ranges_m[0][1]
    b = range_performance(spherical_field(), 50.0, threshold_db=20 * np.log10(2)).detection_ranges_m[0][1]
    assert b == pytest.approx(a / 2, abs=100.0)


def test_receiver_outside_the_water_and_settings_refusals():
    with pytest.raises(InputError, match="receiver depth 120 m must lie inside"):
        range_performance(spherical_field(), 120.0)
    with pytest.raises(ValueError, match="kilometres, not metres"):
        TLSettings(rmax_km=8000.0)
    with pytest.raises(ValueError, match="extra"):
        TLSettings(frequency=100.0)  # a misspelt key is an error, not ignored
    s = TLSettings(source_depth_m=20.0)
    assert s.zr_m == 20.0 and TLSettings(source_depth_m=20.0, receiver_depth_m=35.0).zr_m == 35.0


def test_tl_performance_checks_the_receiver_before_computing_a_field():
    from sonartrack.acoustics.environment import load_environment

    env = load_environment("yellow-winter")  # 76 m deep
    with pytest.raises(InputError, match="receiver depth 90 m"):
        tl_performance(env, TLSettings(source_depth_m=30.0, receiver_depth_m=90.0), store=None)


def test_summary_line():
    s = TLSettings(freq_hz=100.0, source_depth_m=30.0, rmax_km=20.0)
    line = performance_summary("spherical", s, range_performance(spherical_field(), 30.0))
    assert line.startswith("tl spherical: 100 Hz, source 30 m, receiver 30 m, to 20 km; SNR > 0 dB")
    assert "at 0.1-9.4 km" in line
