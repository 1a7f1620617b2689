"""The front end's faster kernels against the plain NumPy formulas they replace: the CBF's whitening made on the
lags and its lags summed per lag-bin product (acoustics/beamforming.py), and the LOFAR beams formed in mirror
pairs (acoustics/lofar.py ``LofarAccumulator``). Each reference is the textbook sum written out here, not the
library's own output."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.beam_powers import _steering_matrix, _sum_over_products
from sonartrack.acoustics.beamforming import (
    BeamformerSettings,
    _band_steering,
    _cbf_from_spectra,
    cbf_powers,
)
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.lofar import LofarAccumulator, LofarSettings

FS, C = 4000.0, 1500.0


def direct_cbf(spectra: np.ndarray, f_hz: np.ndarray, cone_deg: np.ndarray, spacing_m: float) -> np.ndarray:
    """P(theta) = sum_f |sum_n exp(+2 pi i f tau_n) X_n(f)|^2, tau_n = -s_n cos(theta) / c, s_n = ((N - 1)/2 - n) d
    (acoustics/beamforming.py module doc), for spectra (N, F)."""
    n = spectra.shape[0]
    s_n = ((n - 1) / 2 - np.arange(n)) * spacing_m
    out = []
    for theta in np.deg2rad(cone_deg):
        tau = -s_n * np.cos(theta) / C
        y = (np.exp(2j * np.pi * f_hz[None, :] * tau[:, None]) * spectra).sum(axis=0)
        out.append(np.sum(np.abs(y) ** 2))
    return np.array(out)


def whitened(spectra: np.ndarray) -> np.ndarray:
    """Each bin divided by the root of its mean element power (a silent bin left at zero)."""
    power = np.mean(np.abs(spectra) ** 2, axis=0)
    return spectra / np.sqrt(np.where(power > 0, power, 1.0))


@pytest.mark.parametrize("beams", [37, 36])
def test_whitened_cbf_equals_the_direct_sum_over_whitened_spectra(beams):
    """Whitening made on the lags (r_l N / r_0) is whitening the spectra: against the direct sum over elements and
    bins of spectra divided by their mean element power (a tonal 40 dB up in one bin weighs as much as any other)."""
    rng = np.random.default_rng(11)
    n, m, d = 6, 256, 0.5
    x = rng.standard_normal((n, m))
    x += 100.0 * np.sin(2 * np.pi * 500.0 * np.arange(m) / FS)[None, :]  # bin 32: 40 dB above the rest
    s = BeamformerSettings(band_hz=[200.0, 1500.0], beams=beams, whiten=True, fft_precision="double")
    got = cbf_powers(x[None], FS, LineArray(n, d, C), s)[0]
    f = np.fft.rfftfreq(m, 1 / FS)
    band = (f >= 200) & (f < 1500)
    want = direct_cbf(whitened(np.fft.rfft(x, axis=1)[:, band]), f[band], s.cone_deg, d)
    np.testing.assert_allclose(got, want, rtol=1e-10)  # unwhitened, the tonal's beam alone would stand 40 dB up
    assert np.ptp(want) / np.max(want) > 0.1  # and the beams differ: a wrong steering cannot pass by flatness


def test_a_silent_bin_stays_silent_when_whitened():
    """A bin of zero power on every element contributes nothing (no division by zero), the others as whitened."""
    rng = np.random.default_rng(12)
    n, m, d = 5, 64, 0.5
    arr, s = LineArray(n, d, C), BeamformerSettings(band_hz=[400.0, 1200.0], beams=9, fft_precision="double")
    band = Band(400.0, 1200.0)
    idx, steer = _band_steering(n, m, FS, arr, s, band)
    spectra = rng.standard_normal((n, idx.size)) + 1j * rng.standard_normal((n, idx.size))
    spectra[:, 3] = 0.0
    got = _cbf_from_spectra(spectra[None], steer, True)[0]
    want = direct_cbf(whitened(spectra), idx * FS / m, s.cone_deg, d)
    np.testing.assert_allclose(got, want, rtol=1e-10)
    assert np.all(np.isfinite(got))


def test_lag_bin_products_by_hand():
    """3 elements, 1 Hz bins 2..4 (16 samples at 16 Hz, band [2, 5) Hz): lags 1, 2 give products 2, 3, 4 and 4, 6, 8,
    so 5 distinct columns; C = 2 cos(2 pi q df kappa), S = -2 sin(.), kappa = d cos(theta) / c."""
    idx, (cos2, sin2, beams, j0, products) = _steering_matrix(3, 16, 16.0, 0.5, C, (2.0, 5.0), 5)
    np.testing.assert_array_equal(idx, [2, 3, 4])
    np.testing.assert_array_equal(products, [2, 3, 4, 6, 8])
    assert (beams, j0) == (5, 2) and cos2.shape == sin2.shape == (3, 5)  # beams 0, 45, 90 deg; 135, 180 mirrored
    kappa_45 = 0.5 * np.cos(np.pi / 4) / C
    assert cos2[1, 3] == pytest.approx(2 * np.cos(2 * np.pi * 6 * 1.0 * kappa_45), rel=1e-14)
    assert sin2[1, 4] == pytest.approx(-2 * np.sin(2 * np.pi * 8 * 1.0 * kappa_45), rel=1e-14)
    np.testing.assert_allclose(sin2[2], 0.0, atol=1e-15)  # broadside: no delay, no sine


def test_sum_over_products_by_hand():
    """r_l(j) for lags 1, 2 at bins 2, 3, 4 summed per product q = l j: R_2 = r_1(2), R_3 = r_1(3),
    R_4 = r_1(4) + r_2(2), R_6 = r_2(3), R_8 = r_2(4); the products between (5, 7) stay zero."""
    lags = np.array([[[1.0, 2.0, 3.0], [10.0, 20.0, 30.0]]], dtype=complex)  # (1 window, 2 lags, 3 bins)
    lags[0, 1, 0] += 1j
    span = np.full((1, 8 - 2 + 1), np.nan, dtype=complex)  # q = 2..8; NaN: the function must zero it
    got = _sum_over_products(lags, 2, span)[0]
    np.testing.assert_array_equal(got, [1.0, 2.0, 3.0 + 10.0 + 1j, 0.0, 20.0, 0.0, 30.0])


def direct_hann_beam_powers(spectra: np.ndarray, f_hz: np.ndarray, cone_deg: np.ndarray, array: LineArray
                            ) -> np.ndarray:
    """|B|^2 (F, B, K) of the Hann spectra X_w(k) = X(k)/2 - (X(k-1) + X(k+1))/4 of rectangular spectra (K, N, F + 2),
    B = (1/N) sum_n exp(+2 pi i f tau_n) X_w,n with tau_n = (n - (N - 1)/2) d cos(theta) / c (acoustics/lofar.py)."""
    x = spectra.astype(complex)
    hann = 0.5 * x[:, :, 1:-1] - 0.25 * (x[:, :, :-2] + x[:, :, 2:])  # (K, N, F)
    n = array.elements
    out = np.empty((f_hz.size, cone_deg.size, x.shape[0]))
    for b, theta in enumerate(np.deg2rad(cone_deg)):
        tau = (np.arange(n) - (n - 1) / 2) * array.spacing_m * np.cos(theta) / array.sound_speed_mps
        w = np.exp(2j * np.pi * f_hz[:, None] * tau[None, :]) / n  # (F, N)
        out[:, b, :] = np.abs(np.einsum("fn,knf->fk", w, hann)) ** 2
    return out


@pytest.mark.parametrize("beams", [7, 6])
@pytest.mark.parametrize("dtype", [np.complex128, np.complex64])
def test_lofar_mirror_pairs_equal_the_direct_beams(beams, dtype):
    """The accumulator's integrated powers (beams in mirror pairs, bins in chunks) against the direct Hann beams of
    every cone angle, for an odd grid (a broadside beam of its own) and an even one, over more bins than a chunk."""
    rng = np.random.default_rng(13)
    array, m = LineArray(8, 2.5, C), 2000  # 2 Hz bins: 125 in the band
    s = LofarSettings(band_hz=[50.0, 300.0], beams=beams, integration=3)
    acc = LofarAccumulator(FS, array, s, m)
    width = acc.bins.stop - acc.bins.start
    spectra = rng.standard_normal((3, 8, width)) + 1j * rng.standard_normal((3, 8, width))
    spectra[:, :, 20] += 30.0 * np.exp(0.7j * np.arange(8))  # a loud plane wave in one bin (steady phase step)
    acc.add(spectra.astype(dtype))
    want = direct_hann_beam_powers(spectra.astype(dtype), acc.freqs_hz, s.cone_deg, array).mean(axis=2).T
    got = acc.power()[0] / acc._scale
    assert acc.freqs_hz.size > 64  # more than one chunk of bins
    np.testing.assert_allclose(got, want, rtol=1e-10 if dtype == np.complex128 else 2e-5)
