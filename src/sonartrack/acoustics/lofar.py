"""Narrowband (LOFAR) processing per beam: beam spectra, long integration, a background normaliser along
frequency, and tonal line detection at a stated false-alarm probability.

Beams (as acoustics/tonal.py, element n = 0 at the front, cone angle theta from ahead): per window of M samples,

    X_n(f) = rfft(hann * x_n),   B(theta, f) = (1/N) sum_n exp(+2 pi i f tau_n(theta)) X_n(f),
    P(theta, f) = 2 |B|^2 / (fs sum w^2)          (one-sided PSD, input units^2/Hz; Hann bins 1/(window) apart)

Long integration (the LOFAR gram; Urick, Principles of Underwater Sound, sec. 12.6; Waite, Sonar for Practising
Engineers, ch. 6): the mean of L consecutive windows' spectra, Pbar = (1/L) sum_l P_l. A tonal keeps its power
while the spread of the noise estimate falls as 1/sqrt(L): after normalisation a noise bin is Gamma(L, 1/L)
(mean 1), so a line of bin SNR s stands 1 + s over a background whose spread is 1/sqrt(L).

Background normaliser along frequency (split-window, as a CFAR along the frequency axis; Struzinski & Lowe
1984, "A performance comparison of four noise background normalization schemes proposed for signal detection
systems", JASA 76(6)): for bin k, the reference bins are ``reference_bins`` on each side beyond a gap of
``gap_bins`` (the line's own Hann main lobe stays out of its background), and

    mean:       mu_k = mean of the reference bins (split-window mean);
    two-pass:   the same, then the mean again over the reference bins below ``censor`` mu_k (a neighbouring
                line does not raise the background);
    median:     mu_k = median of the reference bins / m_L, m_L the median of Gamma(L, 1/L) (unbiased in noise).

Statistic z_k = Pbar_k / mu_k. The band (not set) runs from where the aperture spans k wavelengths up to the
array's aliasing frequency (:func:`lofar_band`): above it a loud ship's grating lobe meets each beam at one
frequency and draws a false line.

Threshold for a false-alarm probability ``pfa`` per bin and integration period:
with the mean normaliser over R independent reference bins, z is the ratio of a Gamma(L) to the mean of R
Gamma(L) variables, i.e. F-distributed with (2L, 2LR) degrees of freedom, so t = F^-1(1 - pfa; 2L, 2LR) (exact
for independent bins; Hann bins two apart are nearly independent, and the gap keeps the bin's own neighbours
out); the two-pass and median normalisers use the same threshold (their reference is a little noisier: the
false-alarm rate is measured by the tests). Lines are the cells at or above t that are local maxima along
frequency and across beams; SNR = 10 log10(z - 1) (the line's power over the background).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonartrack.acoustics.blas_threads import one_blas_thread
from sonartrack.acoustics.line_array import LineArray
from sonartrack.core.errors import require
from sonartrack.core.rows import Rows
from sonartrack.core.settings import Settings, setting


class LofarSettings(Settings):
    """Narrowband processing per beam (module doc)."""

    band_hz: list[float] | None = setting(None, "frequencies searched for tonal lines [low, high) (not set: from "
                                                "where the aperture spans aperture_wavelengths wavelengths up to the "
                                                "array's aliasing frequency f_a: above f_a a loud ship's grating lobe "
                                                "sweeps through the beams one frequency at a time and looks like a "
                                                "line)", unit="Hz", min_length=2, max_length=2)
    aperture_wavelengths: float = setting(1.5, "band_hz not set: the band starts where the aperture (N - 1) d "
                                               "spans this many wavelengths, low = max(floor_hz, k c / L) "
                                               "(lofar_band)", unit="1", gt=0)
    floor_hz: float = setting(50.0, "band_hz not set: the lowest frequency searched", unit="Hz", gt=0)
    beams: int = setting(61, "cone-angle grid of the narrowband beams, uniform in 0..180 deg (61 = 3 deg steps; the "
                             "16 x 2.5 m array's beam is ~9.5 deg wide at 200 Hz)", unit="1", ge=3)
    integration: int = setting(16, "windows L averaged into one LOFAR line (long integration)", unit="1", ge=1)
    normaliser: Literal["mean", "two-pass", "median"] = setting("two-pass", "background along frequency: split-"
                                                                "window mean, the same censored, or median", unit="")
    gap_bins: int = setting(2, "bins left out on each side of the bin tested (its Hann main lobe)", unit="1", ge=0)
    reference_bins: int = setting(16, "reference bins on each side beyond the gap", unit="1", ge=2)
    censor: float = setting(3.0, "two-pass: reference bins above this times the first-pass mean are left out",
                            unit="1", gt=1)
    pfa: float = setting(1e-4, "false-alarm probability per bin, beam and integration period of the line "
                               "threshold", unit="1", gt=0, lt=0.5)
    sidelobe_guard_db: float = setting(12.0, "a line whose power over the background is this far below the strongest "
                                             "beam's at the same bin and period is that line's sidelobe, not a source "
                                             "(uniform weighting: first sidelobe -13.3 dB)", unit="dB", ge=0)
    edge_bins: int = setting(5, "bins at each end of the band not searched for lines: there the background has "
                                "reference bins on one side only and a sloping spectrum biases it (default scene, "
                                "16 x 2.5 m, 1200 s, seeds 1-8, band then 75-300 Hz: mean z 1.08-1.13 in the lowest "
                                "5 bins, 75-79 Hz, against 1.00 inside, and 13 of 26 line tracks that followed no "
                                "ship lay there; at "
                                "the top, c / (2 d), the endfire beams are one another's grating lobe)", unit="1",
                             ge=0)

    @property
    def cone_deg(self) -> np.ndarray:
        """The narrowband beams' cone angles (deg)."""
        return np.linspace(0.0, 180.0, self.beams)


