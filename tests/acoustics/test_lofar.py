"""Narrowband (LOFAR) processing (acoustics/lofar.py): the line threshold's false-alarm rate on noise spectra,
the normalisers against hand cases, and a quiet target's tonal found after integration where its broadband
statistic stays below the front end's threshold."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.beamforming import BeamformerSettings, bearing_time_record
from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.lofar import (
    LofarSettings,
    background,
    beam_power_spectra,
    detect_lines,
    integrate,
    line_threshold,
    lofar_gram,
)

ARRAY = LineArray(16, 2.5, 1500.0)
FS = 2000.0


def test_mean_normaliser_hand_case():
    """Split-window mean with gap 1 and 2 reference bins: bin 5 of [0..9] averages bins 2, 3, 7, 8."""
    p = np.arange(10.0)
    s = LofarSettings(normaliser="mean", gap_bins=1, reference_bins=2)
    assert background(p, s)[5] == pytest.approx((2 + 3 + 7 + 8) / 4)
    assert background(p, s)[0] == pytest.approx((2 + 3) / 2)  # at the edge: the one side there is


def test_two_pass_censors_a_neighbouring_line():
    p = np.ones(64)
    p[30] = 100.0  # a strong line in bin 40's reference window
    mean = background(p, LofarSettings(normaliser="mean", gap_bins=2, reference_bins=8))
    two = background(p, LofarSettings(normaliser="two-pass", gap_bins=2, reference_bins=8))
    assert mean[36] > 5.0 and two[36] == pytest.approx(1.0)


@pytest.mark.parametrize("normaliser,tol", [("mean", 1.3), ("two-pass", 1.5), ("median", 2.0)])
def test_false_alarm_rate_on_noise_spectra(normaliser, tol):
    """Independent exponential bins averaged over L windows (Gamma(L, 1/L) times a sloping background): the share
    of bins at or above the threshold is pfa (F(2L, 2LR) exact for the mean; the others measured here)."""
    rng = np.random.default_rng(0)
    s = LofarSettings(normaliser=normaliser, integration=8, pfa=1e-2, gap_bins=0, reference_bins=16)
    shape = np.linspace(1.0, 4.0, 400)
    p = integrate(rng.exponential(1.0, (8 * 500, 400)) * shape, 8)  # 500 periods x 400 bins
    z = p / background(p, s)
    rate = np.mean(z[:, 40:-40] >= line_threshold(s))
    assert 1e-2 / tol < rate < 1e-2 * tol, rate


def _quiet_target_record(seconds, cone_deg, rng):
    """16 channels at 2 kHz (Pa): ambient noise of PSD NL = 73 dB re 1 uPa^2/Hz independent between elements, a
    broadband plane wave 20 dB below NL per element (-8 dB after the 12 dB array gain) and a 200 Hz tonal of
    received level 140 - 74 = 66 dB re 1 uPa^2 (source 140 dB, spherical spreading over 5 km)."""
    m = int(seconds * FS)
    nl_pa2_hz = 10 ** (73 / 10) * 1e-12
    x = np.sqrt(nl_pa2_hz * FS / 2) * rng.standard_normal((16, m))
    f = np.fft.rfftfreq(m, 1 / FS)
    tau = (np.arange(16) - 7.5) * ARRAY.spacing_m * np.cos(np.deg2rad(cone_deg)) / ARRAY.sound_speed_mps
    bb = np.fft.rfft(np.sqrt(0.01 * nl_pa2_hz * FS / 2) * rng.standard_normal(m))
    x += np.fft.irfft(bb[None] * np.exp(-2j * np.pi * f[None] * tau[:, None]), m, axis=1)
    t = np.arange(m) / FS
    a_tonal = np.sqrt(2 * 10 ** (66 / 10) * 1e-12)
    x += a_tonal * np.cos(2 * np.pi * 200.0 * (t[None] - tau[:, None]) + 0.4)
    return x


def test_quiet_tonal_found_by_lofar_not_by_broadband():
    rng = np.random.default_rng(5)
    cone = 70.0
    x = _quiet_target_record(128.0, cone, rng)
    blocks = [x[:, k * 2000:(k + 1) * 2000] for k in range(128)]
    fe = BeamformerSettings(band_hz=[150.0, 300.0])  # the octave below aliasing, threshold 4, 1 s windows
    btr = bearing_time_record(iter(blocks), FS, ARRAY, fe)
    z_target = btr.level[:, int(round(cone))]
    assert np.mean(z_target >= fe.threshold) < 0.25  # the broadband statistic: below threshold in most windows
    s = LofarSettings(integration=32)
    gram = lofar_gram(iter(blocks), FS, ARRAY, s, window_s=1.0)
    lines = detect_lines(gram, s)
    hit = (np.abs(lines.frequency_hz - 200.0) <= 1.0) & (np.abs(lines.cone_deg - cone) <= ARRAY.beamwidth_deg(200.0))
    assert len(np.unique(lines.time_s[hit])) == 4  # found in every one of the 4 periods of 32 s
    # expected line SNR on its beam: tonal PSD (66 dB over the Hann ENBW 1.5 Hz, array gain 16) over the beam's
    # background (NL / 16 + the broadband target's NL / 100): 10 log10(10^-0.7 16 / 1.5 / 1.16) = 2.6 dB
    assert np.mean(lines.snr_db[hit]) == pytest.approx(2.6, abs=1.5)
    # one window alone (no integration) at the same pfa misses it in most windows
    s1 = LofarSettings(integration=1)
    lines1 = detect_lines(lofar_gram(iter(blocks), FS, ARRAY, s1, window_s=1.0), s1)
    hit1 = (np.abs(lines1.frequency_hz - 200.0) <= 1.0) & (np.abs(lines1.cone_deg - cone) <= 10.0)
    assert len(np.unique(lines1.time_s[hit1])) < 0.5 * 128
    # false lines: about pfa per cell (cells = periods x beams x bins, less the peak picking), allow 3x + 2
    n_cells = gram.statistic.size
    assert np.sum(~hit) <= 3 * s.pfa * n_cells + 2


def test_beam_spectrum_of_a_tone_on_its_beam():
    """A unit-power tone on a bin, from the beam's own direction, with no noise: the beam PSD at that bin is
    power / (ENBW) with the Hann window's equivalent noise bandwidth 1.5 fs / M."""
    m, f0 = 2000, 200.0
    t = np.arange(m) / FS
    tau = (np.arange(16) - 7.5) * ARRAY.spacing_m * np.cos(np.deg2rad(40.0)) / ARRAY.sound_speed_mps
    x = np.sqrt(2.0) * np.cos(2 * np.pi * f0 * (t[None] - tau[:, None]))
    f, p = beam_power_spectra(x[None], FS, ARRAY, np.array([40.0, 140.0]), [150.0, 250.0])
    k = np.argmin(np.abs(f - f0))
    assert p[0, 0, k] == pytest.approx(1.0 / (1.5 * FS / m), rel=1e-9)
    assert p[0, 1, k] < 0.1 * p[0, 0, k]


