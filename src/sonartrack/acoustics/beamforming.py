"""Bearing-time record of a uniform line array: beam powers per window, normalised across bearing, peaks.

Geometry (as sim/array_signals.py): element n (0 = front) sits s_n = ((N - 1)/2 - n) d ahead of the array
centre; a plane wave from cone angle theta (0 = ahead along the axis, 180 = astern) reaches it at
tau_n = -s_n cos(theta) / c = (n - (N - 1)/2) kappa, with kappa = d cos(theta) / c.

Conventional frequency-domain beamforming (``cbf``; Van Trees, Optimum Array Processing, sec. 2.2): with
X_n(f) the rfft of channel n over one window, the beam output and its power over the band are

    Y(theta, f) = sum_n exp(+2 pi i f tau_n(theta)) X_n(f),      P(theta) = sum_{f in band} |Y(theta, f)|^2.

On a uniform line |Y|^2 depends on the element pairs only through their lag l = m - n:

    |Y|^2 = r_0(f) + 2 Re sum_{l=1}^{N-1} r_l(f) exp(2 pi i f l kappa),   r_l(f) = sum_n conj(X_n(f)) X_{n+l}(f)

so P is ONE real matrix product: a fixed steering matrix (B beams x (1 + 2 (N-1) n_bins)) times the vector
[sum_f r_0, Re r_l(f), Im r_l(f)] of the window (windows batched), exact, with no interpolation between beams.
The grid is symmetric about 90 deg and cos(180 deg - theta) = -cos(theta), so the mirror beam has the same cosine
terms and the opposite sine terms: with a = sum Re r_l 2 cos(.) and b = sum Im r_l (-2 sin(.)) over the first half
of the beams, P(theta) = sum_f r_0 + a + b and P(180 deg - theta) = sum_f r_0 + a - b (half the products and half
the steering matrix). On the rfft grid f_j = j df the phase 2 pi f_j l kappa depends on lag l and bin j only through
their product q = l j, so the lags of the pairs with one product are summed first and the matrix has one column per
distinct product (46 % of the pairs at 32 elements over 50-1000 Hz in 1 Hz bins). The channels' spectra and the
lags are computed in the precision ``fft_precision`` asks, the products in double.

Split-array (``split-array``; paper P0 applied to a line array): the front and rear halves are summed
(unsteered, so each half hears mainly near broadside), band-passed, and cross-correlated
(acoustics/xcorr_bearing.py ``correlate_window``); their centres are D = (N - floor(N/2)) d apart, and lag
tau maps to cone angle theta = arccos(c tau / D). The correlation is sampled on the cone grid at
tau_b = D cos(theta_b) / c by linear interpolation between lags.

Peak positions (CBF over one band, ``peak_interpolation = pattern``): the peaks of each window are refined jointly
with the array's own broadband beam pattern (:func:`pattern_sum`, :func:`resolve_peaks`), so that a louder ship's
lobes do not pull a weaker ship's peak: measured on the passive-chain study's 32 scenes, that pull was a slowly
varying bias of 0.13 deg rms (median target; up to 0.37 deg), correlated over tens of scans, which the TMA took for
information; and a ship hidden on a louder one's lobe gets its own peak (:func:`add_hidden_peaks`).

The array (N, d, c) is one :class:`~sonartrack.acoustics.line_array.LineArray`; the processing band is
resolved and checked once per recording (:func:`front_end_band`) and handed to the power functions.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal, Protocol

import numpy as np

from sonartrack.acoustics.blas_threads import blas_reachable, one_blas_thread
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.lofar import LofarAccumulator, LofarGram, LofarSettings
from sonartrack.acoustics.xcorr_bearing import PeakRecord, correlate_window
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting

#: MAD of a Gaussian sample = 0.6745 sigma, so 1.4826 MAD estimates sigma
MAD_TO_SIGMA = 1.4826
#: windows per batched steering product (memory: batch x 2 Q float64, Q the band's lag-bin products: ~7 MB at 32
#: elements over 50-1000 Hz)
BATCH_WINDOWS = 32
#: windows whose lag vectors are computed together (:func:`_lag_vectors`): the element transforms' arrays of a few
#: windows stay in the core's cache (measured at 32 x 8 kHz, whitening included: 0.31 s per 10 minutes against 0.57 s
#: for whole batches)
LAG_CHUNK_WINDOWS = 4


class BeamformerSettings(Settings):
    """Front end of ``sonartrack passive`` for an N-element line array (module doc).

    Default ``cbf`` over the automatic band: the band the ships radiate (``auto_band_hz``, 50-1000 Hz) from at least
    c / (N d) up to at most fs / 2, every bin steered at its own frequency and whitened, so the narrow beams of the
    upper bins set the picture and the grating lobes above f_a = c / (2 d), which move with frequency, smear out.
    Measured (chain of ``sonartrack passive``, one target per ship wanted; per ship: fraction of its detectable
    windows held, targets, side) on the default scene of ``sonartrack simulate`` (16 x 2.5 m, 4 kHz, 1200 s) and
    two scenes not tuned to (B: 32 x 1.25 m, 8 kHz, ships radiating 50-2000 Hz, turn +60 deg; C: 24 x 5 m, 6 kHz,
    turn -60 deg; 900 s each):

    ===================  ========================================  ==========================================
    scene                old default: octave [f_a/2, f_a]          automatic band (this default)
    ===================  ========================================  ==========================================
    default              5 targets for 3 ships (trawler, tanker    3 targets for 3 ships, sides right,
                         in 2 fragments, 2 sides unresolved)       held 0.99/0.99/1.00
    B (f_a 600 Hz)       4 targets for 3 ships (yacht, -10 dB,     2 targets, ferry/coaster held 0.99/1.00;
                         in 2 fragments, side wrong/unresolved)    the yacht missed (detectable 16 s)
    C (f_a 150 Hz)       3 for 3, sides right                      3 for 3, sides right, ranges within 1 %
    ===================  ========================================  ==========================================

    Per-window detection (first 300 s; fraction of windows with a peak within 2 deg of the true cone angle),
    default scene merchant/trawler/tanker: whole band 1.00/1.00/1.00; per-octave z (octaves from 50 Hz)
    combined by their mean 1.00/0.99/0.91, sqrt(bins)-weighted mean 1.00/1.00/0.85, max 0.97/0.76/0.24; the
    alias-free octave alone 0.96/0.77/0.96. Scene B's yacht: whole band 0.00, octave alone 0.54, the whole band's
    z plus the octave's (``add_alias_free_octave``) 0.53, which in the chain holds it 0.63 (one fragment, side
    unresolved) but on the default scene breaks the trawler's track at the crossing (its wider beams pull the
    crossing ships together): off by default. Known limit: an array of a few wavelengths (8 x 0.5 m) with two ships
    whose beams cover most of 0..180 deg gives no z above 4 (the median and MAD across bearing are the ships');
    one loud ship is found (tests).

    Noise only (the default array, ``ships = []``, 1800 s; the automatic band): 0.043 peaks a window at z >= 4
    (0.32 at 3, 0.0044 at 5); their excess z - threshold exponential (median and 90 % quantile within 7 % of the
    exponential's) with rate alpha = 1.92 per unit z at threshold 3 (95 % interval 1.77..2.08), 2.16 at 4
    (1.68..2.63); 32 x 1.25 m at 8 kHz (900 s): 0.038 a window at z >= 4, alpha 2.06 at 3 (1.82..2.30).

    Split array (P0) on the default scene's 150-300 Hz: detection 0.08 against CBF's 0.70 (its unsteered
    half-array sums hear only near broadside). The submarine (-20 dB per element) stays below any usable
    threshold in 1 s windows."""

    method: Literal["cbf", "split-array", "mvdr"] = setting("cbf", "beamformer: cbf = conventional frequency-domain "
                                                            "beamforming over the band; split-array = P0's cross-"
                                                            "correlation of the two half-array sums; mvdr = Capon "
                                                            "beams with diagonal loading (acoustics/mvdr.py)", unit="")
    band_hz: list[float] | None = setting(None, "processing band [low, high) (not set: auto_band_hz capped at fs / 2, "
                                                "grating lobes above c / (2 d) accepted)",
                                          unit="Hz", min_length=2, max_length=2)
    auto_band_hz: list[float] = setting(default_factory=lambda: [50.0, 1000.0],
                                        doc="the automatic processing band when band_hz is not set: the band where "
                                            "ships' broadband radiated noise stands above the sea noise, capped at "
                                            "fs / 2 (measured better than the octave below aliasing and than "
                                            "combining per-octave statistics: class doc)", unit="Hz",
                                        min_length=2, max_length=2)
    add_alias_free_octave: bool = setting(False, "with the automatic band: add the normalised level of the octave "
                                                 "below aliasing [f_a / 2, f_a] to the whole band's, and normalise "
                                                 "again (finds a weak ship among a loud one's grating lobes; its "
                                                 "wider beams bias crossing ships: class doc)", unit="")
    allow_grating_lobes: bool = setting(False, "accept a band_hz above the aliasing frequency c / (2 d) (grating "
                                               "lobes, smeared over a broad band) instead of refusing it", unit="")
    window_s: float = setting(1.0, "observation window of one line of the bearing-time record", unit="s", gt=0)
    beams: int = setting(181, "cone-angle grid: this many beams uniform in 0..180 deg (181 = 1 deg steps)",
                         unit="1", ge=3)
    peak_interpolation: Literal["pattern", "parabola"] = setting(
        "pattern", "sub-beam peak position: pattern = the array's own broadband beam pattern fitted to each peak with "
        "the other peaks' lobes taken out (:func:`resolve_peaks`; CBF over one band only, else parabola); parabola = a "
        "parabola through the three beams around the maximum (biased by a louder ship's lobes: the peak follows "
        "their slope)", unit="")
    hidden_peaks: bool = setting(True, "with the pattern interpolation: also report a ship hidden on a louder one's "
                                       "lobe, a maximum of z minus the peaks' fitted patterns at or above the "
                                       "threshold and more than a half-power half-width from every peak "
                                       "(:func:`add_hidden_peaks`; keeps a weak ship through a crossing)", unit="")
    threshold: float = setting(4.0, "detection threshold on the normalised statistic z = (P - median) / "
                                    "(1.4826 MAD) across bearing", unit="1")
    max_peaks: int = setting(8, "largest number of peaks kept per window (the highest z)", unit="1", ge=1)
    whiten: bool = setting(True, "divide each frequency bin by its mean element power before beamforming, so that "
                                 "every bin weighs the same (a loud tonal line does not dominate the band)", unit="")
    spread_floor: float = setting(1e-3, "normaliser: the spread is at least this fraction of the background "
                                        "(guards against a zero or constant recording)", unit="1", gt=0)
    censor_passes: int = setting(
        0, "normaliser: the median and MAD are measured again without the beams at or above the threshold, up to "
        "this many times (normalise_across_bearing), for loud ships near endfire whose wide lobes cover much of the "
        "grid and set the background. At 5, on 24 x 1.25 m at 6 kHz a crossing pair at -4 to -7 dB is held 8-740 s "
        "and 90-900 s (both ranges within 0.3 km) instead of 536-726 s, and on 40 x 0.9 m at 8 kHz a -7 dB tanker "
        "8-894 s instead of 178-330 s; but on the passive-chain study crossings kept fell 0.81 -> 0.75 (jumped 1 -> "
        "4) and one determined ML lay 333 sds off (a track that took another ship after a crossing): off by default; "
        "0: once, over every beam", unit="1", ge=0)
    fft_precision: Literal["single", "double"] = setting(
        "single", "precision of the channels' FFT and of the lags across elements (the products are double): single "
        "halves their time with errors ~5e-8 of a beam's power (~1e-5 in z), far below the noise the normaliser "
        "measures; double for reference checks", unit="")

    @property
    def cone_deg(self) -> np.ndarray:
        """The beams' cone angles (deg), uniform 0..180."""
        return np.linspace(0.0, 180.0, self.beams)


@dataclass(frozen=True)
class BearingTimeRecord:
    """The bearing-time record: window centres (T,), beam cone angles (B,), normalised level z (T, B) and
    the peaks (time, cone angle deg as ``bearing_deg``, amplitude = z at the peak); ``lofar``: the narrowband
    LOFAR gram per beam made in the same pass (:func:`bearing_time_record` with ``narrowband``), or None."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    level: np.ndarray
    peaks: PeakRecord
    lofar: LofarGram | None = None


def front_end_band(array: LineArray, settings: BeamformerSettings, fs_hz: float) -> Band:
    """The front end's band on ``array``, resolved and checked once before the first window.

    Parameters
    ----------
    array : LineArray
        The line array (element count, spacing, sound speed).
    settings : BeamformerSettings
        The front end's settings (its ``band_hz``, ``allow_grating_lobes`` and ``window_s``).
    fs_hz : float
        Sample rate of the recording (Hz).

    Returns
    -------
    Band
        ``settings.band_hz``, or ``settings.auto_band_hz`` capped at fs / 2 (:meth:`LineArray.band`).
        Raises :class:`~sonartrack.core.errors.InputError` when the band does not fit the array or the sample
        rate, or when a window holds fewer than 16 samples.
    """
    band = array.band(fs_hz, settings.band_hz, settings.allow_grating_lobes, settings.auto_band_hz)
    require(settings.window_s * fs_hz >= 16,
            f"window_s {settings.window_s:g} s holds fewer than 16 samples at {fs_hz:g} Hz")
    return band


def _band_bins(n_samples: int, fs_hz: float, band_hz) -> tuple[np.ndarray, np.ndarray]:
    """(indices of the rfft bins in [low, high), their frequencies Hz)."""
    f = np.fft.rfftfreq(n_samples, 1.0 / fs_hz)
    idx = np.nonzero((f >= band_hz[0]) & (f < band_hz[1]) & (f > 0))[0]
    return idx, f[idx]


#: the steering of one band (:func:`_steering_matrix`): C, S (ceil(B / 2), Q), the beam count B, the band's first rfft
#: bin j0 and the Q distinct lag-bin products q = l j (sorted)
Steering = tuple[np.ndarray, np.ndarray, int, int, np.ndarray]


def lag_bin_products(n_elements: int, bins: np.ndarray) -> np.ndarray:
    """The distinct products q = l j (sorted) of the lags l = 1..N-1 of an N-element line and the rfft bins j: the
    columns of the CBF's steering matrix (:func:`_steering_matrix`; module doc).

    Parameters
    ----------
    n_elements : int
        N.
    bins : ndarray of int
        The band's rfft bin indices j.

    Returns
    -------
    ndarray of int
        The Q distinct products, ascending (integers: exact).
    """
    return np.unique(np.arange(1, n_elements)[:, None] * np.asarray(bins, dtype=np.int64)[None, :])


@lru_cache(maxsize=4)
def _steering_matrix(n_elements: int, n_samples: int, fs_hz: float, spacing_m: float, sound_speed_mps: float,
                     band: tuple[float, float], beams: int) -> tuple[np.ndarray, Steering]:
    """(band bin indices, steering (C, S, B, j0, q)) of P = M v (module doc) for the first half of the beams (the
    mirror beams at 180 deg - theta reuse them: module doc).

    On the rfft grid f_j = j df (df = fs / M samples) the phase 2 pi f_j l kappa of lag l at bin j depends on the pair
    only through the product q = l j: with the Q distinct products q (sorted), C = 2 cos(2 pi q df kappa) and
    S = -2 sin(2 pi q df kappa), (ceil(B / 2), Q) each, and the lag vectors summed over the pairs of each product
    first (:func:`_lag_vectors`). Q is 46 % of the (N - 1) n_bins pairs at 32 elements over 50-1000 Hz in 1 Hz bins
    (13611 of 29450; 43 % at 64 elements): the steering product, the front end's largest, shrinks as much."""
    idx, _ = _band_bins(n_samples, fs_hz, band)
    products = lag_bin_products(n_elements, idx)
    half = (beams + 1) // 2
    kappa = spacing_m * np.cos(np.deg2rad(np.linspace(0.0, 180.0, beams)[:half])) / sound_speed_mps  # (B/2,)
    phase = np.outer(kappa, (2.0 * np.pi * fs_hz / n_samples) * products)  # (B/2, Q): 2 pi (q df) kappa
    c = 2.0 * np.cos(phase)
    s = np.sin(phase, out=phase)
    s *= -2.0
    return idx, (c, s, beams, int(idx[0]) if idx.size else 1, products)


def _dtypes(settings: BeamformerSettings) -> tuple[type, type]:
    """(real, complex) dtype of the front end's spectra and products (``fft_precision``)."""
    return (np.float32, np.complex64) if settings.fft_precision == "single" else (np.float64, np.complex128)


def _rfft_bins(blocks: np.ndarray, bins: slice, real_dtype: type) -> np.ndarray:
    """rfft along the last axis of ``blocks`` in ``real_dtype``, the ``bins`` kept (scipy's pocketfft: in single
    precision 7 times numpy's speed on 8000-sample windows, whose float32 path is slower than its float64 one)."""
    import scipy.fft

    return scipy.fft.rfft(np.asarray(blocks, dtype=real_dtype), axis=-1)[..., bins]


def _lag_vectors(spectra: np.ndarray, whiten: bool, first_bin: int, products: np.ndarray) -> np.ndarray:
    """[sum_f r_0, Re R_q, Im R_q] (K, 1 + 2 Q) of band spectra (K, N, F) whose first rfft bin is j0 =
    ``first_bin``, with R_q = sum of r_l(f_j) over the lag-bin pairs (l >= 1, j) of product l j = q, for the Q
    products ``products`` (:func:`_steering_matrix`; module doc). Computed in the spectra's precision (R_q sums at
    most a few pairs) and returned in double (the product with the steering matrix sums ~1e4 terms that cancel: in
    single precision it errs by ~2e-6 of the power, 3e-4 in z, against 5e-8 and 1e-5 in double).

    All lags at once through the element axis: with A = DFT_2N of X_n (zero-padded to 2N, so nothing wraps),
    r_l = IDFT_2N(|A|^2)[l] = sum_n conj(X_n) X_{n+l} for 0 <= l < N (Wiener-Khinchin; 2 N log 2N operations per
    bin instead of N^2 / 2); |A|^2 is real, so its inverse transform is Hermitian and ``ihfft`` gives its first
    half at half the cost.

    ``whiten``: the lags of the spectra divided, per window and bin, by the root of their mean element power
    p(f) = r_0(f) / N are r_l(f) / p(f) = r_l(f) N / r_0(f) (a bin of zero power left as it is): the division is made
    on the lags rather than on the N spectra, which spares a pass over them. Windows go through in chunks of
    :data:`LAG_CHUNK_WINDOWS`."""
    k, n, f = spectra.shape
    p = products.size
    out = np.empty((k, 1 + 2 * p))
    span = np.empty((min(k, LAG_CHUNK_WINDOWS), int(products[-1]) - first_bin + 1 if p else 0), dtype=spectra.dtype)
    for a in range(0, k, LAG_CHUNK_WINDOWS):
        rows = slice(a, a + LAG_CHUNK_WINDOWS)
        lags = _chunk_lags(spectra[rows], whiten, out[rows, 0])
        summed = _sum_over_products(lags, first_bin, span)[:, products - first_bin]
        out[rows, 1:1 + p], out[rows, 1 + p:] = summed.real, summed.imag
    return out


def _chunk_lags(spectra: np.ndarray, whiten: bool, r0_sum: np.ndarray) -> np.ndarray:
    """The lags r_l(f), l = 1..N-1 (k, N - 1, F), of a few windows' spectra (k, N, F) in their precision, whitened
    (``whiten``: :func:`_lag_vectors`); sum_f r_0(f) of each window written into ``r0_sum`` (k,)."""
    import scipy.fft

    n = spectra.shape[1]
    a = scipy.fft.fft(spectra, 2 * n, axis=1, workers=1)
    power = np.square(a.real)
    power += np.square(a.imag)  # |A|^2, one temporary fewer than a.real**2 + a.imag**2 (the same numbers)
    r = scipy.fft.ihfft(power, axis=1, workers=1)  # (k, N + 1, F): lags 0..N
    r0 = r[:, 0].real.astype(float)  # sum_n |X_n(f)|^2 (k, F)
    if not whiten:
        r0_sum[:] = r0.sum(axis=1)
        return r[:, 1:n]
    w = n / np.where(r0 > 0, r0, n)  # 1 / mean element power per window and bin (1 where the bin is silent)
    r0_sum[:] = np.sum(r0 * w, axis=1)
    lags = r[:, 1:n]
    lags *= w.astype(r.real.dtype)[:, None, :]  # in place: r is this call's own array
    return lags


def _sum_over_products(lags: np.ndarray, first_bin: int, span: np.ndarray) -> np.ndarray:
    """sum of lags[:, l - 1, j - j0] over the pairs of each product q = l j, at q - j0 of a zeroed (k, q_max - j0 + 1)
    view of ``span`` (k <= its rows): lag l's bins j0, j0 + 1, .. land on q = l j0, l (j0 + 1), .., a stride of l,
    so each lag is one strided addition."""
    k, n_lags, f = lags.shape
    out = span[:k]
    out[...] = 0
    for lag in range(1, n_lags + 1):
        start = (lag - 1) * first_bin  # q - j0 at j = j0
        out[:, start: start + lag * (f - 1) + 1: lag] += lags[:, lag - 1]
    return out


def _steer(lag_vectors: np.ndarray, steer: Steering) -> np.ndarray:
    """P (K, B) of lag vectors [v_0, v_re, v_im] (K, 1 + 2 Q) and the steering (C, S, B, ..) of the first half of the
    beams: P(theta) = v_0 + v_re C^T + v_im S^T, and P(180 deg - theta) = v_0 + v_re C^T - v_im S^T (module doc).
    BLAS products on one thread (acoustics/blas_threads.py; einsum, 9 times slower, where numpy's OpenBLAS cannot
    be reached)."""
    c, s, beams = steer[:3]
    n = c.shape[1]
    v0, v_re, v_im = lag_vectors[:, :1], lag_vectors[:, 1:1 + n], lag_vectors[:, 1 + n:]
    if not blas_reachable():
        even, odd = np.einsum("kj,bj->kb", v_re, c), np.einsum("kj,bj->kb", v_im, s)
    else:
        with one_blas_thread():
            even, odd = v_re @ c.T, v_im @ s.T
    mirror = (v0 + even - odd)[:, :beams - c.shape[0]]
    return np.concatenate([v0 + even + odd, mirror[:, ::-1]], axis=1)


def _band_of(array: LineArray, settings: BeamformerSettings, fs_hz: float, band: Band | None) -> Band:
    return band if band is not None else array.band(fs_hz, settings.band_hz, settings.allow_grating_lobes,
                                                    settings.auto_band_hz)


def cbf_powers(blocks: np.ndarray, fs_hz: float, array: LineArray, settings: BeamformerSettings,
               band: Band | None = None) -> np.ndarray:
    """CBF beam powers P(theta) of K windows at once (module doc).

    Parameters
    ----------
    blocks : ndarray (K, N, M)
        K windows of M samples of the N elements (element 0 = front).
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array (spacing and sound speed of the steering delays).
    settings : BeamformerSettings
        ``beams`` and ``whiten``; its ``band_hz`` when ``band`` is None.
    band : Band, optional
        The processing band, resolved once by the caller (:func:`front_end_band`); None resolves it here.

    Returns
    -------
    ndarray (K, B)
        Beam power over the band at each of the B cone angles ``settings.cone_deg`` (input units^2).
    """
    s = settings
    _, n, m = blocks.shape
    band = _band_of(array, s, fs_hz, band)
    idx, steer = _band_steering(n, m, fs_hz, array, s, band)
    bins = slice(idx[0], idx[-1] + 1) if idx.size else slice(0, 0)  # contiguous bins: a view, not a copy
    return _cbf_from_spectra(_rfft_bins(blocks, bins, _dtypes(s)[0]), steer, s.whiten)


def _band_steering(n: int, m: int, fs_hz: float, array: LineArray, s: BeamformerSettings,
                   band: Band) -> tuple[np.ndarray, Steering]:
    """(bin indices, steering (C, S, B, j0, q): :func:`_steering_matrix`) of ``band`` for N elements and M-sample
    windows (cached: built once per recording)."""
    return _steering_matrix(n, m, float(fs_hz), float(array.spacing_m), float(array.sound_speed_mps),
                            band.as_tuple(), int(s.beams))


def _cbf_from_spectra(spectra: np.ndarray, steer: Steering, whiten: bool) -> np.ndarray:
    """Beam powers (K, B) of band spectra (K, N, F): whitened (``whiten``), lag vectors, one product with the
    steering matrix (module doc); the spectra's precision sets the transforms' (single: ~5e-8 of a beam's power,
    ~1e-5 in z, far below the noise the normaliser measures), the product is in double."""
    return _steer(_lag_vectors(spectra, whiten, steer[3], steer[4]), steer)


def alias_free_octave(array: LineArray, settings: BeamformerSettings, fs_hz: float, band: Band) -> Band | None:
    """The optional second sub-band of the automatic front end (``add_alias_free_octave``): the octave below the
    array's aliasing frequency, [f_a / 2, f_a] with f_a = min(c / (2 d), fs / 2), when the automatic band
    (``band_hz`` not set, CBF) reaches above f_a and holds that octave; None otherwise.

    Parameters
    ----------
    array : LineArray
        The line array.
    settings : BeamformerSettings
        The front end's settings (``band_hz`` and ``method``).
    fs_hz : float
        Sample rate (Hz).
    band : Band
        The resolved processing band (:func:`front_end_band`).

    Returns
    -------
    Band or None
        The octave, or None.
    """
    if not settings.add_alias_free_octave or settings.band_hz is not None or settings.method != "cbf":
        return None
    f_a = array.aliasing_hz(fs_hz)
    inside = band.low_hz <= 0.5 * f_a and f_a < band.high_hz
    return Band(0.5 * f_a, f_a) if inside and 0.5 * f_a * settings.window_s >= 8 else None


def combined_statistic(z_band: np.ndarray, z_octave: np.ndarray) -> np.ndarray:
    """The automatic front end's statistic before its final normalisation: z_band + z_octave, the normalised
    levels of the whole band and of its alias-free octave (class doc of :class:`BeamformerSettings`: the whole band
    gives narrow beams where grating lobes smear out, the octave a weak ship next to a loud one's grating lobes).

    Parameters
    ----------
    z_band, z_octave : numpy.ndarray
        (B,) or (K, B) normalised beam levels (dimensionless) of the whole band and of the octave, same shape.

    Returns
    -------
    numpy.ndarray
        Their sum, same shape.
    """
    return np.asarray(z_band, float) + np.asarray(z_octave, float)


def split_array_powers(block: np.ndarray, fs_hz: float, array: LineArray, settings: BeamformerSettings,
                       band: Band | None = None) -> np.ndarray:
    """Cross-correlation of the two half-array sums sampled on the cone grid (module doc, paper P0).

    Parameters
    ----------
    block : ndarray (N, M)
        One window of the N elements.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array (spacing and sound speed: the halves' centres are (N - floor(N/2)) d apart).
    settings : BeamformerSettings
        ``beams``; its ``band_hz`` when ``band`` is None.
    band : Band, optional
        The processing band (:func:`front_end_band`); None resolves it here.

    Returns
    -------
    ndarray (B,)
        The correlation at the lag of each cone angle of ``settings.cone_deg``.
    """
    s = settings
    c = array.sound_speed_mps
    n, m = block.shape
    half = n // 2
    separation_m = (n - half) * array.spacing_m
    sums = np.stack([block[:half].sum(axis=0), block[n - half:].sum(axis=0)])
    spectra = np.fft.rfft(sums - sums.mean(axis=1, keepdims=True), axis=1)
    idx, _ = _band_bins(m, fs_hz, _band_of(array, s, fs_hz, band).as_tuple())
    keep = np.zeros(spectra.shape[1], dtype=bool)
    keep[idx] = True
    front, rear = np.fft.irfft(np.where(keep, spectra, 0.0), m, axis=1)
    max_lag = int(np.ceil(separation_m / c * fs_hz)) + 1
    cc = correlate_window(front, rear, max_lag)
    lag_samples = separation_m * np.cos(np.deg2rad(s.cone_deg)) / c * fs_hz
    return np.interp(lag_samples, np.arange(-max_lag, max_lag + 1), cc)


def beam_powers(block: np.ndarray, fs_hz: float, array: LineArray, cone_deg: np.ndarray,
                settings: BeamformerSettings) -> np.ndarray:
    """Beam powers of one window with the method of ``settings`` (:func:`cbf_powers`, :func:`split_array_powers` or
    acoustics/mvdr.py ``mvdr_powers``).

    Parameters
    ----------
    block : ndarray (N, M)
        One window of the N elements.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array.
    cone_deg : ndarray (B,)
        The beams' cone angles (deg); must be ``settings.cone_deg``.
    settings : BeamformerSettings
        The front end's settings.

    Returns
    -------
    ndarray (B,)
        The beam powers.
    """
    x = np.asarray(block, dtype=float)
    cone = np.asarray(cone_deg, dtype=float)
    require(cone.shape == settings.cone_deg.shape and np.allclose(cone, settings.cone_deg),
            f"cone_deg must be settings.cone_deg ({settings.beams} beams uniform in 0..180 deg)")
    if settings.method == "split-array":
        return split_array_powers(x, fs_hz, array, settings)
    if settings.method == "mvdr":
        from sonartrack.acoustics.mvdr import mvdr_powers

        return mvdr_powers(x[None], fs_hz, array, settings)[0]
    return cbf_powers(x[None], fs_hz, array, settings)[0]


def normalise_across_bearing(power: np.ndarray, settings: BeamformerSettings) -> np.ndarray:
    """Detection statistic z = (P - median_b P) / max(1.4826 MAD_b P, spread_floor |median_b P|), per window.

    Why median and MAD: the ships occupy a few beams of the grid, so the median across bearing is the noise
    background and the MAD its spread, both unmoved by the ships (breakdown point 50 %); a split-window (CFAR)
    normaliser would need a guard width matched to the beam width, which changes 20-fold across the band
    and with cone angle. z is invariant to the recording's scale and offset (any recording level works);
    for noise-only windows it is roughly standard normal at each beam (P sums ~2 n_bins chi-square terms).
    Works on (B,) or (K, B) (each row normalised alone).

    Where that breaks: loud ships near endfire, whose beams there are 1 / sin(theta) times wider in cone angle, lift
    more than half of the uniform cone-angle grid (two ships at 20-25 deg on 24 x 1.25 m), so the median and MAD are
    theirs and a weaker ship at z 6-7 over the true background is measured at 2-3. With ``censor_passes`` > 0 the
    median and MAD are measured again over the beams below the threshold, repeatedly (a censored estimate, as the
    LOFAR two-pass normaliser's, acoustics/lofar.py): noise alone, with no beam at the threshold, is normalised
    exactly as before; a row with fewer than a quarter of its beams below the threshold keeps its previous z.

    Parameters
    ----------
    power : numpy.ndarray
        (B,) or (K, B) beam powers (any linear unit), beams along the last axis.
    settings : BeamformerSettings
        Its ``spread_floor`` (dimensionless), ``threshold`` and ``censor_passes``.

    Returns
    -------
    numpy.ndarray
        z (dimensionless), same shape; 0 where the spread is 0.
    """
    p = np.asarray(power, dtype=float)
    z = _robust_z(p, p, settings.spread_floor)
    for _ in range(settings.censor_passes):
        keep = z < settings.threshold
        # at least a quarter of the beams stay in the background: a row mostly above threshold keeps its last z
        enough = keep.sum(axis=-1, keepdims=True) >= max(3, p.shape[-1] // 4)
        new = np.where(enough, _robust_z(p, np.where(keep | ~enough, p, np.nan), settings.spread_floor), z)
        if np.array_equal(new, z):
            break
        z = new
    return z


def _robust_z(p: np.ndarray, background: np.ndarray, spread_floor: float) -> np.ndarray:
    """(p - median) / max(1.4826 MAD, spread_floor |median|) with the median and MAD of ``background`` along the last
    axis (NaN: left out)."""
    median = np.median if background is p else np.nanmedian
    med = median(background, axis=-1, keepdims=True)
    spread = MAD_TO_SIGMA * median(np.abs(background - med), axis=-1, keepdims=True)
    spread = np.maximum(spread, spread_floor * np.abs(med))
    return np.divide(p - med, spread, out=np.zeros_like(p), where=spread > 0)


def pick_beam_peaks(z: np.ndarray, cone_deg: np.ndarray, settings: BeamformerSettings) -> tuple[np.ndarray, np.ndarray]:
    """(cone angle deg (k,), amplitude = z (k,)) of the local maxima of z at or above the threshold.

    The grid is mirrored at 0 and 180 deg (cos is even there), so a target at endfire is a local maximum;
    a parabola through the three beams around each maximum refines the angle (offset in (-0.5, 0.5) beams)
    and the height. At most ``max_peaks`` peaks, the highest, in increasing cone angle.

    Parameters
    ----------
    z : numpy.ndarray
        (B,) statistic of one window.
    cone_deg : numpy.ndarray
        (B,) the beams' cone angles (deg from the array's forward axis, 0 = ahead), uniform in 0..180.
    settings : BeamformerSettings
        Its ``threshold`` (on z) and ``max_peaks``.

    Returns
    -------
    cone_deg : numpy.ndarray
        (k,) refined cone angles (deg, within 0..180).
    amplitude : numpy.ndarray
        (k,) refined peak heights of z.
    """
    z = np.asarray(z, dtype=float)
    padded = np.concatenate([z[1:2], z, z[-2:-1]])
    mid = padded[1:-1]
    idx = np.nonzero((mid > padded[:-2]) & (mid >= padded[2:]) & (mid >= settings.threshold))[0]
    y0, y1, y2 = padded[idx], padded[idx + 1], padded[idx + 2]
    den = y0 - 2.0 * y1 + y2
    delta = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
    delta = np.clip(delta, -0.5, 0.5)
    height = y1 - 0.25 * (y0 - y2) * delta
    step = cone_deg[1] - cone_deg[0]
    angle = np.clip(cone_deg[idx] + delta * step, 0.0, 180.0)
    if len(idx) > settings.max_peaks:
        keep = np.sort(np.argsort(-height, kind="stable")[: settings.max_peaks])
        angle, height = angle[keep], height[keep]
    return angle, height


def pick_beam_peaks_rows(z: np.ndarray, cone_deg: np.ndarray, settings: BeamformerSettings
                         ) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`pick_beam_peaks` of each row of z (K, B), the K windows of a batch in one set of array operations:
    the same element-wise formulas (the same numbers), the ``max_peaks`` cut made per row where a row holds more.

    Parameters
    ----------
    z : numpy.ndarray
        (K, B) statistic of K windows.
    cone_deg : numpy.ndarray
        (B,) the beams' cone angles (deg), uniform in 0..180.
    settings : BeamformerSettings
        Its ``threshold`` and ``max_peaks``.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Per row, (cone angles deg (k,), amplitudes (k,)) as :func:`pick_beam_peaks` gives them.
    """
    z = np.asarray(z, dtype=float).reshape(-1, np.shape(z)[-1])
    padded = np.concatenate([z[:, 1:2], z, z[:, -2:-1]], axis=1)
    mid = padded[:, 1:-1]
    rows, idx = np.nonzero((mid > padded[:, :-2]) & (mid >= padded[:, 2:]) & (mid >= settings.threshold))
    y0, y1, y2 = padded[rows, idx], padded[rows, idx + 1], padded[rows, idx + 2]
    den = y0 - 2.0 * y1 + y2
    delta = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
    delta = np.clip(delta, -0.5, 0.5)
    height = y1 - 0.25 * (y0 - y2) * delta
    angle = np.clip(cone_deg[idx] + delta * (cone_deg[1] - cone_deg[0]), 0.0, 180.0)
    bounds = np.searchsorted(rows, np.arange(z.shape[0] + 1))
    out = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        ang, h = angle[a:b], height[a:b]
        if b - a > settings.max_peaks:
            keep = np.sort(np.argsort(-h, kind="stable")[: settings.max_peaks])
            ang, h = ang[keep], h[keep]
        out.append((ang, h))
    return out


#: sampling of the tabulated beam pattern in u = cos(theta): linear interpolation between samples errs by about
#: (step^2 / 8) |g''| < 1e-4 of the peak for main lobes down to 0.01 in u (64 elements x 2.5 m at 1 kHz: 0.009)
PATTERN_STEP_U = 1e-4
#: fractional-beam offsets of a source from a peak's beam at which the three-beam ratio is tabulated
PATTERN_DELTAS = np.linspace(-0.75, 0.75, 151)
#: passes of the joint refinement (each: amplitudes of all peaks, then each peak's vertex with the others' lobes
#: taken out); the positions move by < 1e-3 deg after the third on two ships 5 deg apart
PATTERN_ITERATIONS = 3


@dataclass(frozen=True, slots=True)
class BeamPattern:
    """The whitened CBF's response to one broadband plane wave, as a function of u - u_s (u = cos theta), and the
    three-beam ratio of a source near each beam (:func:`beam_pattern`).

    ``g`` the response at ``u_grid`` = 0, PATTERN_STEP_U, ... 2 (even in u - u_s; g(0) = 1); ``cone_deg`` the beams;
    ``ratio`` (B, D) the ratio q = (y_+ - y_-) / (2 y_0 - y_- - y_+) of the beams k - 1, k, k + 1 for a source at
    cone_deg[k] + delta step, delta = PATTERN_DELTAS; ``monotone`` (B,) whether q rises with delta at beam k (false
    at the grid's ends, whose mirrored neighbours are equal)."""

    u_grid: np.ndarray
    g: np.ndarray
    cone_deg: np.ndarray
    ratio: np.ndarray
    monotone: np.ndarray
    #: the main lobe's half-power half-width in u (g = 1/2 there)
    half_width_u: float

    def response(self, du: np.ndarray) -> np.ndarray:
        """g(u - u_s) at the offsets ``du`` in u (any shape; |du| <= 2), linear between the table's samples (the
        grid is uniform: the sample index by division, no search)."""
        x = np.minimum(np.abs(du) / PATTERN_STEP_U, self.g.size - 1.000001)
        i = x.astype(np.intp)
        w = x - i
        return self.g[i] * (1.0 - w) + self.g[i + 1] * w


def pattern_sum(du: np.ndarray, f0_hz: float, df_hz: float, n_bins: int, array: LineArray) -> np.ndarray:
    """The whitened CBF's broadband beam pattern g(du) of one plane wave, du = cos(theta) - cos(theta_s).

    Every bin of a whitened band weighs the same, so the power of the beam steered at theta is the sum over the
    bins f_k = f0 + k df (k < K) of the uniform line's array factor (Van Trees, Optimum Array Processing, sec. 2.4,
    eq. 2.97), written with the lags l of the module doc:

        g(du) = [N K + 2 sum_{l=1}^{N-1} (N - l) sum_k cos(2 pi f_k l d du / c)] / (N^2 K),

    and the sum over the bins in closed form, sum_k cos(a + k b) = sin(K b / 2) / sin(b / 2) cos(a + (K - 1) b / 2).
    Sources that are independent add their patterns in the expected power (their cross terms average out).

    Parameters
    ----------
    du : numpy.ndarray
        Offsets in u = cos(cone angle) (dimensionless), any shape.
    f0_hz, df_hz : float
        First bin and bin spacing of the band (Hz).
    n_bins : int
        Number of bins K (>= 1).
    array : LineArray
        Element count N, spacing d (m) and sound speed c (m/s).

    Returns
    -------
    numpy.ndarray
        g(du), same shape as ``du``; 1 at du = 0.
    """
    x = np.asarray(du, dtype=float)
    n, k = array.elements, int(n_bins)
    total = np.full(x.shape, float(n * k))
    scale = 2.0 * np.pi * array.spacing_m / array.sound_speed_mps * x
    for lag in range(1, n):
        a, half = scale * lag * f0_hz, 0.5 * scale * lag * df_hz
        sh = np.sin(half)
        flat = np.abs(sh) < 1e-9  # b/2 a multiple of pi: every bin in phase, the limit K cos(K b/2) / cos(b/2)
        kernel = np.where(flat, k * np.cos(k * half) / np.where(flat, np.cos(half), 1.0),
                          np.sin(k * half) / np.where(flat, 1.0, sh))
        total += 2.0 * (n - lag) * kernel * np.cos(a + (k - 1) * half)
    return total / (n * n * k)


def beam_pattern(array: LineArray, settings: BeamformerSettings, fs_hz: float, band: Band) -> BeamPattern | None:
    """The front end's beam pattern on ``array`` over ``band`` (:class:`BeamPattern`), cached per recording; None
    when the band holds no bin.

    Parameters
    ----------
    array : LineArray
        The line array.
    settings : BeamformerSettings
        Its ``window_s`` (the bins) and ``beams``.
    fs_hz : float
        Sample rate (Hz).
    band : Band
        The processing band (:func:`front_end_band`).

    Returns
    -------
    BeamPattern or None
        The tabulated pattern and three-beam ratios.
    """
    return _beam_pattern(array, int(round(settings.window_s * fs_hz)), float(fs_hz), band.as_tuple(),
                         int(settings.beams))


@lru_cache(maxsize=4)
def _beam_pattern(array: LineArray, n_samples: int, fs_hz: float, band: tuple[float, float],
                  beams: int) -> BeamPattern | None:
    _, f = _band_bins(n_samples, fs_hz, band)
    if f.size == 0:
        return None
    grid = np.arange(0.0, 2.0 + PATTERN_STEP_U, PATTERN_STEP_U)
    g = pattern_sum(grid, float(f[0]), fs_hz / n_samples, f.size, array)
    cone = np.linspace(0.0, 180.0, beams)
    step = cone[1] - cone[0]
    nb = np.clip(np.arange(beams)[:, None] + np.array([-1, 0, 1])[None], -1, beams)
    nb = np.where(nb < 0, 1, np.where(nb >= beams, beams - 2, nb))  # mirrored at 0 and 180 deg, as the peak search
    u_src = np.cos(np.deg2rad(cone[:, None] + PATTERN_DELTAS[None] * step))  # (B, D)
    y = np.interp(np.abs(np.cos(np.deg2rad(cone[nb]))[:, None, :] - u_src[..., None]), grid, g)  # (B, D, 3)
    den = 2.0 * y[..., 1] - y[..., 0] - y[..., 2]
    ratio = np.divide(y[..., 2] - y[..., 0], den, out=np.zeros_like(den), where=den > 0)
    monotone = np.all(np.diff(ratio, axis=1) > 0, axis=1) & np.all(den > 0, axis=1)
    half = float(grid[np.argmax(g < 0.5)])
    return BeamPattern(grid, g, cone, ratio, monotone, half)


def _vertices(residual: np.ndarray, angle_deg: np.ndarray, pattern: BeamPattern) -> np.ndarray:
    """Each peak's cone angle (deg) from its own slice of ``residual`` (K, B, J): the largest of the three beams
    around its current angle ``angle_deg`` (K, J), and the offset delta whose tabulated three-beam ratio equals the
    measured one (the parabola's q / 2 where the ratio is not monotone), within half a beam."""
    cone = pattern.cone_deg
    n_w, b, n_p = residual.shape
    step = cone[1] - cone[0]
    kk, jj = np.arange(n_w)[:, None], np.arange(n_p)[None, :]
    k0 = np.rint((angle_deg - cone[0]) / step).astype(np.intp)
    cand = np.minimum(np.maximum(k0[None] + np.array([-1, 0, 1])[:, None, None], 0), b - 1)  # (3, K, J)
    k = np.take_along_axis(cand, np.argmax(residual[kk[None], cand, jj[None]], axis=0)[None], axis=0)[0]
    padded = np.concatenate([residual[:, 1:2], residual, residual[:, -2:-1]], axis=1)  # mirrored at 0 and 180 deg
    y0, y1, y2 = padded[kk, k, jj], padded[kk, k + 1, jj], padded[kk, k + 2, jj]
    den = 2.0 * y1 - y0 - y2
    q = np.divide(y2 - y0, den, out=np.zeros_like(den), where=den > 0)
    # the tabulated ratio rises with delta: linear interpolation between the two entries around q
    table = pattern.ratio[k]  # (K, J, D)
    hi = np.minimum(np.maximum(np.sum(table < q[..., None], axis=-1), 1), table.shape[-1] - 1)
    r0 = np.take_along_axis(table, (hi - 1)[..., None], axis=-1)[..., 0]
    r1 = np.take_along_axis(table, hi[..., None], axis=-1)[..., 0]
    w = np.minimum(np.maximum((q - r0) / np.where(r1 > r0, r1 - r0, 1.0), 0.0), 1.0)
    exact = PATTERN_DELTAS[hi - 1] + w * (PATTERN_DELTAS[hi] - PATTERN_DELTAS[hi - 1])
    delta = np.minimum(np.maximum(np.where(pattern.monotone[k], exact, 0.5 * q), -0.5), 0.5)
    return np.minimum(np.maximum(cone[k] + delta * step, 0.0), 180.0)


def _amplitudes(z: np.ndarray, resp: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Least-squares amplitudes a_j >= 0 (clipped; 0 for padding) of the peaks' patterns ``resp`` (K, B, J) in z
    (K, B) with a constant per window: the normal equations of [1, resp] (a small ridge keeps two peaks on one lobe
    solvable; a padded peak's empty column gets a unit diagonal)."""
    n_w, b, n_p = resp.shape
    design = np.empty((n_w, b, n_p + 1))
    design[..., 0] = 1.0
    design[..., 1:] = resp
    design_t = design.transpose(0, 2, 1)
    gram = design_t @ design
    diag = np.arange(n_p + 1)
    gram[:, diag, diag] = gram[:, diag, diag] * (1.0 + 1e-9) + np.concatenate(
        [np.zeros((n_w, 1)), ~valid], axis=1)
    rhs = (design_t @ z[..., None])[..., 0]
    try:
        coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # two peaks with one pattern: the pseudo-inverse shares their amplitude
        coef = (np.linalg.pinv(gram) @ rhs[..., None])[..., 0]
    return np.where(valid, np.maximum(coef[:, 1:], 0.0), 0.0)


def _padded_angles(angles_deg: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """(angles (K, J) zero-padded, valid (K, J), counts) of one array of peak angles per window."""
    counts = [len(a) for a in angles_deg]
    n_p = max(counts, default=0)
    valid = np.arange(n_p)[None, :] < np.array(counts, dtype=int)[:, None]
    ang = np.zeros((len(counts), n_p))
    for i, a in enumerate(angles_deg):
        ang[i, :len(a)] = a
    return ang, valid, counts


def _fit(z: np.ndarray, ang: np.ndarray, valid: np.ndarray, pattern: BeamPattern) -> tuple[np.ndarray, np.ndarray]:
    """(patterns (K, B, J), amplitudes (K, J)) of the peaks at ``ang`` fitted to z (K, B) (:func:`_amplitudes`)."""
    u = np.cos(np.deg2rad(pattern.cone_deg))
    resp = pattern.response(u[None, :, None] - np.cos(np.deg2rad(ang))[:, None, :]) * valid[:, None, :]
    return resp, _amplitudes(z, resp, valid)


def resolve_peaks_batch(z: np.ndarray, angles_deg: list[np.ndarray], pattern: BeamPattern,
                        iterations: int = PATTERN_ITERATIONS) -> list[np.ndarray]:
    """:func:`resolve_peaks` on K windows at once: z (K, B), one array of peak angles (deg) per window (padded to the
    most peaks inside; a window's result depends on its own row only). Returns one array per window."""
    z = np.atleast_2d(np.asarray(z, dtype=float))
    ang, valid, counts = _padded_angles(angles_deg)
    if ang.shape[1] == 0:
        return [np.asarray(a, dtype=float).copy() for a in angles_deg]
    # a window with one peak has nothing to take out: one pass, whatever its batch holds, so that a window's angles
    # are the same batched or alone (the live chain's windows come one at a time: systems/live/)
    again = valid & (np.array(counts, dtype=int) > 1)[:, None]
    for it in range(iterations if ang.shape[1] > 1 else 1):
        resp, amp = _fit(z, ang, valid, pattern)
        residual = (z - (resp @ amp[..., None])[..., 0])[:, :, None] + resp * amp[:, None, :]
        ang = np.where(valid if it == 0 else again, _vertices(residual, ang, pattern), ang)
    return [ang[i, :c] for i, c in enumerate(counts)]


def add_hidden_peaks(z: np.ndarray, peaks: list[tuple[np.ndarray, np.ndarray]], pattern: BeamPattern,
                     settings: BeamformerSettings) -> list[tuple[np.ndarray, np.ndarray]]:
    """The windows' peaks with the ships hidden on louder ones' lobes added (one CLEAN step: Hogbom, Astron.
    Astrophys. Suppl. 15, 1974; the sources' fitted patterns taken out of the map, the residual searched again).

    A weak ship less than a beamwidth or so from a loud one makes a shoulder on the loud one's lobe, not a maximum
    of z, and has no peak. With the peaks' patterns fitted to z (:func:`resolve_peaks`), the residual
    z - sum_j a_j g(cos theta - u_j) is at most z everywhere (a_j >= 0, g >= 0); its maxima at or above the
    threshold more than the main lobe's half-power half-width (in u) from every peak are new peaks, with the
    residual's height as their amplitude, and each window with new peaks is refined again. At most ``max_peaks``
    per window (the highest), in increasing cone angle.

    Parameters
    ----------
    z : numpy.ndarray
        (K, B) the windows' normalised levels.
    peaks : list of (numpy.ndarray, numpy.ndarray)
        Per window, the refined peak angles (deg) and heights.
    pattern : BeamPattern
        The front end's pattern (:func:`beam_pattern`).
    settings : BeamformerSettings
        Its ``threshold`` and ``max_peaks``.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Per window, the angles (deg) and heights with the hidden peaks.
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    ang, valid, _ = _padded_angles([a for a, _ in peaks])
    resp, amp = _fit(z, ang, valid, pattern)
    residual = z - (resp @ amp[..., None])[..., 0]
    out, grown = list(peaks), []
    for i, (a, h) in enumerate(peaks):
        if not len(a):
            continue
        a2, h2 = pick_beam_peaks(residual[i], pattern.cone_deg, settings)
        du = np.abs(np.cos(np.deg2rad(a2))[:, None] - np.cos(np.deg2rad(a))[None, :])
        new = np.all(du > pattern.half_width_u, axis=1)
        if new.any():
            out[i] = (np.concatenate([a, a2[new]]), np.concatenate([h, h2[new]]))
            grown.append(i)
    if grown:
        refined = resolve_peaks_batch(z[grown], [out[i][0] for i in grown], pattern)
        for i, a in zip(grown, refined, strict=True):
            h = out[i][1]
            keep = np.sort(np.argsort(-h, kind="stable")[: settings.max_peaks])
            order = keep[np.argsort(a[keep], kind="stable")]
            out[i] = (a[order], h[order])
    return out


def resolve_peaks(z: np.ndarray, angle_deg: np.ndarray, pattern: BeamPattern,
                  iterations: int = PATTERN_ITERATIONS) -> np.ndarray:
    """The peaks' cone angles refined jointly with the array's own beam pattern (the RELAX iteration: Li & Stoica,
    IEEE Trans. Signal Process. 44(2), 1996, sec. III).

    The expected beam power of independent sources is a constant plus the sum of their patterns,
    z(theta) = c + sum_j a_j g(cos theta - u_j) (:func:`pattern_sum`; the normaliser is affine in each window). A
    parabola through three beams finds the vertex of the sum, which the slope of the other sources' lobes pulls
    off each source's own: 0.1-0.3 deg on 16-element arrays with a ship 17 deg away, towards endfire where the
    beam is wide, slowly varying and so not averaged out by the TMA. Each pass fits c and the amplitudes a_j >= 0
    by least squares over all beams, then moves each peak to the vertex of z minus the other peaks' patterns,
    found exactly for the pattern: the offset from the largest beam whose three-beam ratio equals the tabulated
    one (:class:`BeamPattern`; a single plane wave's peak then lies on its cone angle to < 0.01 beamwidth). Two
    ships within one beam give one peak and stay one source (their strength-weighted centre).

    Parameters
    ----------
    z : numpy.ndarray
        (B,) the window's normalised level on the pattern's beams.
    angle_deg : numpy.ndarray
        (J,) the peaks' cone angles (deg) as picked (:func:`pick_beam_peaks`).
    pattern : BeamPattern
        The front end's pattern (:func:`beam_pattern`).
    iterations : int
        Passes over all peaks (one when there is a single peak: nothing to take out).

    Returns
    -------
    numpy.ndarray
        (J,) refined cone angles (deg, within 0..180), same order.
    """
    return resolve_peaks_batch(np.asarray(z, dtype=float)[None], [np.asarray(angle_deg, dtype=float)], pattern,
                               iterations)[0]


def _batches(blocks: Iterable[np.ndarray], size: int):
    batch: list[np.ndarray] = []
    for b in blocks:
        batch.append(np.asarray(b, dtype=float))
        if len(batch) == size:
            yield np.stack(batch)
            batch = []
    if batch:
        yield np.stack(batch)


def _check_block(shape: tuple[int, ...], n: int, nw: int) -> None:
    require(tuple(shape) == (n, nw), f"blocks must be (elements, window_s * fs) = ({n}, {nw}), got {tuple(shape)}")


def _spectra_batches(blocks: Iterable[np.ndarray], n: int, nw: int, bins: slice, real_dtype: type, size: int,
                     exact: list[bool] | None = None):
    """Batches (K <= size, N, bins) of the windows' rectangular rfft spectra over ``bins``, each window transformed
    as it arrives (only the band's bins are kept: a batch's samples are never held together). The batch is one
    buffer, reused for the next: its consumer is done with it when it asks for the next. ``exact``: set to
    [False] once a block arrives in another precision than ``real_dtype`` (its spectra are rounded to it)."""
    width = bins.stop - bins.start
    buf, k = np.empty((size, n, width), dtype=np.result_type(real_dtype, np.complex64)), 0
    for block in blocks:
        _check_block(np.shape(block), n, nw)
        if exact is not None and np.asarray(block).dtype != real_dtype:
            exact[0] = False
        buf[k] = _rfft_bins(block, bins, real_dtype)
        k += 1
        if k == size:
            yield buf
            k = 0
    if k:
        yield buf[:k]


class SpectraSink(Protocol):
    """Where the CBF front end hands each batch's rectangular rfft spectra over ``bins`` (:func:`bearing_time_record`).
    ``exact`` is False once a window arrived in another precision than the front end's (its spectra were rounded)."""

    bins: slice

    def write(self, spectra: np.ndarray, exact: bool) -> None:
        """Take K windows' rectangular spectra (K, N, bins of :attr:`bins`), in time order (a view of the front
        end's buffer, reused for the next batch: copy what is kept)."""


def _cbf_batches(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, s: BeamformerSettings, band: Band,
                 octave: Band | None, lofar: LofarAccumulator | None, sink: SpectraSink | None = None):
    """CBF beam powers (K, B) per batch of windows (the band's, or with ``octave`` the combined statistic of the
    band and that octave: :func:`combined_statistic`), each window transformed once; the same spectra feed the
    LOFAR gram (``lofar``), so the narrowband gram costs no pass of its own, and the ``sink`` (its bins added to
    the span transformed)."""
    n, nw = array.elements, int(round(s.window_s * fs_hz))
    steering = [_band_steering(n, nw, fs_hz, array, s, b) for b in [band] + ([octave] if octave else [])]
    spans = [(int(i[0]), int(i[-1]) + 1) if i.size else (0, 0) for i, _ in steering]
    spans += [(lofar.bins.start, lofar.bins.stop)] if lofar is not None else []
    spans += [(sink.bins.start, sink.bins.stop)] if sink is not None else []
    lo, hi = min(a for a, _ in spans), max(b for _, b in spans)
    exact = [True]
    for spectra in _spectra_batches(blocks, n, nw, slice(lo, hi), _dtypes(s)[0], BATCH_WINDOWS, exact):
        if sink is not None:
            sink.write(spectra[:, :, sink.bins.start - lo: sink.bins.stop - lo], exact[0])
        if lofar is not None:
            lofar.add(spectra[:, :, lofar.bins.start - lo: lofar.bins.stop - lo])
        powers = [_cbf_from_spectra(spectra[:, :, a - lo: b - lo], st, s.whiten)  # the LOFAR's span left out
                  for (a, b), (_, st) in zip(spans, steering, strict=False)]
        yield powers[0] if octave is None else combined_statistic(normalise_across_bearing(powers[0], s),
                                                                  normalise_across_bearing(powers[1], s))


def _other_batches(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, s: BeamformerSettings, band: Band,
                   mvdr, lofar: LofarAccumulator | None):
    """Beam powers (K, B) per batch of windows of the ``split-array`` (a batch of one) and ``mvdr`` methods; the
    LOFAR gram (``lofar``) from the same windows' spectra."""
    nw = int(round(s.window_s * fs_hz))
    for batch in _batches(blocks, 1 if s.method == "split-array" else BATCH_WINDOWS):
        _check_block(batch.shape[1:], array.elements, nw)
        if lofar is not None:
            lofar.add(_rfft_bins(batch, lofar.bins, np.float64))
        if s.method == "mvdr":
            from sonartrack.acoustics.mvdr import mvdr_powers

            yield mvdr_powers(batch, fs_hz, array, s, band, mvdr)
        else:
            yield split_array_powers(batch[0], fs_hz, array, s, band)[None]


class FrontEnd:
    """The front end window by window: beam powers, the normaliser and the peaks of each window as it comes, with the
    LOFAR accumulator and the spectra sink fed from the same transforms (:func:`bearing_time_record` runs it over a
    whole recording; the live chain, systems/live/, over the windows of a stream as they complete). A window's row
    and peaks do not depend on the windows batched with it (to rounding: the batched products)."""

    def __init__(self, fs_hz: float, array: LineArray, settings: BeamformerSettings, *, band: Band | None = None,
                 mvdr=None, narrowband: LofarSettings | None = None, spectra_sink: SpectraSink | None = None):
        s = self.settings = settings
        self.fs_hz, self.array, self.mvdr, self.sink = float(fs_hz), array, mvdr, spectra_sink
        self.band = front_end_band(array, s, fs_hz) if band is None else band
        self.n_samples = int(round(s.window_s * fs_hz))
        self.lofar = None if narrowband is None else LofarAccumulator(fs_hz, array, narrowband, self.n_samples)
        self.octave = alias_free_octave(array, s, fs_hz, self.band) if s.method == "cbf" else None
        # the pattern is the CBF's over one band (the octave's sum of two statistics has another shape)
        exact = s.peak_interpolation == "pattern" and s.method == "cbf" and self.octave is None
        self.pattern = beam_pattern(array, s, fs_hz, self.band) if exact else None

    def windows(self, blocks: Iterable[np.ndarray]):
        """(z (B,), peak angles (deg), peak heights) of each window of ``blocks`` (N, window_s fs), in order, read as
        they are asked for (CBF windows batched by ``BATCH_WINDOWS``)."""
        s = self.settings
        if s.method == "cbf":
            batches = _cbf_batches(blocks, self.fs_hz, self.array, s, self.band, self.octave, self.lofar, self.sink)
        else:
            batches = _other_batches(blocks, self.fs_hz, self.array, s, self.band, self.mvdr, self.lofar)
        for power in batches:
            z = normalise_across_bearing(power, s)
            yield from ((row, a, h) for row, (a, h) in zip(z, self._peaks(z), strict=True))

    def _peaks(self, z: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        picked = pick_beam_peaks_rows(z, self.settings.cone_deg, self.settings)
        if self.pattern is not None:  # the batch's windows refined at once (resolve_peaks_batch)
            angles = resolve_peaks_batch(z, [a for a, _ in picked], self.pattern)
            picked = [(a, h) for a, (_, h) in zip(angles, picked, strict=True)]
            if self.settings.hidden_peaks:
                picked = add_hidden_peaks(z, picked, self.pattern, self.settings)
        return picked


class RecordBuilder:
    """The bearing-time record's rows and peaks, window by window (``progress`` called with k after window k)."""

    def __init__(self, s: BeamformerSettings, progress: Callable[[int], None] | None):
        self.s, self.progress, self.k = s, progress, 0
        self.levels, self.ts, self.bs, self.amps = [], [], [], []

    def add(self, row: np.ndarray, angle: np.ndarray, height: np.ndarray) -> None:
        """Append the next window's row z (B,) and its peaks (angles in deg, heights)."""
        self.ts.append(np.full(len(angle), (self.k + 0.5) * self.s.window_s))
        self.bs.append(angle)
        self.amps.append(height)
        self.levels.append(row.astype(np.float32))
        if self.progress is not None:
            self.progress(self.k)
        self.k += 1

    def record(self, lofar: LofarGram | None) -> BearingTimeRecord:
        """The record of the windows added, with ``lofar`` as its gram."""
        s, cone = self.s, self.s.cone_deg
        level = np.stack(self.levels) if self.levels else np.zeros((0, cone.size), dtype=np.float32)
        cat = (lambda parts: np.concatenate(parts)) if self.ts else (lambda parts: np.zeros(0))
        return BearingTimeRecord(np.arange(self.k) * s.window_s + 0.5 * s.window_s, cone, level,
                                 PeakRecord(cat(self.ts), cat(self.bs), cat(self.amps)), lofar)


def bearing_time_record(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, settings: BeamformerSettings,
                        *, band: Band | None = None, progress: Callable[[int], None] | None = None,
                        mvdr=None, narrowband: LofarSettings | None = None,
                        spectra_sink: SpectraSink | None = None) -> BearingTimeRecord:
    """Beamform, normalise and pick peaks in every window of ``blocks``; CBF windows in batches of
    ``BATCH_WINDOWS`` (one matrix product each); with ``narrowband``, the LOFAR gram per beam from the same
    windows' spectra (acoustics/lofar.py :class:`~sonartrack.acoustics.lofar.LofarAccumulator`: no pass of its own).

    Parameters
    ----------
    blocks : iterable of ndarray (N, window_s fs)
        The recording's windows in order (e.g. io/wav_blocks.py ``iter_wav_blocks``), N = ``array.elements``.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The line array.
    settings : BeamformerSettings
        The front end's settings.
    band : Band, optional
        The processing band, resolved and checked once by the caller (:func:`front_end_band`); None resolves
        and checks it here.
    progress : callable, optional
        Called with k after window k.
    mvdr : MvdrSettings, optional
        Segment and loading of the ``mvdr`` method (acoustics/mvdr.py; its defaults when None).
    narrowband : LofarSettings, optional
        The narrowband settings (band, beams, integration, normaliser; any subclass, such as the passive chain's):
        when given, the record's ``lofar`` is the gram :func:`~sonartrack.acoustics.lofar.lofar_gram` makes of
        the same windows (None when they hold no whole integration period).
    spectra_sink : SpectraSink, optional
        Given each batch's rectangular spectra over its ``bins`` (the CBF method only), for a later pass that needs
        them (systems/passive/tonal_pass.py ``SpectraSpill``): they cost no transform of their own.

    Returns
    -------
    BearingTimeRecord
        Window centres time_s = (k + 0.5) window_s (s), the beams' cone angles (deg), the normalised level z per
        window and beam, the peaks, and the LOFAR gram (or None).
    """
    fe = FrontEnd(fs_hz, array, settings, band=band, mvdr=mvdr, narrowband=narrowband, spectra_sink=spectra_sink)
    rows = RecordBuilder(settings, progress)
    for row in fe.windows(blocks):
        rows.add(*row)
    return rows.record(None if fe.lofar is None else fe.lofar.gram(settings.window_s))
