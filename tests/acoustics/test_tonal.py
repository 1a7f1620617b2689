"""Tonal line on a beam (acoustics/tonal.py): frequency, array gain, steering, drift, no-tonal, memory."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.tonal import (
    TonalAccumulator,
    TonalSettings,
    beam_spectra,
    pick_line,
    spectral_peaks,
)
from sonartrack.acoustics.tonal_spectra import _hann_bias_table

FS = 4000.0
N_EL = 16
D_M = 2.5
C = 1500.0
ARRAY = LineArray(N_EL, D_M, C)


def _delays_s(cone_deg: float, n_el: int = N_EL) -> np.ndarray:
    """tau_n = -s_n cos(theta) / c, s_n = ((N - 1)/2 - n) d (the array convention of sim/array_signals.py)."""
    s = ((n_el - 1) / 2.0 - np.arange(n_el)) * D_M
    return -s * np.cos(np.deg2rad(cone_deg)) / C


def _window(rng, k: int, *, tone_hz=None, tone_snr_db=0.0, cone_deg=70.0, n_el=N_EL, broadband_snr_db=None,
            drift_hz_per_s=0.0, phase0=0.0):
    """Window k (1 s): a plane-wave tone (and/or plane-wave broadband noise) from ``cone_deg`` in white noise.

    Ambient: unit one-sided PSD per element (variance fs/2); the tone's power is tone_snr_db above it in 1 Hz.
    Tone phase 2 pi (f0 t + rate t^2 / 2), continuous across windows (t = absolute time)."""
    t = k + np.arange(int(FS)) / FS
    x = rng.standard_normal((n_el, t.size)) * np.sqrt(FS / 2.0)
    tau = _delays_s(cone_deg, n_el)[:, None]
    if tone_hz is not None:
        amp = np.sqrt(2.0 * 10.0 ** (tone_snr_db / 10.0))
        tt = t[None, :] - tau
        x += amp * np.cos(2.0 * np.pi * (tone_hz * tt + 0.5 * drift_hz_per_s * tt**2) + phase0)
    if broadband_snr_db is not None:
        f = np.fft.rfftfreq(t.size, 1.0 / FS)
        src = np.fft.rfft(rng.standard_normal(t.size) * np.sqrt(FS / 2.0 * 10.0 ** (broadband_snr_db / 10.0)))
        x += np.fft.irfft(src[None, :] * np.exp(-2j * np.pi * f[None, :] * tau), t.size, axis=1)
    return x


def _accumulate(settings, n_windows, cone_deg, seed=1, **kw):
    rng = np.random.default_rng(seed)
    acc = None
    for k in range(n_windows):
        f, p = beam_spectra(_window(rng, k, **kw), FS, ARRAY, [cone_deg], settings)
        acc = acc or TonalAccumulator(settings, f.size)
        acc.add(k + 0.5, p[0], f)
    return acc


def test_hann_parabola_bias_is_removed():
    s = TonalSettings()
    t = np.arange(int(FS)) / FS
    errors = []
    for f0 in 123.0 + np.linspace(0.0, 0.5, 11):
        f, p = beam_spectra(np.cos(2 * np.pi * f0 * t)[None], FS, ARRAY, [90.0], s)
        errors.append(spectral_peaks(p[0], f, s, max_peaks=1)[0][0] - f0)
    assert np.max(np.abs(errors)) < 1e-3
    table_hat, table_true = _hann_bias_table()
    assert np.max(np.abs(table_hat - table_true)) > 0.01  # the bias corrected is real at the 0.01-bin level


@pytest.mark.parametrize("band_hz,m", [([100.0, 400.0], 4000), ([0.0, 2000.0], 4000), ([0.0, 2000.0], 3999)])
def test_beam_spectra_matches_loop_over_bins_and_psd_scale(band_hz, m):
    """Against the windowed transform written out (the window applied in time), summed over the elements for each
    beam and bin: inside the band (the window applied in frequency) and a band from 0 Hz to fs / 2 with even and odd
    window lengths (the edge bins)."""
    s = TonalSettings(band_hz=band_hz)
    rng = np.random.default_rng(3)
    x = rng.standard_normal((N_EL, m))
    cones = [20.0, 70.0, 135.0]
    f, p = beam_spectra(x, FS, ARRAY, cones, s)
    w = np.hanning(m + 1)[:-1]  # periodic Hann
    spec = np.fft.rfft(x * w, axis=1)
    fall = np.fft.rfftfreq(m, 1.0 / FS)
    assert f.size == np.sum((fall >= band_hz[0]) & (fall <= band_hz[1]))
    for j, cone in enumerate(cones):
        for i in (0, 1, 57, f.size - 2, f.size - 1):
            b = int(np.flatnonzero(fall == f[i])[0])
            beam = np.mean(np.exp(2j * np.pi * fall[b] * _delays_s(cone)) * spec[:, b])
            assert p[j, i] == pytest.approx(2.0 * abs(beam) ** 2 / (FS * np.sum(w**2)), rel=1e-9)
    _, p1 = beam_spectra(x[:1], FS, ARRAY, [90.0], s)
    assert np.mean(p1[0, 1:-1]) == pytest.approx(2.0 / FS, rel=0.1)  # white noise, variance 1: one-sided PSD 2 / fs


def test_plane_wave_tonal_frequency_and_array_gain():
    s = TonalSettings()
    acc = _accumulate(s, 40, 70.0, tone_hz=123.4, tone_snr_db=10.0)
    r = acc.result()
    assert r is not None
    assert abs(r.line_hz - 123.4) < 0.02
    good = np.isfinite(r.frequency_hz)
    assert good.mean() > 0.95
    assert abs(np.median(r.frequency_hz[good]) - 123.4) < 0.02
    assert 0.005 <= r.sigma_hz < 0.1
    # array gain: the tonal SNR (line power over background, both from the mean spectrum) of the beam at
    # 70 deg vs that of one element (averaged over the 16 elements' own spectra: less noisy)
    rng = np.random.default_rng(5)
    beam, element = 0.0, 0.0
    for k in range(20):
        x = _window(rng, k, tone_hz=123.4, tone_snr_db=10.0)
        f, p = beam_spectra(x, FS, ARRAY, [70.0], s)
        beam = beam + p[0]
        element = element + sum(beam_spectra(row[None], FS, ARRAY, [90.0], s)[1][0] for row in x)
    gain_db = 10 * np.log10(_tonal_snr(beam, f, 123.4) / _tonal_snr(element, f, 123.4))
    assert gain_db == pytest.approx(10 * np.log10(N_EL), abs=1.0)


def _tonal_snr(mean_power, f, tone_hz):
    """Line power (the excess summed over +-3 bins) over the background PSD (median of 110-140 Hz off the line)."""
    background = np.median(mean_power[(f > 110) & (f < 140) & (np.abs(f - tone_hz) > 3)])
    return np.sum(mean_power[np.abs(f - tone_hz) <= 3] - background) / background


def test_wrong_steering_loses_the_line():
    s = TonalSettings()
    on = _accumulate(s, 60, 70.0, tone_hz=123.4, tone_snr_db=0.0).result()
    off = _accumulate(s, 60, 20.0, tone_hz=123.4, tone_snr_db=0.0).result()
    assert on is not None and abs(on.line_hz - 123.4) < 0.1
    assert off is None or abs(off.line_hz - 123.4) > 2.0


def test_drifting_line_is_followed():
    s = TonalSettings(tolerance_hz=0.3)  # narrower than the drift's half-range: the follower must track it
    n, rate = 300, 0.8 / 300.0
    acc = _accumulate(s, n, 70.0, n_el=4, tone_hz=120.0, tone_snr_db=12.0, drift_hz_per_s=rate)
    r = acc.result()
    assert r is not None
    truth = 120.0 + rate * r.time_s
    good = np.isfinite(r.frequency_hz)
    assert good.mean() > 0.9
    assert good[:20].mean() > 0.8 and good[-20:].mean() > 0.8  # both ends, 0.4 Hz from the mean line
    err = r.frequency_hz[good] - truth[good]
    assert np.sqrt(np.mean(err**2)) < 0.1
    assert r.sigma_hz == pytest.approx(np.sqrt(np.mean(err**2)), rel=0.35)  # sigma measured from the data


def test_broadband_target_without_tonal_gives_none():
    s = TonalSettings()
    assert _accumulate(s, 100, 70.0, n_el=4, broadband_snr_db=3.0).result() is None
    with_tonal = _accumulate(s, 100, 70.0, n_el=4, broadband_snr_db=3.0, tone_hz=300.3, tone_snr_db=10.0)
    assert with_tonal.result() is not None
    assert TonalAccumulator(s, 100).result() is None


def test_leaked_line_belongs_to_the_louder_beam():
    s = TonalSettings()
    f = np.arange(50.0, 200.0)
    quiet = np.ones_like(f)
    quiet[70] = 3.0  # 120 Hz leaked here (excess 2)
    quiet[120] = 2.5  # its own, weaker line at 170 Hz (excess 1.5)
    loud = 4.0 * np.ones_like(f)
    loud[70] = 40.0  # the 120 Hz source's beam: excess 36
    assert pick_line(quiet, f, s)[0] == pytest.approx(120.0, abs=0.01)
    assert pick_line(quiet, f, s, other_powers=loud[None])[0] == pytest.approx(170.0, abs=0.01)


def test_memory_is_a_few_floats_per_window():
    s = TonalSettings(max_candidates=8)
    rng = np.random.default_rng(0)
    f = np.arange(50.0, 1001.0)
    acc = TonalAccumulator(s, f.size)
    sizes = []
    for k in range(400):
        acc.add(float(k), rng.exponential(size=f.size), f)
        if k in (99, 399):
            sizes.append(acc.state_nbytes())
    per_window = (sizes[1] - sizes[0]) / 300
    assert per_window == 8 * (1 + s.max_candidates)
    assert acc.mean_spectrum().shape == (f.size,)
    arrays = [v for v in vars(acc).values() if isinstance(v, np.ndarray)]
    # mean spectrum, its frequencies and the few provisional lines
    assert sum(a.nbytes for a in arrays) <= 2 * 8 * f.size + 8 * s.provisional_lines


def test_weak_line_keeps_a_candidate_slot_among_stronger_peaks():
    """Each window has 5 strong peaks at random bins and a weaker steady line: with 3 candidate slots, the
    line is kept only through the slot reserved for the mean spectrum's provisional line."""
    s = TonalSettings(max_candidates=3, provisional_lines=1)
    rng = np.random.default_rng(2)
    f = np.arange(50.0, 1001.0)
    acc = TonalAccumulator(s, f.size)
    for k in range(200):
        power = np.ones(f.size)
        power[100] = 4.0  # the line at 150 Hz, 6 dB
        power[rng.choice(np.r_[10:90, 110:940], 5, replace=False)] = 20.0  # 13 dB, elsewhere each window
        acc.add(float(k), power, f)
    r = acc.result()
    assert r is not None and r.line_hz == pytest.approx(150.0, abs=0.01)
    assert np.isfinite(r.frequency_hz).mean() > 0.9


def test_settings_refuse_an_inverted_band():
    with pytest.raises(ValueError, match="band_hz"):
        TonalSettings(band_hz=[500.0, 100.0])
