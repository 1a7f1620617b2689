"""Tonal beams of float32 windows (single-precision transform and steering) and the running-median SNR of several
beams at once (acoustics/tonal.py), against the equations written out in double."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.tonal import (
    TonalAccumulator,
    TonalSettings,
    _median,
    _peak_bins,
    beam_spectra,
    spectral_peaks,
    window_peak_bins,
    window_snr_db,
)

FS = 8000.0
N_EL = 32
D_M = 1.25
C = 1500.0
ARRAY = LineArray(N_EL, D_M, C)


def _direct_beams(x: np.ndarray, cone_deg: np.ndarray, band_hz) -> tuple[np.ndarray, np.ndarray]:
    """P(f) = 2 |(1/N) sum_n exp(2 pi i f tau_n) rfft(hann x_n)(f)|^2 / (fs sum w^2), the Hann window applied in
    time and one steering matrix per beam (the module doc's equation, in double)."""
    n_el, n = x.shape
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)
    f = np.fft.rfftfreq(n, 1.0 / FS)
    keep = (f >= band_hz[0]) & (f <= band_hz[1])
    spec = np.fft.rfft(x.astype(float) * w, axis=1)[:, keep]
    s_n = ((n_el - 1) / 2.0 - np.arange(n_el)) * D_M
    tau = -np.cos(np.deg2rad(cone_deg))[:, None] * s_n[None, :] / C  # (k, N)
    steer = np.exp(2j * np.pi * f[keep][None, None, :] * tau[:, :, None])  # (k, N, F)
    beams = np.einsum("knf,nf->kf", steer, spec) / n_el
    return f[keep], 2.0 * np.abs(beams) ** 2 / (FS * np.sum(w**2))


def _window(rng, tone_hz: float, cone_deg: float) -> np.ndarray:
    """One second of a plane-wave tone (10 dB in 1 Hz) from ``cone_deg`` in unit-PSD white noise, as float32."""
    t = np.arange(int(FS)) / FS
    s_n = ((N_EL - 1) / 2.0 - np.arange(N_EL)) * D_M
    tau = (-s_n * np.cos(np.deg2rad(cone_deg)) / C)[:, None]
    x = rng.standard_normal((N_EL, t.size)) * np.sqrt(FS / 2.0)
    x += np.sqrt(2.0 * 10.0) * np.cos(2.0 * np.pi * tone_hz * (t[None, :] - tau))
    return x.astype(np.float32)


@pytest.mark.parametrize("band_hz", [[50.0, 1000.0], [0.0, 4000.0]])
def test_float32_beams_match_double_equation_to_rounding(band_hz):
    """A float32 window (the interleaved layout of a file's samples) gives the double equation's powers to a
    relative 1e-5 of each bin's power plus the band's median level (the beam's rounding is ~1e-6 of its magnitude,
    ~2e-6 on a power), and the tone's peak to 1e-5 Hz; the powers come back in double."""
    rng = np.random.default_rng(3)
    x = np.ascontiguousarray(_window(rng, 321.37, 63.0).T).T  # channels strided, as read from a wav file
    cones = np.array([63.0, 20.0, 150.0])
    s = TonalSettings(band_hz=band_hz)
    f, p = beam_spectra(x, FS, ARRAY, cones, s)
    f_ref, p_ref = _direct_beams(x, cones, band_hz)
    assert p.dtype == np.float64
    np.testing.assert_array_equal(f, f_ref)
    level = np.median(p_ref)
    assert np.max(np.abs(p - p_ref) / (p_ref + level)) < 1e-5
    assert np.max(np.abs(p - p_ref)) > 0.0  # the single-precision path is taken (double would agree to 1e-12)
    peak = spectral_peaks(p[0], f, s, max_peaks=1)[0][0]
    peak_ref = spectral_peaks(p_ref[0], f_ref, s, max_peaks=1)[0][0]
    assert abs(peak - peak_ref) < 1e-5
    assert abs(peak - 321.37) < 0.1


def test_float64_beams_stay_double():
    """A float64 window keeps the double transform: the equation's powers to 1e-10 of the median level."""
    rng = np.random.default_rng(4)
    x = _window(rng, 400.2, 100.0).astype(float) + 1e-3 * rng.standard_normal((N_EL, int(FS)))
    f, p = beam_spectra(x, FS, ARRAY, [100.0, 40.0], TonalSettings())
    _, p_ref = _direct_beams(x, np.array([100.0, 40.0]), [50.0, 1000.0])
    assert np.max(np.abs(p - p_ref)) < 1e-10 * np.median(p_ref)


