"""The passive chain's per-window kernels made in fewer array passes, against the plain formulas they replace:
the peaks of a batch of windows picked together (acoustics/beamforming.py ``pick_beam_peaks_rows``), the tonal
window's peaks tested for SNR at the local maxima only (acoustics/tonal.py ``window_peak_bins``), the Hann window
applied in frequency in place (``_hann_spectra``) and the LOFAR accumulator's reused power buffer
(acoustics/lofar.py). Each reference is written out here from its formula, not taken from the library."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft
from scipy.ndimage import median_filter

from sonartrack.acoustics.beamforming import BeamformerSettings, pick_beam_peaks, pick_beam_peaks_rows
from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.lofar import LofarAccumulator, LofarSettings
from sonartrack.acoustics.tonal import TonalSettings, window_peak_bins
from sonartrack.acoustics.tonal_spectra import _hann_spectra

FS, C = 4000.0, 1500.0


def plain_beam_peaks(z: np.ndarray, cone_deg: np.ndarray, threshold: float, max_peaks: int):
    """Local maxima of z (mirrored at both ends) at or above the threshold, parabola-refined (vertex offset
    delta = (y0 - y2) / (2 (y0 - 2 y1 + y2)) in beams, clipped to +-0.5; height y1 - (y0 - y2) delta / 4), the
    max_peaks highest kept in angle order: written out with a Python loop over the beams."""
    ext = [z[1], *z, z[-2]]
    step = cone_deg[1] - cone_deg[0]
    found = []
    for b in range(len(z)):
        y0, y1, y2 = ext[b], ext[b + 1], ext[b + 2]
        if y1 > y0 and y1 >= y2 and y1 >= threshold:
            den = y0 - 2.0 * y1 + y2
            delta = min(max(0.5 * (y0 - y2) / den if den < 0 else 0.0, -0.5), 0.5)
            found.append((min(max(cone_deg[b] + delta * step, 0.0), 180.0), y1 - 0.25 * (y0 - y2) * delta))
    if len(found) > max_peaks:
        highest = sorted(range(len(found)), key=lambda i: -found[i][1])[:max_peaks]  # sorted() is stable
        found = [found[i] for i in sorted(highest)]
    return np.array([a for a, _ in found]), np.array([h for _, h in found])


def test_batch_peaks_equal_the_plain_formula_row_by_row():
    """A batch of windows: rows with no peak, an endfire peak (mirrored grid), a flat top (y1 == y2), more peaks
    than max_peaks with a tie in height, and a row of noise; angles and heights equal the per-row loop to the
    last bit, and equal the single-window function's."""
    s = BeamformerSettings(beams=37, threshold=3.0, max_peaks=2)
    cone = s.cone_deg
    rng = np.random.default_rng(5)
    z = rng.standard_normal((7, 37))
    z[0] = 0.0  # no peak
    z[1, 0], z[1, 1] = 9.0, 4.0  # endfire: beam 0 is a maximum against its mirror image, beam 1
    z[2, 10:12] = 6.0  # flat top: the first of the two is the peak (> left, >= right)
    z[3, [3, 9, 15, 21, 27]] = [5.0, 8.0, 7.0, 4.0, 7.0]  # five peaks, two kept: 8 and the first of two 7s
    z[3, [14, 16, 26, 28]] = 0.0  # symmetric neighbours: heights exactly 7 and 7, a tie at the cut
    z[4, -1], z[4, -2] = 12.0, 1.0  # the other endfire
    z[5] *= 3.0
    z[6] = 0.0
    z[6, [5, 18, 30]] = [6.0, 5.0, 4.0]  # one peak more than max_peaks: the lowest dropped
    got = pick_beam_peaks_rows(z, cone, s)
    assert len(got) == 7 and got[0][0].size == 0 and list(got[6][1]) == [6.0, 5.0]
    for row, (angle, height) in zip(z, got, strict=True):
        want_a, want_h = plain_beam_peaks(row, cone, s.threshold, s.max_peaks)
        np.testing.assert_array_equal(angle, want_a.reshape(-1))
        np.testing.assert_array_equal(height, want_h.reshape(-1))
        one_a, one_h = pick_beam_peaks(row, cone, s)
        np.testing.assert_array_equal(angle, one_a)
        np.testing.assert_array_equal(height, one_h)
    assert got[3][0][1] == cone[15] and got[3][1][1] == 7.0 and got[1][0][0] == 0.0 and got[4][0][-1] == 180.0
    assert sum(a.size for a, _ in got) >= 7  # the cases above are not empty by accident


