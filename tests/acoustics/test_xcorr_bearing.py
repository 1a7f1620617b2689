"""Cross-correlation bearings (paper P0): exact delays across 0-180 deg, multipath peaks, peak model, bad input."""

import numpy as np
import pytest

from sonartrack.acoustics.peak_fit import fit_peak_model
from sonartrack.acoustics.signals import Multipath, SourceSpec, simulate_two_channel
from sonartrack.acoustics.xcorr_bearing import (
    BearingSettings,
    bearings_from_recording,
    cone_angle_deg,
    estimate_peaks,
    peaks_summary,
    window_count,
)
from sonartrack.core.errors import InputError
from sonartrack.io.peaks import read_peaks_csv, write_peaks_csv
from sonartrack.sim.bearing_peaks import STRONG, WEAK, PeakModel, generate_scans

FS, D, C = 8000.0, 30.0, 1500.0


@pytest.mark.parametrize("theta", [0.0, 3.0, 10.0, 45.0, 90.0, 120.0, 170.0, 177.0, 180.0])
def test_noise_free_delay_gives_the_bearing(theta):
    x = simulate_two_channel(np.random.default_rng(1), duration_s=2.0, fs_hz=FS, spacing_m=D, sound_speed_mps=C,
                             sources=[SourceSpec(theta, 40.0)], noise_std=1e-3, band_hz=(50.0, 3000.0))
    rec = estimate_peaks(x, FS, D, C, threshold=15000)
    assert len(rec.time_s) == 2
    # delay error of the parabolic fit: a few hundredths of a sample; bearing error dtheta = c dD / (d sin theta)
    tau = D * np.cos(np.deg2rad(theta)) / C
    got_tau = D * np.cos(np.deg2rad(rec.bearing_deg)) / C
    assert np.all(np.abs(got_tau - tau) < 0.06 / FS)
    dc = 0.06 * C / (FS * D)  # the same delay tolerance as a change of cos(theta); steep near endfire
    tol = max(abs(np.rad2deg(np.arccos(np.clip(np.cos(np.deg2rad(theta)) + s * dc, -1, 1))) - theta) for s in (-1, 1))
    assert np.all(np.abs(rec.bearing_deg - theta) <= tol + 1e-9)


def test_multipath_gives_its_own_peak_where_geometry_says():
    x = simulate_two_channel(np.random.default_rng(2), duration_s=3.0, fs_hz=FS, spacing_m=D, sound_speed_mps=C,
                             sources=[SourceSpec(70.0, 20.0, (Multipath(0.03, 0.7, 25.0),))], noise_std=0.1,
                             band_hz=(100.0, 2000.0))
    rec = estimate_peaks(x, FS, D, C, threshold=3000)
    for _, b, a in rec.by_scan():
        assert np.min(np.abs(b - 70.0)) < 0.5 and np.min(np.abs(b - 95.0)) < 0.5
        assert a[np.argmin(np.abs(b - 70.0))] > a[np.argmin(np.abs(b - 95.0))]


def test_peak_generator_moments():
    rng = np.random.default_rng(3)
    model = PeakModel(amplitude_threshold=0.0)
    K = 4000
    scans = generate_scans(rng, model, np.full((K, 1), 90.0), [STRONG])
    n_false = np.array([np.sum(s.origin < 0) for s in scans])
    assert n_false.mean() == pytest.approx(model.false_rate / model.gate_deg * 180, rel=0.03)
    true = [s for s in scans if np.any(s.origin == 0)]
    b = np.array([s.bearing_deg[s.origin == 0][0] for s in true])
    a = np.array([s.amplitude[s.origin == 0][0] for s in true])
    assert b.std() == pytest.approx(STRONG.sigma_p_deg, rel=0.05) and abs(b.mean() - 90) < 0.1
    assert a.mean() == pytest.approx(STRONG.amplitude_mean, rel=0.01)
    assert a.std() == pytest.approx(STRONG.amplitude_sd, rel=0.05)
    fa = np.concatenate([s.amplitude[s.origin < 0] for s in scans])
    assert fa.mean() == pytest.approx(1 / model.false_amplitude_rate, rel=0.03)