@dataclass(frozen=True)
class LofarGram:
    """Integrated, normalised beam spectra: period centres ``time_s`` (T,), ``cone_deg`` (B,), ``freqs_hz`` (F,),
    ``power`` (T, B, F) the integrated PSD (input units^2/Hz) and ``statistic`` (T, B, F) z = power / background."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    freqs_hz: np.ndarray
    power: np.ndarray
    statistic: np.ndarray


def lofar_band(array: LineArray, fs_hz: float, settings: LofarSettings) -> tuple[float, float]:
    """The narrowband band: ``band_hz``, or [max(floor, k c / L), f_a] with L = (N - 1) d the aperture,
    k = ``aperture_wavelengths`` and f_a = min(c / (2 d), fs / 2).

    Why tied to the aperture: the beam is ~lambda / L rad wide, so below k c / L the aperture spans fewer than k
    wavelengths and the narrowband beams no longer resolve a bearing; the old [f_a / 4, f_a] ignored N, so on
    64 x 0.5 m at 16 kHz it searched 375-1500 Hz and never saw ships' tonals at 90-200 Hz, while on 8 x 5 m it
    went down to 37.5 Hz where the 35 m aperture is about one wavelength. ``floor_hz`` bounds long arrays (the
    chain was not measured below 50 Hz). The top stays f_a (grating lobes above it, module doc). If the rule
    gives low >= high (a short array), the band falls back to [f_a / 4, f_a].

    Parameters
    ----------
    array : LineArray
        The array (its aperture and aliasing frequency).
    fs_hz : float
        Sample rate (Hz).
    settings : LofarSettings
        ``band_hz``, ``aperture_wavelengths``, ``floor_hz``.

    Returns
    -------
    tuple of float
        (low, high) in Hz.
    """
    if settings.band_hz is not None:
        lo, hi = settings.band_hz
    else:
        hi = array.aliasing_hz(fs_hz)
        aperture_m = (array.elements - 1) * array.spacing_m
        lo = hi / 4.0
        if aperture_m > 0:
            lo_aperture = max(settings.floor_hz, settings.aperture_wavelengths * array.sound_speed_mps / aperture_m)
            lo = lo_aperture if lo_aperture < hi else lo
    require(0 < lo < hi <= fs_hz / 2, f"LOFAR band {[lo, hi]} Hz must satisfy 0 < low < high <= fs / 2")
    return float(lo), float(hi)


@dataclass(frozen=True, slots=True)
class LineDetections(Rows):
    """Tonal line detections, one row each: period centre (s), cone angle (deg), frequency (Hz), statistic z,
    SNR (dB), beam index."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    frequency_hz: np.ndarray
    statistic: np.ndarray
    snr_db: np.ndarray
    beam: np.ndarray


