"""Adaptive beams of a uniform line array: MVDR (Capon) beam powers with diagonal loading, per frequency bin.

Same geometry and output as the conventional front end (acoustics/beamforming.py ``cbf_powers``): element n
(0 = front) is reached by a plane wave from cone angle theta (0 = ahead) at tau_n = (n - (N - 1)/2) kappa,
kappa = d cos(theta) / c; the steering vector of bin f is a_n(theta, f) = exp(-2 pi i f tau_n), so that the
conventional beam is a^H x = sum_n exp(+2 pi i f tau_n) X_n(f), the CBF's sum. Output: (K windows, B beams)
on the cone grid ``BeamformerSettings.cone_deg`` over the band's bins.

Cross-spectral matrix (CSM) of one window (Welch): the window is cut into segments of ``segment_s`` with
50 % overlap, each Hann-weighted and transformed, and per bin f

    R(f) = (1/L) sum_l x_l(f) x_l(f)^H                      (L segments, x_l the N element spectra)

With ``whiten`` each bin's R is divided by its mean element power tr(R)/N (every bin weighs the same, as in
the CBF). Diagonal loading (Van Trees, Optimum Array Processing, sec. 6.6.4; Cox, Zeskind & Owen 1987):

    R_L = R + delta (tr(R) / N) I

MVDR / Capon (Capon 1969, "High-resolution frequency-wavenumber spectrum analysis", Proc. IEEE 57(8), eq. 8;
Van Trees, sec. 6.2.1, eqs. 6.14-6.15): the weights that pass the look direction undistorted with least output
power and that power are

    w = R_L^-1 a / (a^H R_L^-1 a),        P(theta, f) = w^H R_L w = 1 / (a^H R_L^-1 a),

and the beam power over the band is P(theta) = sum_{f in band} P(theta, f) (input units^2 per segment
spectrum, Hann-weighted). Two limits checked by the tests: a single plane wave of power s in white noise of
power n per element (R = s a0 a0^H + n I) gives P(theta0, f) = s + (n + delta tr(R)/N) / N; and as
delta -> infinity, N^2 (P - lambda / N) -> a^H R a (lambda = delta tr(R)/N), the conventional beam power of the
same CSM.

Why segments: one window's spectrum is one snapshot (R of rank one, not invertible); the segments give L
snapshots (L = 2 window_s / segment_s - 1). The segment must stay long against the array's transit time
(N d / c, 27 ms for 16 x 2.5 m) for the per-bin (narrowband) model to hold, and the loading keeps R_L
invertible when L < N. Cost: one N x N Cholesky solve per bin and window plus B N^2 products per bin
(benchmarks/bench_mvdr.py).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting


class MvdrSettings(Settings):
    """MVDR (Capon) beams with diagonal loading (module doc); the cone grid, band and whitening are the front
    end's (acoustics/beamforming.py ``BeamformerSettings``)."""

    segment_s: float = setting(0.25, "segment of the Welch cross-spectral matrix (50 % overlap, Hann): 0.25 s gives "
                                     "7 snapshots in 1 s windows and 4 Hz bins", unit="s", gt=0)
    loading: float = setting(0.01, "diagonal loading delta: R + delta (tr R / N) I (robustness to steering errors "
                                   "and few snapshots; less loading resolves closer sources at high SNR)", unit="1",
                             gt=0)


def steering_vectors(f_hz: np.ndarray, cone_deg: np.ndarray, array: LineArray, n_elements: int) -> np.ndarray:
    """Plane-wave steering vectors a_n(theta, f) = exp(-2 pi i f tau_n(theta)) (module doc).

    Parameters
    ----------
    f_hz : ndarray (F,)
        Frequencies (Hz).
    cone_deg : ndarray (B,)
        Cone angles (deg, 0 = ahead).
    array : LineArray
        Spacing and sound speed.
    n_elements : int
        N (element 0 = front).

    Returns
    -------
    ndarray (F, B, N) complex
        The steering vectors (|a_n| = 1).
    """
    kappa = array.spacing_m * np.cos(np.deg2rad(np.asarray(cone_deg, float))) / array.sound_speed_mps
    tau = (np.arange(n_elements) - 0.5 * (n_elements - 1))[None, :] * kappa[:, None]  # (B, N)
    return np.exp(-2j * np.pi * np.asarray(f_hz, float)[:, None, None] * tau[None])


def capon_power(csm: np.ndarray, steering: np.ndarray, loading: float) -> np.ndarray:
    """MVDR power P = 1 / (a^H R_L^-1 a), R_L = R + delta (tr R / N) I, per bin and beam (module doc; Capon 1969
    eq. 8, Van Trees eq. 6.15).

    Parameters
    ----------
    csm : ndarray (..., F, N, N) complex
        Hermitian cross-spectral matrices.
    steering : ndarray (F, B, N) complex
        Steering vectors (:func:`steering_vectors`).
    loading : float
        delta >= 0 (0 needs a full-rank R).

    Returns
    -------
    ndarray (..., F, B)
        The MVDR powers (units of R).
    """
    n = csm.shape[-1]
    lam = loading * np.real(np.trace(csm, axis1=-2, axis2=-1)) / n
    r = csm + lam[..., None, None] * np.eye(n)
    chol = np.linalg.cholesky(r)  # R_L = C C^H, so a^H R_L^-1 a = |C^-1 a|^2
    a = np.broadcast_to(np.swapaxes(steering, -1, -2), chol.shape[:-1] + (steering.shape[1],))
    u = np.linalg.solve(chol, a)  # (..., F, N, B): triangular, solved as general (numpy has no batched trsm)
    denom = np.einsum("...nb,...nb->...b", u.conj(), u).real
    return 1.0 / denom