def test_fitter_recovers_the_generator():
    rng = np.random.default_rng(4)
    model = PeakModel()
    K = 3000
    truth = np.column_stack([np.full(K, 50.0), np.full(K, 130.0)])
    scans = generate_scans(rng, model, truth, [STRONG, WEAK])
    fit = fit_peak_model([(s.bearing_deg, s.amplitude) for s in scans], truth, threshold=model.amplitude_threshold)
    assert fit.false_amplitude_rate == pytest.approx(model.false_amplitude_rate, rel=0.05)
    assert fit.false_rate == pytest.approx(model.false_rate, rel=0.1)
    np.testing.assert_allclose(fit.sigma_p_deg, [STRONG.sigma_p_deg, WEAK.sigma_p_deg], rtol=0.08)
    assert fit.amplitude_mean[0] == pytest.approx(STRONG.amplitude_mean, rel=0.03)
    # the weak track's amplitudes are truncated at the threshold: its mean is biased up a little
    assert fit.amplitude_mean[1] == pytest.approx(WEAK.amplitude_mean, rel=0.05)


def test_peaks_csv_round_trip_and_bad_files(tmp_path):
    rec = estimate_peaks(simulate_two_channel(np.random.default_rng(5), duration_s=2.0, fs_hz=FS, spacing_m=D,
                                              sources=[SourceSpec(60.0, 10.0)]), FS, D)
    p = write_peaks_csv(tmp_path / "p.csv", rec)
    back = read_peaks_csv(p)
    np.testing.assert_allclose(back.bearing_deg, rec.bearing_deg, rtol=1e-5)
    empty = tmp_path / "e.csv"
    empty.write_text("")
    with pytest.raises(InputError, match="empty"):
        read_peaks_csv(empty)
    hdr = tmp_path / "h.csv"
    hdr.write_text("time_s,bearing_deg,amplitude\n")
    with pytest.raises(InputError, match="no rows"):
        read_peaks_csv(hdr)
    rad = tmp_path / "r.csv"
    rad.write_text("time_s,bearing_deg,amplitude\n0,-1.2,9000\n")
    with pytest.raises(InputError, match="0..180"):
        read_peaks_csv(rad)
    with pytest.raises(InputError, match="spacing must be positive"):
        estimate_peaks(np.zeros((2, 8000)), FS, 0.0)


def test_cone_angle_and_window_count_by_hand():
    # tau = d cos(theta) / c: 0 -> broadside 90 deg, d/c -> endfire 0 deg, -d/(2c) -> 120 deg
    np.testing.assert_allclose(cone_angle_deg([0.0, D / C, -D / (2 * C), 2 * D / C], D, C), [90.0, 0.0, 120.0, 0.0])
    assert window_count(8000 * 3 + 7999, 8000.0, 1.0) == 3  # a partial last window is dropped
    assert window_count(8000, 8000.0, 0.5) == 2


def test_settings_face_gives_the_same_peaks_and_refuses_bad_values():
    x = simulate_two_channel(np.random.default_rng(6), duration_s=3.0, fs_hz=FS, spacing_m=D,
                             sources=[SourceSpec(75.0, 5.0)])
    s = BearingSettings(spacing_m=D, threshold=4000.0, max_peaks=3)
    a, b = bearings_from_recording(x, FS, s), estimate_peaks(x, FS, D, C, 1.0, 4000.0, 3)
    np.testing.assert_array_equal(a.bearing_deg, b.bearing_deg)
    assert np.max(np.unique(a.time_s, return_counts=True)[1]) <= 3
    assert peaks_summary(a, x.shape[1], FS, 1.0).startswith("3 windows of 1 s at 8000 Hz")
    with pytest.raises(ValueError, match="greater than 0"):
        BearingSettings(spacing_m=-1.0)
    with pytest.raises(InputError, match="shorter than one 5 s window"):
        estimate_peaks(x, FS, D, window_s=5.0)