def plain_window_peaks(power: np.ndarray, df_hz: float, background_hz: float, min_snr_db: float) -> list:
    """Per row: bins k (1..F-2) with p_k > p_{k-1}, p_k >= p_{k+1} and 10 log10(p_k / median) >= min_snr_db, the
    median that of the odd count of bins round(background_hz / df) | 1 centred on k (the row mirrored at its
    ends), strongest first, ties in bin order."""
    out = []
    width = max(3, int(round(background_hz / df_hz)) | 1)
    for p in np.maximum(power, np.finfo(float).tiny):
        med = median_filter(p, size=width, mode="reflect")
        snr = 10.0 * np.log10(p / np.maximum(med, np.finfo(float).tiny))
        ks = [k for k in range(1, p.size - 1) if p[k] > p[k - 1] and p[k] >= p[k + 1] and snr[k] >= min_snr_db]
        out.append(np.array(sorted(ks, key=lambda k: -snr[k]), dtype=np.int64))
    return out


@pytest.mark.parametrize("min_snr_db", [3.0, 0.0])
def test_window_peaks_at_the_local_maxima_equal_the_plain_formula(min_snr_db):
    """Lines 20, 10 and exactly 3 dB above a flat background (the last on the threshold), a tie of two equal lines
    (bin order kept), and noise: the bins and their order equal the per-row formula's."""
    rng = np.random.default_rng(8)
    p = rng.exponential(1.0, (4, 300))
    p[0] = 1.0
    p[0, [40, 120, 200]] = [100.0, 10.0, 10.0**0.3]  # 20, 10 and 3 dB over a median of exactly 1
    p[1] = 1.0
    p[1, [50, 250]] = 30.0  # equal SNR: bin order
    p[2, 10:] = np.linspace(1.0, 2.0, 290)  # a ramp: no local maximum but the top end's neighbour
    got = window_peak_bins(p, 1.0, TonalSettings(background_hz=20.0), min_snr_db=min_snr_db)
    want = plain_window_peaks(p, 1.0, 20.0, min_snr_db)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    assert list(got[0]) == [40, 120, 200] and list(got[1][:2]) == [50, 250]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_hann_spectra_equal_the_shift_theorem_bit_for_bit(dtype):
    """X_w(k) = X(k) / 2 - (X(k - 1) + X(k + 1)) / 4 of the rectangular rfft, the same bits as written this way,
    and the rfft of the Hann-windowed samples to the precision's rounding."""
    rng = np.random.default_rng(2)
    x = rng.standard_normal((5, 512)).astype(dtype)
    idx = np.arange(20, 200)
    got = _hann_spectra(x, idx)
    rect = scipy.fft.rfft(x, axis=1, workers=1)
    want = 0.5 * rect[:, idx] - 0.25 * (rect[:, idx - 1] + rect[:, idx + 1])
    assert got.dtype == want.dtype
    np.testing.assert_array_equal(got, want)
    hann = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(512) / 512)
    windowed = np.fft.rfft(x.astype(float) * hann, axis=1)[:, idx]
    np.testing.assert_allclose(got, windowed, atol=(1e-4 if dtype == np.float32 else 1e-11) * np.abs(windowed).max())


def test_lofar_batches_of_any_size_and_precision_give_each_periods_own_gram():
    """The accumulator's power buffer is reused from batch to batch: batches of 3 windows (single), 3 (double: the
    same shape, another precision), 7 and 2 (single) give, period by period (3 windows each, normalised alone),
    the gram of a fresh accumulator fed only that period's windows in one batch."""
    rng = np.random.default_rng(4)
    array, n = LineArray(8, 0.75, C), 400
    s = LofarSettings(band_hz=[100.0, 900.0], beams=15, integration=3)
    acc = LofarAccumulator(FS, array, s, n)
    width = acc.bins.stop - acc.bins.start
    spectra = (rng.standard_normal((15, 8, width)) + 1j * rng.standard_normal((15, 8, width))).astype(np.complex64)
    spectra[7] *= 100.0  # a loud window: a stale buffer row would show
    double = range(3, 6)  # windows in double precision
    for a, b in ((0, 3), (3, 6), (6, 13), (13, 15)):
        acc.add(spectra[a:b].astype(np.complex128) if a in double else spectra[a:b])
    got = acc.gram(1.0)
    assert got.power.shape[0] == 5
    for period in range(5):
        ref = LofarAccumulator(FS, array, s, n)
        windows = spectra[3 * period: 3 * period + 3]
        ref.add(windows.astype(np.complex128) if 3 * period in double else windows)
        # a double period matches to double rounding (its sum cut in two parts); a single one to single rounding:
        # BLAS may block a complex64 product differently for another batch size (seen: 1e-6 relative with numpy
        # 2.4.6's OpenBLAS on one CPU), far below the 1e4 a stale row of the loud window would give
        rtol = 1e-12 if 3 * period in double else 1e-5
        np.testing.assert_allclose(got.power[period], ref.gram(1.0).power[0], rtol=rtol)