@lru_cache(maxsize=4)
def _segments(n_samples: int, segment: int) -> tuple[np.ndarray, np.ndarray]:
    """(start indices of the 50 %-overlap segments, the periodic Hann window of one segment)."""
    hop = max(segment // 2, 1)
    starts = np.arange(0, n_samples - segment + 1, hop)
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(segment) / segment)
    return starts, w


def cross_spectral_matrices(blocks: np.ndarray, fs_hz: float, band: Band, segment_s: float,
                            whiten: bool) -> tuple[np.ndarray, np.ndarray]:
    """Welch cross-spectral matrices of K windows over the band (module doc).

    Parameters
    ----------
    blocks : ndarray (K, N, M)
        K windows of M samples of N elements.
    fs_hz : float
        Sample rate (Hz).
    band : Band
        Processing band [low, high) (Hz).
    segment_s : float
        Segment length (s); at most the window.
    whiten : bool
        Divide each bin's matrix by tr(R) / N.

    Returns
    -------
    f_hz : ndarray (F,)
        The band's segment bins (Hz).
    csm : ndarray (K, F, N, N) complex
        R(f) per window.
    """
    k, n, m = blocks.shape
    seg = int(round(segment_s * fs_hz))
    require(2 <= seg <= m, f"mvdr segment_s {segment_s:g} s must hold 2..{m} samples (one window) at {fs_hz:g} Hz")
    starts, w = _segments(m, seg)
    f = np.fft.rfftfreq(seg, 1.0 / fs_hz)
    idx = np.nonzero((f >= band.low_hz) & (f < band.high_hz) & (f > 0))[0]
    require(idx.size > 0, f"no {fs_hz / seg:.3g} Hz bin of the mvdr segment falls in the band {band.as_tuple()} Hz: "
                          "lengthen segment_s")
    frames = np.stack([blocks[:, :, s:s + seg] for s in starts], axis=1) * w  # (K, L, N, seg)
    x = np.fft.rfft(frames, axis=-1)[..., idx]  # (K, L, N, F)
    csm = np.einsum("klnf,klmf->kfnm", x, x.conj()) / len(starts)
    if whiten:
        p = np.real(np.trace(csm, axis1=-2, axis2=-1)) / n
        csm = csm / np.where(p > 0, p, 1.0)[..., None, None]
    return f[idx], csm


def mvdr_powers(blocks: np.ndarray, fs_hz: float, array: LineArray, settings, band: Band | None = None,
                mvdr: MvdrSettings | None = None) -> np.ndarray:
    """MVDR beam powers P(theta) = sum_f 1 / (a^H R_L^-1 a) of K windows (module doc), on the CBF's cone grid.

    Parameters
    ----------
    blocks, fs_hz, array : ndarray (K, N, M), float, LineArray
        As :func:`~sonartrack.acoustics.beam_powers.cbf_powers`'s: K windows of the N elements, the sample rate
        (Hz), the array (spacing and sound speed of the steering delays).
    settings : BeamformerSettings
        The front end's ``beams`` (cone grid), ``whiten`` and, when ``band`` is None, ``band_hz``.
    band : Band, optional
        The processing band (acoustics/beamforming.py ``front_end_band``); None resolves it here.
    mvdr : MvdrSettings, optional
        Segment length and loading (defaults when None).

    Returns
    -------
    ndarray (K, B)
        Beam power over the band at the B cone angles ``settings.cone_deg``.
    """
    mv = mvdr or MvdrSettings()
    x = np.asarray(blocks, dtype=float)
    require(x.ndim == 3, f"blocks must be (windows, elements, samples), got shape {x.shape}")
    if band is None:
        band = array.band(fs_hz, settings.band_hz, settings.allow_grating_lobes)
    f, csm = cross_spectral_matrices(x, fs_hz, band, mv.segment_s, settings.whiten)
    steer = steering_vectors(f, settings.cone_deg, array, x.shape[1])
    return capon_power(csm, steer, mv.loading).sum(axis=-2)


def cbf_csm_powers(csm: np.ndarray, steering: np.ndarray) -> np.ndarray:
    """Conventional beam power a^H R a per bin and beam, of the same cross-spectral matrices (the limit of
    :func:`capon_power` under infinite loading, module doc).

    Parameters
    ----------
    csm : ndarray (..., F, N, N)
        Cross-spectral matrices.
    steering : ndarray (F, B, N)
        Steering vectors.

    Returns
    -------
    ndarray (..., F, B)
        a^H R a (units of R).
    """
    return np.einsum("fbn,...fnm,fbm->...fb", steering.conj(), csm, steering).real