def _running_median_brute(row: np.ndarray, width: int) -> np.ndarray:
    """Median of each bin's ``width`` neighbours, the row mirrored at its ends (d c b a | a b c d | d c b a)."""
    half = width // 2
    padded = np.concatenate((row[:half][::-1], row, row[::-1][:half]))
    return np.array([np.median(padded[i:i + width]) for i in range(row.size)])


@pytest.mark.parametrize("n_bins", [11, 12, 40, 953])
def test_window_snr_of_several_beams_is_each_beams_own(n_bins):
    """Rows filtered in one call give each row's own running median (brute force), zeros floored at the smallest
    float; background_hz = 20 Hz over 1-Hz bins is a 21-bin median."""
    rng = np.random.default_rng(5)
    p = rng.exponential(size=(4, n_bins))
    p[1, :3] = 0.0
    p[2] = 0.0
    tiny = np.finfo(float).tiny
    with np.errstate(over="ignore", divide="ignore"):
        snr = window_snr_db(p, 1.0, TonalSettings(background_hz=20.0))
        q = np.maximum(p, tiny)
        ref = np.array([10 * np.log10(r / np.maximum(_running_median_brute(r, 21), tiny)) for r in q])
    np.testing.assert_array_equal(snr, ref)


@pytest.mark.parametrize("levels", [0, 4])
def test_peaks_of_several_beams_are_each_beams_own(levels):
    """The batched peak search gives, per row, the bins and order of the one-row search (ties of equal SNR in
    bin order: ``levels`` quantises the powers to make ties and plateaus)."""
    rng = np.random.default_rng(7)
    p = rng.exponential(size=(5, 300))
    if levels:
        p = np.round(p * levels) / levels
    p[3] = 0.0
    s = TonalSettings(background_hz=20.0)
    with np.errstate(over="ignore", divide="ignore"):
        batched = window_peak_bins(p, 1.0, s, min_snr_db=1.0)
        single = [_peak_bins(np.maximum(row, np.finfo(float).tiny), 1.0, s, 1.0)[0] for row in p]
    assert sum(b.size for b in batched) > 50
    for b, one in zip(batched, single, strict=True):
        np.testing.assert_array_equal(b, one)


def test_peak_bins_by_hand():
    """Local maxima standing 3 dB above a flat background of 1, strongest first; the edge is not a peak
    (nor is the 2.8-dB bump), the plateau counts once (its first bin: p[k] > p[k-1] and p[k] >= p[k+1])."""
    p = np.ones((1, 41))
    p[0, [5, 20, 30]] = [4.0, 10.0, 1.9]
    p[0, 12:14] = 3.0
    p[0, 0] = 50.0
    got = window_peak_bins(p, 1.0, TonalSettings(background_hz=20.0), min_snr_db=3.0)[0]
    np.testing.assert_array_equal(got, [20, 5, 12])


def test_accumulator_with_peaks_found_for_several_beams_equals_its_own():
    """Handing add() the window's peaks (found with the other beams') changes nothing in the candidates."""
    rng = np.random.default_rng(6)
    s = TonalSettings()
    a, b = None, None
    for k in range(20):
        f, p = beam_spectra(_window(rng, 250.3 + 0.01 * k, 70.0), FS, ARRAY, [70.0, 30.0], s)
        peaks = window_peak_bins(p, f[1] - f[0], s)
        a = a or TonalAccumulator(s, f.size)
        b = b or TonalAccumulator(s, f.size)
        a.add(k + 0.5, p[0], f)
        b.add(k + 0.5, p[0], f, peak_bins=peaks[0])
    np.testing.assert_array_equal(np.asarray(a._candidates), np.asarray(b._candidates))
    ta, tb = a.result(), b.result()
    assert ta is not None and tb is not None
    assert abs(ta.line_hz - 250.4) < 0.2
    np.testing.assert_array_equal(ta.frequency_hz, tb.frequency_hz)


def test_follower_median_is_numpys():
    """The drift follower's median of its last few estimates equals np.median, odd and even counts (the middle
    pair's mean), to the bit."""
    rng = np.random.default_rng(9)
    for n in range(1, 7):
        for _ in range(50):
            v = list(rng.normal(100.0, 1.0, n))
            assert _median(v) == float(np.median(v))
    assert _median([3.0, 1.0, 2.0, 10.0]) == 2.5
