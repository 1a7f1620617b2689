"""The conventional front end (acoustics/beamforming.py ``cbf_powers``) against a time-domain delay-and-sum written
here from the textbook definition, in the textbook's own conventions (Van Trees, Optimum Array Processing, sec.
2.2; Johnson & Dudgeon, Array Signal Processing, sec. 4.1).

Textbook conventions used by the reference (and how they map to ours):

* elements indexed m = 0..N-1 from the REAR, at positions z_m = (m - (N - 1)/2) d along the axis (bow = +z);
  ours index n = 0 from the FRONT: n = N - 1 - m;
* arrival angle psi measured from BROADSIDE, positive toward the bow; ours is the cone angle theta from the bow
  (0 = ahead): psi = 90 deg - theta;
* a plane wave from psi reaches element m at t_m = -z_m sin(psi) / c (the bow element first for psi > 0);
  delay-and-sum steered at psi advances each element by its arrival delay, y(t) = sum_m x_m(t + t_m(psi));
* beam power over the band: the energy of y in the window, P = (M / 2) sum_t y(t)^2, which by Parseval equals
  sum over the rfft bins of |Y(f)|^2 when y holds only bins strictly inside (0, fs/2) (all our tones are in the
  band), i.e. the CBF's sum over the band's bins.

The delays are applied to a long record (8 windows) by an FFT phase shift, integer and fractional parts alike;
the signals are tones on the window's bins (periodic in the window), so the shift of the long record is the
exact delay, and the reference never forms a cross-spectrum or a lag vector as the front end does.
"""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.beamforming import BeamformerSettings, cbf_powers
from sonartrack.acoustics.line_array import Band, LineArray

FS = 4000.0
M = 1000  # one window: 0.25 s, 4 Hz bins
N = 12
D_M, C_MPS = 2.5, 1500.0
BAND = (150.0, 300.0)


def _tones(rng, n_tones):
    """Frequencies on the window's bins strictly inside the band, amplitudes, phases."""
    bins = np.arange(int(np.ceil(BAND[0] * M / FS)), int(np.ceil(BAND[1] * M / FS)))
    k = rng.choice(bins, n_tones, replace=False)
    return k * FS / M, rng.uniform(0.2, 1.0, n_tones), rng.uniform(0, 2 * np.pi, n_tones)


def _textbook_record(rng, psi_sources_deg, n_records=8):
    """x_m(t) (rear-first, N x 8M): plane waves from broadside angles psi plus independent tones per element."""
    t = np.arange(n_records * M) / FS
    z = (np.arange(N) - (N - 1) / 2) * D_M
    x = np.zeros((N, t.size))
    for psi in psi_sources_deg:
        f, a, ph = _tones(rng, 12)
        t_arr = -z * np.sin(np.deg2rad(psi)) / C_MPS  # arrival delay of element m
        x += np.sum(a[None, :, None] * np.cos(2 * np.pi * f[None, :, None] * (t[None, None] - t_arr[:, None, None])
                                              + ph[None, :, None]), axis=1)
    for m in range(N):  # element noise: independent tones
        f, a, ph = _tones(rng, 6)
        x[m] += 0.5 * np.sum(a[:, None] * np.cos(2 * np.pi * f[:, None] * t[None] + ph[:, None]), axis=0)
    return x


def _advance(x, tau_s):
    """x(t + tau) of a long record by an FFT phase shift (integer and fractional samples alike)."""
    f = np.fft.rfftfreq(x.size, 1 / FS)
    return np.fft.irfft(np.fft.rfft(x) * np.exp(2j * np.pi * f * tau_s), x.size)


def textbook_das_power(x_rear_first, psi_deg, window):
    """Delay-and-sum beam energy (module doc) of window number ``window`` of the long record."""
    z = (np.arange(N) - (N - 1) / 2) * D_M
    out = np.empty(len(psi_deg))
    for i, psi in enumerate(psi_deg):
        t_arr = -z * np.sin(np.deg2rad(psi)) / C_MPS
        y = sum(_advance(x_rear_first[m], t_arr[m]) for m in range(N))
        seg = y[window * M:(window + 1) * M]
        out[i] = 0.5 * M * np.sum(seg**2)
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_cbf_equals_time_domain_delay_and_sum(seed):
    rng = np.random.default_rng(seed)
    x_tb = _textbook_record(rng, psi_sources_deg=[20.0, -47.3])
    ours = BeamformerSettings(band_hz=list(BAND), beams=37, whiten=False, fft_precision="double")
    theta = ours.cone_deg  # ours: cone angle from the bow
    psi = 90.0 - theta  # textbook: from broadside toward the bow
    x_ours = x_tb[::-1]  # ours: element 0 = front (bow) = textbook's last element
    windows = [2, 5]
    blocks = np.stack([x_ours[:, w * M:(w + 1) * M] for w in windows])
    p_ours = cbf_powers(blocks, FS, LineArray(N, D_M, C_MPS), ours, Band(*BAND))
    for i, w in enumerate(windows):
        ref = textbook_das_power(x_tb, psi, w)
        # double-precision FFT: the equations agree to rounding; a wrong delay differs by O(1)
        np.testing.assert_allclose(p_ours[i], ref, rtol=1e-9, atol=0)
    # the sources are where each convention says: the two highest beam maxima at theta = 90 - psi
    p = p_ours[0]
    peaks = [i for i in range(1, len(p) - 1) if p[i] > p[i - 1] and p[i] >= p[i + 1]]
    top = sorted(theta[sorted(peaks, key=lambda i: -p[i])[:2]])
    np.testing.assert_allclose(top, [90.0 - 20.0, 90.0 + 47.3], atol=5.0)


def test_mapping_matters():
    """The reference is not blind to the conventions: with the elements not reversed (front/rear swapped) the
    powers differ by far more than the tolerance (so the equality above is a check of the mapping)."""
    rng = np.random.default_rng(3)
    x_tb = _textbook_record(rng, psi_sources_deg=[35.0])
    ours = BeamformerSettings(band_hz=list(BAND), beams=19, whiten=False)
    p_wrong = cbf_powers(x_tb[None, :, 0:M], FS, LineArray(N, D_M, C_MPS), ours, Band(*BAND))[0]
    ref = textbook_das_power(x_tb, 90.0 - ours.cone_deg, 0)
    assert np.max(np.abs(p_wrong - ref) / ref) > 0.1


def test_long_record_shift_is_the_exact_delay():
    """The reference's FFT shift of a tone on the window's bins equals the analytic delayed tone."""
    t = np.arange(8 * M) / FS
    f = 37 * FS / M
    tau = 0.0123457  # 49.38 samples: integer and fractional parts
    np.testing.assert_allclose(_advance(np.cos(2 * np.pi * f * t + 0.3), tau), np.cos(2 * np.pi * f * (t + tau) + 0.3),
                               atol=1e-12)