def test_sidelobe_guard_drops_a_weaker_copy_of_a_line():
    """Two beams hold a line at the same bin; the second's power over its background is 20 dB below the first's:
    it is a sidelobe (guard 12 dB) and is dropped; at 6 dB below it is kept (two sources)."""
    from sonartrack.acoustics.lofar import LofarGram

    f = np.arange(40.0)
    for below_db, kept in ((20.0, 1), (6.0, 2)):
        power = np.ones((1, 3, 40))
        power[0, 0, 20] = 1.0 + 1000.0
        power[0, 2, 20] = 1.0 + 1000.0 * 10 ** (-below_db / 10)
        stat = power.copy()  # background 1
        gram = LofarGram(np.array([8.0]), np.array([0.0, 90.0, 180.0]), f, power, stat)
        lines = detect_lines(gram, LofarSettings(integration=16))
        assert len(lines) == kept


def _noisy_blocks(n_windows, m=2000, seed=9):
    """Windows of the quiet-target record (a 200 Hz tonal at 70 deg in noise), m samples each."""
    x = _quiet_target_record(n_windows * m / FS, 70.0, np.random.default_rng(seed))
    return [x[:, k * m:(k + 1) * m] for k in range(n_windows)]


@pytest.mark.parametrize("method", ["cbf", "mvdr"])
def test_lofar_of_the_front_end_pass_equals_lofar_gram(method):
    """The gram the front end accumulates from its own rectangular spectra (the Hann window applied in frequency)
    against lofar_gram's windowed transforms of the same 37 windows: 2 whole periods of 16, the last 5 windows
    dropped by both; to rounding in double precision (float64 power), to float32's rounding in the gram."""
    blocks = _noisy_blocks(37)
    s = LofarSettings(integration=16, band_hz=[120.0, 330.0], beams=31)
    fe = BeamformerSettings(method=method, band_hz=[150.0, 300.0], fft_precision="double")
    btr = bearing_time_record(iter(blocks), FS, ARRAY, fe, narrowband=s)
    ref = lofar_gram(iter(blocks), FS, ARRAY, s, window_s=1.0)
    want = integrate(np.concatenate([beam_power_spectra(np.stack(blocks[i:i + 8]), FS, ARRAY, s.cone_deg,
                                                        s.band_hz)[1] for i in range(0, 32, 8)]), 16)
    assert btr.lofar is not None and btr.lofar.power.shape == ref.power.shape == want.shape == (2, 31, 210)
    from sonartrack.acoustics.lofar import LofarAccumulator

    acc = LofarAccumulator(FS, ARRAY, s, 2000)
    acc.add(np.fft.rfft(np.stack(blocks), axis=2)[:, :, acc.bins])
    np.testing.assert_allclose(acc.power(), want, rtol=1e-9)
    np.testing.assert_array_equal(btr.lofar.freqs_hz, ref.freqs_hz)
    np.testing.assert_allclose(btr.lofar.time_s, ref.time_s)
    np.testing.assert_allclose(btr.lofar.power, ref.power, rtol=3e-7)  # one float32 rounding apart at most
    np.testing.assert_allclose(btr.lofar.statistic, ref.statistic, rtol=3e-7)
    np.testing.assert_array_equal(btr.lofar.cone_deg, s.cone_deg)
    plain = bearing_time_record(iter(blocks), FS, ARRAY, fe)
    np.testing.assert_array_equal(btr.level, plain.level)  # the broadband record unchanged by the narrowband