def beam_power_spectra(blocks: np.ndarray, fs_hz: float, array: LineArray, cone_deg: np.ndarray,
                       band_hz) -> tuple[np.ndarray, np.ndarray]:
    """Conventional beams' one-sided PSDs of K windows (module doc).

    Parameters
    ----------
    blocks : ndarray (K, N, M)
        K windows of M samples of N elements (element 0 = front).
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        Spacing and sound speed of the steering delays.
    cone_deg : ndarray (B,)
        Beam cone angles (deg).
    band_hz : sequence of 2 floats
        [low, high) (Hz).

    Returns
    -------
    freqs_hz : ndarray (F,)
        The band's bins (Hz).
    power : ndarray (K, B, F)
        PSD per window, beam and bin (input units^2/Hz).
    """
    x = np.asarray(blocks, dtype=float)
    m = x.shape[2]
    idx, f, w = _lofar_bins(m, fs_hz, band_hz)
    spec = np.fft.rfft(x * w, axis=2)[:, :, idx[0]: idx[-1] + 1]  # (K, N, F)
    return f, _beam_psd(spec, _lofar_steering(f, array, cone_deg, x.shape[1]), 2.0 / (fs_hz * np.sum(w**2)))


def _lofar_bins(m: int, fs_hz: float, band_hz) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(indices of the rfft bins of M-sample windows in [low, high), their frequencies Hz, the periodic Hann
    window of M samples)."""
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(m) / m)
    f = np.fft.rfftfreq(m, 1.0 / fs_hz)
    idx = np.nonzero((f >= band_hz[0]) & (f < band_hz[1]))[0]
    require(idx.size >= 3, f"the LOFAR band {list(band_hz)} Hz holds fewer than 3 bins of {fs_hz / m:g} Hz")
    return idx, f[idx], w


def _lofar_steering(f_hz: np.ndarray, array: LineArray, cone_deg, n: int) -> np.ndarray:
    """exp(+2 pi i f tau_n(theta)) / N (F, B, N), the beams' weights (module doc)."""
    kappa = array.spacing_m * np.cos(np.deg2rad(np.asarray(cone_deg, float))) / array.sound_speed_mps
    tau = (np.arange(n) - 0.5 * (n - 1))[None, :] * kappa[:, None]  # (B, N)
    return np.exp(2j * np.pi * f_hz[:, None, None] * tau[None]) / n


def _beam_psd(spec: np.ndarray, steer: np.ndarray, scale: float) -> np.ndarray:
    """scale |B|^2 (K, B, F) of the beams steer (F, B, N) applied to the Hann spectra (K, N, F)."""
    with one_blas_thread():
        beams = np.matmul(steer, spec.transpose(2, 1, 0)).transpose(2, 1, 0)  # (F, B, N) @ (F, N, K)
    return scale * (beams.real**2 + beams.imag**2)


#: bins of the LOFAR accumulator's beams formed together: the chunk's Hann spectra, products and powers stay in the
#: core's cache (measured 32 x 8 kHz, 61 beams: 15 % less time than all 450 bins at once)
LOFAR_CHUNK_BINS = 64


