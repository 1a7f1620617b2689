"""MVDR (Capon) beams: the closed form of one plane wave in white noise, the infinite-loading limit (CBF), and a
weak source one beamwidth beside a loud one (acoustics/mvdr.py)."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.beamforming import BeamformerSettings, cbf_powers
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.mvdr import (
    MvdrSettings,
    capon_power,
    cbf_csm_powers,
    cross_spectral_matrices,
    mvdr_powers,
    steering_vectors,
)

ARRAY = LineArray(16, 2.5, 1500.0)
FS = 4000.0


def _plane_wave_csm(f_hz, theta0_deg, s, n_power):
    a0 = steering_vectors(np.array([f_hz]), np.array([theta0_deg]), ARRAY, ARRAY.elements)[0, 0]
    return s * np.outer(a0, a0.conj()) + n_power * np.eye(ARRAY.elements)


@pytest.mark.parametrize("loading", [0.0, 0.1])
def test_single_plane_wave_closed_form(loading):
    """R = s a0 a0^H + n I: a0^H R^-1 a0 = N / (n + N s) by the matrix inversion lemma, so P(theta0) = s + n / N,
    with n raised by the loading delta tr(R) / N = delta (s + n)."""
    s, n, f, theta0 = 2.0, 0.5, 220.0, 63.0
    csm = _plane_wave_csm(f, theta0, s, n)[None]
    steer = steering_vectors(np.array([f]), np.array([theta0, 100.0]), ARRAY, ARRAY.elements)
    p = capon_power(csm, steer, loading)[0]
    n_loaded = n + loading * (s + n)
    assert p[0] == pytest.approx(s + n_loaded / ARRAY.elements, rel=1e-12)
    # away from the source the wave is nulled: far below the source's power, above the loaded noise floor / N
    assert n_loaded / ARRAY.elements * 0.99 < p[1] < 0.2 * s


def test_infinite_loading_is_cbf():
    """R_L^-1 = (I - R / lam + ...) / lam for large lam = delta tr(R)/N, so N^2 (P - lam / N) -> a^H R a."""
    rng = np.random.default_rng(1)
    x = rng.standard_normal((3, 16, 4000))
    f, csm = cross_spectral_matrices(x, FS, Band(150.0, 300.0), 0.25, whiten=False)
    steer = steering_vectors(f, np.linspace(0, 180, 37), ARRAY, 16)
    delta = 1e7
    lam = delta * np.real(np.trace(csm, axis1=-2, axis2=-1)) / 16
    p = capon_power(csm, steer, delta)
    limit = 16**2 * (p - lam[..., None] / 16)
    cbf = cbf_csm_powers(csm, steer)
    # next term of the expansion is O(|R|^2 / lam) ~ 1e-7 relative; float rounding of P ~ lam / N costs ~1e-4
    np.testing.assert_allclose(limit, cbf, rtol=2e-3)
    # and a^H R a computed by hand for one bin and beam
    a = steer[4, 10]
    assert cbf[1, 4, 10] == pytest.approx(np.real(a.conj() @ csm[1, 4] @ a), rel=1e-12)


def _record(sources, noise_power, seconds, rng):
    """N channels of broadband plane waves (cone angle deg, power per element) + independent white noise; the
    delays are exact phase ramps on the rfft of the whole record (circular)."""
    m = int(seconds * FS)
    f = np.fft.rfftfreq(m, 1 / FS)
    tau_unit = (np.arange(16) - 7.5) * ARRAY.spacing_m / ARRAY.sound_speed_mps  # tau_n / cos(theta)
    x = np.sqrt(noise_power) * rng.standard_normal((16, m))
    for cone_deg, power in sources:
        s = np.fft.rfft(np.sqrt(power) * rng.standard_normal(m))
        tau = tau_unit * np.cos(np.deg2rad(cone_deg))
        x += np.fft.irfft(s[None] * np.exp(-2j * np.pi * f[None] * tau[:, None]), m, axis=1)
    return x


def _local_max_near(p_db, cone, angle, tol=2.0):
    near = np.abs(cone - angle) <= tol
    interior = (p_db[1:-1] > p_db[:-2]) & (p_db[1:-1] >= p_db[2:])
    peaks = np.nonzero(interior)[0] + 1
    return any(near[i] for i in peaks)


def test_weak_beside_loud_resolved_by_mvdr_not_cbf():
    """A source 20 dB below a loud one, one beamwidth (0.89 lambda / (N d) at the band centre) away: the MVDR
    spectrum has a peak at the weak source with a dip between, the CBF's does not. Levels per element: loud +30 dB,
    weak +10 dB over the independent noise (measured: at weak 0 dB the MVDR dip shrinks to ~1.5 dB)."""
    rng = np.random.default_rng(7)
    bw = ARRAY.beamwidth_deg(225.0)
    loud, weak = 90.0, 90.0 + bw
    x = _record([(loud, 1.0), (weak, 0.01)], 0.001, 4.0, rng)
    blocks = x.reshape(16, 4, 4000).transpose(1, 0, 2)
    fe = BeamformerSettings(band_hz=[150.0, 300.0], beams=361, whiten=True)
    cone = fe.cone_deg
    p_mvdr = 10 * np.log10(mvdr_powers(blocks, FS, ARRAY, fe, mvdr=MvdrSettings(loading=0.001)).mean(axis=0))
    p_cbf = 10 * np.log10(cbf_powers(blocks, FS, ARRAY, fe).mean(axis=0))
    assert _local_max_near(p_mvdr, cone, loud) and _local_max_near(p_mvdr, cone, weak)
    between = (cone > loud + 1) & (cone < weak - 1)
    assert p_mvdr[between].min() < p_mvdr[np.abs(cone - weak) <= 2].max() - 3.0
    assert not _local_max_near(p_cbf, cone, weak, tol=3.0)


def test_output_shape_and_grid_match_cbf():
    rng = np.random.default_rng(3)
    blocks = rng.standard_normal((2, 16, 4000))
    fe = BeamformerSettings(band_hz=[150.0, 300.0])
    p = mvdr_powers(blocks, FS, ARRAY, fe)
    assert p.shape == cbf_powers(blocks, FS, ARRAY, fe).shape == (2, fe.beams)
    assert np.all(p > 0)


def test_segment_outside_window_refused():
    from sonartrack.core.errors import InputError

    fe = BeamformerSettings(band_hz=[150.0, 300.0])
    with pytest.raises(InputError, match="segment_s"):
        mvdr_powers(np.zeros((1, 16, 400)), FS, ARRAY, fe, mvdr=MvdrSettings(segment_s=1.0))


def test_front_end_method_mvdr_runs_mvdr_powers():
    """``method = "mvdr"`` in the front end's settings: the bearing-time record's level is the normalised MVDR power
    (acoustics/beamforming.py dispatches to acoustics/mvdr.py)."""
    from sonartrack.acoustics.beamforming import bearing_time_record, normalise_across_bearing

    rng = np.random.default_rng(4)
    x = _record([(60.0, 0.1)], 1.0, 3.0, rng)
    blocks = [x[:, k * 4000:(k + 1) * 4000] for k in range(3)]
    fe = BeamformerSettings(method="mvdr", band_hz=[150.0, 300.0])
    mv = MvdrSettings(loading=0.02)
    btr = bearing_time_record(iter(blocks), FS, ARRAY, fe, mvdr=mv)
    expected = normalise_across_bearing(mvdr_powers(np.stack(blocks), FS, ARRAY, fe, mvdr=mv), fe)
    np.testing.assert_allclose(btr.level, expected, rtol=1e-5, atol=1e-5)  # the record keeps float32
    assert np.all(np.abs(btr.peaks.bearing_deg[btr.peaks.amplitude == btr.peaks.amplitude.max()] - 60.0) < 2.0)