def test_lofar_of_the_front_end_pass_in_single_precision_and_too_short():
    blocks = _noisy_blocks(20)
    s = LofarSettings(integration=16)
    single = bearing_time_record(iter(blocks), FS, ARRAY, BeamformerSettings(band_hz=[150.0, 300.0]), narrowband=s)
    ref = lofar_gram(iter(blocks), FS, ARRAY, s, window_s=1.0)
    np.testing.assert_allclose(single.lofar.statistic, ref.statistic, rtol=1e-5)  # float32 transforms: ~1e-6
    short = bearing_time_record(iter(blocks[:15]), FS, ARRAY, BeamformerSettings(), narrowband=s)
    assert short.lofar is None and short.level.shape[0] == 15  # no whole period: no gram, the record as ever
    assert bearing_time_record(iter(blocks), FS, ARRAY, BeamformerSettings()).lofar is None


@pytest.mark.parametrize("m", [2000, 1999])
def test_lofar_accumulator_up_to_half_the_sample_rate(m):
    """A band reaching fs / 2 (even window: the bin beyond the band is the Nyquist bin; odd window: the band's last
    bin is the last rfft bin, its neighbour the conjugate) against the windowed transforms, to rounding."""
    from sonartrack.acoustics.lofar import LofarAccumulator

    x = np.random.default_rng(4).standard_normal((3, 16, m))
    s = LofarSettings(integration=3, band_hz=[900.0, FS / 2], beams=7)
    acc = LofarAccumulator(FS, ARRAY, s, m)
    acc.add(np.fft.rfft(x, axis=2)[:, :, acc.bins])
    _, want = beam_power_spectra(x, FS, ARRAY, s.cone_deg, s.band_hz)
    np.testing.assert_allclose(acc.power(), want.mean(axis=0, keepdims=True), rtol=1e-9)


@pytest.mark.parametrize("bin_index,found", [(0, False), (4, False), (5, True), (34, True), (35, False), (39, False)])
def test_lines_at_the_band_edges_are_not_searched(bin_index, found):
    """A strong line in one beam: detected at bins edge_bins .. F - 1 - edge_bins (5 .. 34 of 40), not nearer the
    band's ends, where the background's reference is one-sided."""
    from sonartrack.acoustics.lofar import LofarGram

    power = np.ones((1, 3, 40))
    power[0, 1, bin_index] = 1000.0
    gram = LofarGram(np.array([8.0]), np.array([0.0, 90.0, 180.0]), np.arange(40.0), power, power.copy())
    lines = detect_lines(gram, LofarSettings(integration=16, edge_bins=5))
    assert len(lines) == int(found)
    if found:
        assert lines.frequency_hz[0] == bin_index and lines.beam[0] == 1


def test_line_detection_in_chunks_of_periods_is_the_whole_gram_at_once(monkeypatch):
    """detect_lines searches a long gram in chunks of periods (memory); every test it makes is within one period,
    so 150 periods in chunks of 64 give exactly the detections of one chunk of all 150."""
    import sonartrack.acoustics.lofar as lofar

    rng = np.random.default_rng(5)
    T, B, F = 150, 9, 80
    stat = rng.gamma(16, 1 / 16, size=(T, B, F)).astype(np.float32)
    stat[:, 4, 30] += 3.0  # a line on beam 4
    stat[100:, 2, 55] += 4.0  # another from period 100
    gram = lofar.LofarGram((np.arange(T) + 0.5) * 16.0, np.linspace(0, 180, B), np.arange(F) + 100.0,
                           (stat * 1e-3).astype(np.float32), stat)
    s = lofar.LofarSettings()
    chunked = lofar.detect_lines(gram, s)
    monkeypatch.setattr(lofar, "PERIODS_PER_CHUNK", 10_000)
    whole = lofar.detect_lines(gram, s)
    assert len(chunked) > T  # the two lines (and some noise) are found
    for f in ("time_s", "cone_deg", "frequency_hz", "statistic", "snr_db", "beam"):
        np.testing.assert_array_equal(getattr(chunked, f), getattr(whole, f))