def _mirror_weights(f_hz: np.ndarray, array: LineArray, cone_deg: np.ndarray) -> np.ndarray:
    """[C; S] (F, 2 H, N), H = ceil(B / 2): the real and imaginary parts of the steering weights
    (:func:`_lofar_steering`) of the first H of the B beams ``cone_deg`` (cone angles up to 90 deg;
    :func:`_mirror_beam_powers`)."""
    steer = _lofar_steering(f_hz, array, np.asarray(cone_deg)[: (len(cone_deg) + 1) // 2], array.elements)
    return np.ascontiguousarray(np.concatenate([steer.real, steer.imag], axis=1))


def _mirror_beam_powers(xt: np.ndarray, weights: np.ndarray, out: np.ndarray) -> None:
    """|B|^2 (F, B, K) into ``out`` of the Hann spectra of rectangular spectra ``xt`` (F + 2, N, K) (the band's bins
    and one beyond each edge: class doc), with the weights [C; S] (F, 2 H, N) of :func:`_mirror_weights`.

    The grid of cone angles is symmetric about 90 deg and tau_n(180 deg - theta) = -tau_n(theta), so beam B - 1 - h
    has the conjugate weights of beam h: with U = sum_n C_n X_n and V = sum_n S_n X_n (real weights on complex
    spectra: one real product for both), beam h is U + i V = (Re U - Im V) + i (Im U + Re V) and its mirror
    U - i V = (Re U + Im V) + i (Im U - Re V), each summed from its parts as the complex product sums them (no
    difference of powers, which a loud mirror beam would swamp in rounding): half the multiplications."""
    f, n, k = xt.shape[0] - 2, xt.shape[1], xt.shape[2]
    half, beams = weights.shape[1] // 2, out.shape[1]
    hann = np.add(xt[:-2], xt[2:], out=np.empty((f, n, k), dtype=xt.dtype))  # C order: real view below
    hann *= -0.25
    hann += 0.5 * xt[1:-1]
    with one_blas_thread():  # a threaded BLAS spins on a loaded machine (acoustics/blas_threads.py)
        uv = np.matmul(weights, hann.view(weights.dtype)).view(hann.dtype)  # (F, 2H, 2K) real = (F, 2H, K) complex
    u, v = uv[:, :half], uv[:, half:]
    re, im = u.real - v.imag, u.imag + v.real
    np.multiply(re, re, out=out[:, :half])
    out[:, :half] += im * im
    re, im = u.real + v.imag, u.imag - v.real
    mirror = out[:, half:][:, ::-1]  # beams B - 1 .. H: the mirrors of beams 0 .. B - H - 1
    np.multiply(re[:, :beams - half], re[:, :beams - half], out=mirror)
    mirror += im[:, :beams - half] * im[:, :beams - half]


class LofarAccumulator:
    """The LOFAR gram built window by window from the windows' rectangular rfft spectra, so that it comes out of
    the front end's own transforms (acoustics/beamforming.py ``bearing_time_record``) with no pass of its own.

    The Hann window is applied in frequency: the periodic Hann w_m = 1/2 - (1/2) cos(2 pi m / M) is a sum of
    three complex exponentials, so X_w(k) = X(k) / 2 - (X(k - 1) + X(k + 1)) / 4 exactly (the DFT's shift
    theorem; Harris 1978, "On the use of windows for harmonic analysis with the discrete Fourier transform",
    Proc. IEEE 66(1), sec. IV); the band's bins need one rectangular bin beyond each edge (:attr:`bins`). The
    beams, PSD scale, integration over L windows and normaliser are those of :func:`lofar_gram`, which gives the
    same gram from the same windows (tests: to rounding in double precision). The beams come in mirror pairs
    (:func:`_mirror_beam_powers`: half the products), a few bins at a time (:data:`LOFAR_CHUNK_BINS`)."""

    def __init__(self, fs_hz: float, array: LineArray, settings: LofarSettings, n_samples: int):
        self.settings = settings
        idx, self.freqs_hz, w = _lofar_bins(int(n_samples), fs_hz, lofar_band(array, fs_hz, settings))
        #: the rectangular rfft bins :meth:`add` takes: the band's and one beyond each edge (bin >= 1: low > 0), but
        #: the last rfft bin when the band reaches it (an odd window up to fs / 2; the bin beyond it is its conjugate)
        self.bins = slice(int(idx[0]) - 1, min(int(idx[-1]) + 2, int(n_samples) // 2 + 1))
        self._mirror_top = int(idx[-1]) + 2 > int(n_samples) // 2 + 1
        self._weights = _mirror_weights(self.freqs_hz, array, settings.cone_deg)
        self._weights32 = self._weights.astype(np.float32)
        self._scale = 2.0 / (fs_hz * np.sum(w**2))
        self._sum, self._count, self._lines = 0.0, 0, []
        self._power: np.ndarray | None = None  # the beam powers' buffer of :meth:`add` (F, B, K)

    def add(self, spectra: np.ndarray) -> None:
        """Add K windows' rectangular spectra (K, N, bins of :attr:`bins`) in time order.

        Parameters
        ----------
        spectra : ndarray (K, N, W)
            rfft of each window (no window function) over :attr:`bins`; complex64 spectra are beamformed in single
            precision (the front end's ``fft_precision``), others in double; the sums are double.
        """
        x = np.asarray(spectra)
        if self._mirror_top:  # X(k + 1) = conj(X(k)) at the last bin k = (M - 1) / 2 of an odd window M
            x = np.concatenate([x, np.conj(x[:, :, -1:])], axis=2)
        single = x.dtype == np.complex64
        xt = x.astype(np.complex64 if single else np.complex128, copy=False).transpose(2, 1, 0)  # (W, N, K)
        weights = self._weights32 if single else self._weights
        shape = (weights.shape[0], self.settings.beams, xt.shape[2])  # (F, B, K)
        if self._power is None or self._power.shape != shape or self._power.dtype != weights.dtype:
            self._power = np.empty(shape, dtype=weights.dtype)  # reused by the next batch: no fresh pages per batch
        power = self._power
        for a in range(0, power.shape[0], LOFAR_CHUNK_BINS):
            _mirror_beam_powers(xt[a: a + LOFAR_CHUNK_BINS + 2], weights[a: a + LOFAR_CHUNK_BINS],
                                power[a: a + LOFAR_CHUNK_BINS])
        k, length = 0, self.settings.integration
        while k < power.shape[2]:
            take = min(length - self._count, power.shape[2] - k)
            self._sum = self._sum + power[:, :, k:k + take].sum(axis=2, dtype=float)
            self._count, k = self._count + take, k + take
            if self._count == length:  # a period complete: normalised now (along frequency only, so period by
                # period gives the same numbers): 12 bytes a cell kept, not the ~90 of normalising the whole
                # recording's gram at once
                self._lines.append(_normalised((self._scale / length) * self._sum.T, self.settings))
                self._sum, self._count = 0.0, 0

    def take_periods(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The periods completed since the last call, taken out (power (B, F), statistic (B, F) each): a live
        chain keeps its own bounded history of them (systems/live/); :meth:`gram` then holds none of them."""
        out, self._lines = self._lines, []
        return out

    def state(self) -> dict:
        """The open period's partial sum and window count (what a checkpoint keeps; the completed periods are the
        caller's, :meth:`take_periods`)."""
        return {"sum": self._sum, "count": self._count}

    def restore(self, state: dict) -> None:
        """Back to a :meth:`state`: the open period continues where it was."""
        self._sum, self._count = state["sum"], int(state["count"])

    def gram(self, window_s: float) -> LofarGram | None:
        """The gram of the complete integration periods added so far (a last incomplete one is dropped), or None
        when there is none.

        Parameters
        ----------
        window_s : float
            Window length (s): period k is centred at (k + 0.5) L window_s.

        Returns
        -------
        LofarGram or None
            As :func:`lofar_gram`.
        """
        if not self._lines:
            return None
        t = (np.arange(len(self._lines)) + 0.5) * self.settings.integration * window_s
        power = np.stack([p.astype(np.float32) for p, _ in self._lines])
        return LofarGram(t, self.settings.cone_deg, self.freqs_hz, power, np.stack([z for _, z in self._lines]))

    def power(self) -> np.ndarray:
        """The integrated spectra of the complete periods so far, in double precision.

        Returns
        -------
        ndarray (T, B, F)
            Mean PSD over each period's L windows per beam and bin (input units^2/Hz); T may be 0.
        """
        shape = (0, self.settings.beams, self.freqs_hz.size)
        return np.stack([p for p, _ in self._lines]) if self._lines else np.zeros(shape)


def _normalised(power: np.ndarray, s: LofarSettings) -> tuple[np.ndarray, np.ndarray]:
    """One period's integrated spectra (B, F) as they are and their statistic (power over its background, float32)."""
    stat = power / np.maximum(background(power, s), np.finfo(float).tiny)
    return power, stat.astype(np.float32)


def _gram(power: np.ndarray, freqs_hz: np.ndarray, s: LofarSettings, window_s: float) -> LofarGram:
    """The gram of integrated spectra (T, B, F): normalised along frequency, periods stamped at their centres."""
    stat = power / np.maximum(background(power, s), np.finfo(float).tiny)
    t = (np.arange(power.shape[0]) + 0.5) * s.integration * window_s
    return LofarGram(t, s.cone_deg, freqs_hz, power.astype(np.float32), stat.astype(np.float32))


def _window_sums(p: np.ndarray, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
    """Sum and count of p[..., k + j] for j in [lo, hi) (one side of the reference window), zero-padded at the
    band's edges (the edge bins use the reference bins there are)."""
    f = p.shape[-1]
    c = np.concatenate([np.zeros(p.shape[:-1] + (1,)), np.cumsum(p, axis=-1)], axis=-1)
    k = np.arange(f)
    a, b = np.clip(k + lo, 0, f), np.clip(k + hi, 0, f)
    return c[..., b] - c[..., a], (b - a).astype(float)


def _split_window_mean(p: np.ndarray, gap: int, ref: int) -> tuple[np.ndarray, np.ndarray]:
    s1, n1 = _window_sums(p, -gap - ref, -gap)
    s2, n2 = _window_sums(p, gap + 1, gap + 1 + ref)
    return s1 + s2, n1 + n2


def background(power: np.ndarray, settings: LofarSettings) -> np.ndarray:
    """The background mu_k along the last axis (frequency) of ``power`` (module doc).

    Parameters
    ----------
    power : ndarray (..., F)
        Integrated spectra.
    settings : LofarSettings
        Normaliser, gap, reference bins, censoring, integration (median bias).

    Returns
    -------
    ndarray (..., F)
        The background level (units of ``power``).
    """
    s = settings
    p = np.asarray(power, dtype=float)
    if s.normaliser == "median":
        from scipy.ndimage import median_filter
        from scipy.stats import gamma

        half = s.gap_bins + s.reference_bins
        foot = np.ones(2 * half + 1, dtype=bool)
        foot[s.reference_bins: s.reference_bins + 2 * s.gap_bins + 1] = False
        shape = (1,) * (p.ndim - 1) + foot.shape
        med = median_filter(p, footprint=foot.reshape(shape), mode="mirror")
        return med / gamma.median(s.integration, scale=1.0 / s.integration)
    total, count = _split_window_mean(p, s.gap_bins, s.reference_bins)
    mu = total / np.maximum(count, 1.0)
    if s.normaliser == "two-pass":
        kept = np.where(p <= s.censor * mu, p, 0.0)  # censored bins leave both the sum and the count
        total, _ = _split_window_mean(kept, s.gap_bins, s.reference_bins)
        count, _ = _split_window_mean((p <= s.censor * mu).astype(float), s.gap_bins, s.reference_bins)
        mu = np.where(count > 0, total / np.maximum(count, 1.0), mu)
    return mu


def line_threshold(settings: LofarSettings, reference_count=None):
    """Threshold t on z with P(z >= t | noise) = pfa: F(2L, 2LR) quantile, R = 2 ``reference_bins`` (module doc), or
    R = ``reference_count`` where fewer reference bins make the background.

    Parameters
    ----------
    settings : LofarSettings
        pfa, integration L and reference bins.
    reference_count : int or ndarray of int, optional
        The reference bins R of each cell (at least 1; not given: 2 ``reference_bins``).

    Returns
    -------
    float or ndarray
        t (ratio to the background), per cell where ``reference_count`` is given.
    """
    from scipy.special import fdtri  # the F quantile itself: scipy.stats costs a third of a second to import

    dof = 2 * settings.integration
    if reference_count is None:
        return float(fdtri(dof, dof * 2 * settings.reference_bins, 1.0 - settings.pfa))
    return fdtri(dof, dof * np.asarray(reference_count), 1.0 - settings.pfa)


def integrate(power: np.ndarray, n: int) -> np.ndarray:
    """Mean of consecutive groups of ``n`` windows along axis 0 (a last incomplete group is dropped).

    Parameters
    ----------
    power : ndarray (K, ...)
        Per-window spectra.
    n : int
        Windows per group L.

    Returns
    -------
    ndarray (K // n, ...)
        The integrated spectra.
    """
    p = np.asarray(power)
    t = p.shape[0] // n
    return p[: t * n].reshape((t, n) + p.shape[1:]).mean(axis=1)


def lofar_gram(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, settings: LofarSettings,
               window_s: float) -> LofarGram:
    """Beam spectra of every window, integrated over L windows and normalised along frequency (module doc).

    Parameters
    ----------
    blocks : iterable of ndarray (N, window_s fs)
        The recording's windows in order.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array.
    settings : LofarSettings
        Band, beams, integration and normaliser.
    window_s : float
        Window length (s): period k is centred at (k + 0.5) L window_s.

    Returns
    -------
    LofarGram
        The integrated gram (float32 power and statistic).
    """
    s = settings
    band = lofar_band(array, fs_hz, s)
    lines, group, prep = [], [], None
    for block in blocks:
        group.append(np.asarray(block, float))
        if len(group) == s.integration:  # one batched transform and product per integration period
            x = np.stack(group)
            if prep is None:  # as beam_power_spectra, the bins and beams once (F B N complex exponentials)
                idx, f, w = _lofar_bins(x.shape[2], fs_hz, band)
                prep = idx, f, w, _lofar_steering(f, array, s.cone_deg, x.shape[1]), 2.0 / (fs_hz * np.sum(w**2))
            idx, f, w, steer, scale = prep
            lines.append(_beam_psd(np.fft.rfft(x * w, axis=2)[:, :, idx[0]: idx[-1] + 1], steer, scale).mean(axis=0))
            group = []
    require(bool(lines), f"the recording holds fewer windows than one LOFAR integration ({s.integration})")
    return _gram(np.stack(lines), prep[1], s, window_s)


def detect_lines(gram: LofarGram, settings: LofarSettings) -> LineDetections:
    """Cells of the gram at or above :func:`line_threshold` that are local maxima along frequency and across beams,
    less the sidelobes: a cell whose line power over the background, P - mu = mu (z - 1), is more than
    ``sidelobe_guard_db`` below the largest over the beams at that bin and period; the ``edge_bins`` at each end of
    the band are not searched.

    Parameters
    ----------
    gram : LofarGram
        Integrated, normalised spectra.
    settings : LofarSettings
        The threshold's pfa, integration and reference bins.

    Returns
    -------
    LineDetections
        One row per line and period, SNR = 10 log10(z - 1) dB.
    """
    parts = [_detect_periods(gram, settings, slice(i, i + PERIODS_PER_CHUNK))
             for i in range(0, max(len(gram.time_s), 1), PERIODS_PER_CHUNK)]
    t, b, k, zz = (np.concatenate([p[j] for p in parts]) for j in range(4))
    return LineDetections(gram.time_s[t], gram.cone_deg[b], gram.freqs_hz[k], zz,
                          10.0 * np.log10(np.maximum(zz - 1.0, 1e-6)), b.astype(np.int64))


#: periods searched at once by :func:`detect_lines` (every test is within one period, so chunks change nothing
#: but the memory: the working arrays of a whole long recording's gram would be tens of bytes a cell)
PERIODS_PER_CHUNK = 64


def _detect_periods(gram: LofarGram, settings: LofarSettings, periods: slice):
    """(period, beam, bin indices, z) of the detections among ``periods`` of the gram (:func:`detect_lines`)."""
    z = np.asarray(gram.statistic[periods], dtype=float)
    pad_f = np.pad(z, ((0, 0), (0, 0), (1, 1)), constant_values=-np.inf)
    pad_b = np.pad(z, ((0, 0), (1, 1), (0, 0)), constant_values=-np.inf)
    peak = (z > pad_f[..., :-2]) & (z >= pad_f[..., 2:]) & (z > pad_b[:, :-2]) & (z >= pad_b[:, 2:])
    excess = np.asarray(gram.power[periods], float) * (1.0 - 1.0 / np.maximum(z, 1e-12))  # P - mu, mu = P / z
    main = excess >= np.max(excess, axis=1, keepdims=True) * 10.0 ** (-settings.sidelobe_guard_db / 10.0)
    inner = np.zeros(z.shape[2], bool)
    inner[settings.edge_bins: z.shape[2] - settings.edge_bins] = True
    t, b, k = np.nonzero(peak & main & inner & (z >= line_threshold(settings)))
    return t + (periods.start or 0), b, k, z[t, b, k]
