"""Matched filters: LFM pulse compression (delay, gain = time-bandwidth product, -13 dB sidelobes, range-Doppler
coupling) and the CW Doppler filter bank (an echo at Doppler f_d in the right filter)."""

import numpy as np
import pytest

from sonartrack.acoustics.matched_filter import (
    Waveform,
    cw_doppler_bank,
    doppler_to_range_rate,
    fft_length,
    lfm_coupling_delay_s,
    pulse_compress,
    range_rate_to_doppler,
)
from sonartrack.core.errors import InputError

LFM = Waveform("lfm", 1.0, 1500.0, 100.0)


def compress(x: np.ndarray, w: Waveform, fs: float) -> np.ndarray:
    replica = w.replica(fs)
    n_fft = fft_length(x.shape[-1] + replica.size)
    return pulse_compress(np.fft.fft(x, n_fft, axis=-1), replica, x.shape[-1] - replica.size + 1)


def echo(w: Waveform, fs: float, m: int, delay_samples: int, doppler_hz: float = 0.0) -> np.ndarray:
    x = np.zeros(m, complex)
    s = w.replica(fs, doppler_hz)
    x[delay_samples: delay_samples + s.size] = s
    return x


def test_lfm_compresses_at_the_echo_delay():
    fs = 200.0
    z = compress(echo(LFM, fs, 3000, 1234), LFM, fs)
    assert int(np.argmax(np.abs(z))) == 1234
    # the peak is the pulse's energy E = tau fs (unit amplitude)
    assert np.abs(z[1234]) == pytest.approx(200.0, rel=1e-4)


def test_lfm_correlation_equals_direct_sum():
    fs = 200.0
    rng = np.random.default_rng(1)
    x = rng.standard_normal(600) + 1j * rng.standard_normal(600)
    z = compress(x, LFM, fs)
    s = LFM.replica(fs)
    direct = np.array([np.sum(x[d: d + s.size] * np.conj(s)) for d in range(z.size)])
    np.testing.assert_allclose(z, direct, rtol=1e-4, atol=1e-3)


def test_lfm_processing_gain_is_the_time_bandwidth_product():
    # SNR_out / SNR_in(in the pulse's band B) = tau B = 100 (module doc); noise output power by Monte Carlo
    fs, m = 200.0, 4000
    rng = np.random.default_rng(2)
    noise = (rng.standard_normal((40, m)) + 1j * rng.standard_normal((40, m))) / np.sqrt(2.0)  # variance 1
    out_noise = np.mean(np.abs(compress(noise, LFM, fs)) ** 2)
    peak = np.abs(compress(echo(LFM, fs, m, 500), LFM, fs)[500]) ** 2  # amplitude 1
    snr_in_band = 1.0 / (1.0 * 100.0 / fs)
    gain = (peak / out_noise) / snr_in_band
    assert gain == pytest.approx(LFM.duration_s * LFM.bandwidth_hz, rel=0.03)


def test_lfm_first_sidelobe_is_13_db_down():
    fs = 2000.0  # oversampled, to see the sinc's shape
    z = np.abs(compress(echo(LFM, fs, 6000, 2000), LFM, fs))
    level = 20 * np.log10(z / z.max())
    right = level[2000:2000 + 200]
    mins = np.nonzero((right[1:-1] < right[:-2]) & (right[1:-1] < right[2:]))[0] + 1
    first_lobe = right[mins[0]: mins[1]].max()
    assert -13.8 <= first_lobe <= -12.8
    # the first null is 1 / B after the peak
    assert mins[0] / fs == pytest.approx(1.0 / LFM.bandwidth_hz, abs=1.5 / fs)


@pytest.mark.parametrize("doppler", [-8.0, 5.0])
def test_lfm_range_doppler_coupling(doppler):
    fs = 200.0
    z = compress(echo(LFM, fs, 3000, 1000, doppler), LFM, fs)
    shift = lfm_coupling_delay_s(doppler, LFM)
    assert shift == pytest.approx(-doppler * 0.01)
    assert abs(int(np.argmax(np.abs(z))) - (1000 + shift * fs)) <= 1


@pytest.mark.parametrize("doppler", [-6.3, 0.0, 3.3, 9.7])
def test_cw_echo_peaks_in_its_doppler_filter(doppler):
    fs = 200.0
    cw = Waveform("cw", 1.0, 1500.0)
    x = echo(cw, fs, 2000, 700, doppler)
    z, delay, dop = cw_doppler_bank(x, fs, cw, 15.0, hop=50)
    i, j = np.unravel_index(np.argmax(np.abs(z)), z.shape)
    assert abs(dop[j] - doppler) <= 0.5 * (dop[1] - dop[0]) + 1e-9
    assert abs(delay[i] - 700 / fs) <= 0.5 * 50 / fs + 1e-9
    assert dop.min() >= -15.0 and dop.max() <= 15.0


def test_doppler_and_range_rate_are_inverse_and_closing_is_positive():
    # a closing target (total path shrinking) raises the frequency
    assert range_rate_to_doppler(-3.0, 1500.0, 1500.0) == pytest.approx(3.0)
    assert doppler_to_range_rate(range_rate_to_doppler(2.5, 1750.0, 1490.0), 1750.0, 1490.0) == pytest.approx(2.5)


def test_waveforms_the_chain_cannot_describe_are_refused():
    with pytest.raises(InputError, match="zero-bandwidth"):
        Waveform("lfm", 1.0, 1500.0, 0.0)
    with pytest.raises(InputError, match="lfm or cw"):
        Waveform("hfm", 1.0, 1500.0, 100.0)
    with pytest.raises(InputError, match="positive"):
        Waveform("cw", 0.0, 1500.0)


@pytest.mark.parametrize("hop, taper", [(50, "rect"), (37, "rect"), (50, "hann")])
def test_cw_bank_is_each_windows_dft_at_the_kept_frequencies(hop, taper):
    """The bank (block DFTs combined across a window's blocks, or one product) against each window's DFT written
    here: z(d, f) = sum_t w(t) x(d + t) exp(-2 pi i f t / f_s) for the bins f = j f_s / (2 n) with |f| <= 15 Hz,
    windows every ``hop`` samples inside the series."""
    fs, n = 200.0, 200
    cw = Waveform("cw", n / fs, 1500.0)
    rng = np.random.default_rng(7)
    x = (rng.standard_normal((3, 1337)) + 1j * rng.standard_normal((3, 1337))).astype(np.complex64)
    z, delay, dop = cw_doppler_bank(x, fs, cw, 15.0, hop=hop, pad=2, taper=taper)
    f = np.arange(-n, n) * fs / (2 * n)
    f = f[np.abs(f) <= 15.0]
    t = np.arange(n)
    w = np.ones(n) if taper == "rect" else 1.0 - np.cos(2.0 * np.pi * (t + 0.5) / n)
    starts = np.arange(0, x.shape[1] - n + 1, hop)
    want = np.stack([(x[:, s: s + n] * w) @ np.exp(-2j * np.pi * np.outer(t, f) / fs) for s in starts], axis=1)
    np.testing.assert_allclose(dop, f, atol=1e-9)
    np.testing.assert_allclose(delay, starts / fs)
    assert z.shape == want.shape and z.dtype == np.complex64
    np.testing.assert_allclose(z, want, atol=2e-4 * np.abs(want).max())
