"""A tracked target's tonal line, measured on its beam window by window (the frequency input of paper P2).

Per window (``window_s``) of an N-element uniform line array (element 0 = front, element n sits
s_n = ((N - 1)/2 - n) d ahead of the centre, as sim/array_signals.py), a plane wave from cone angle theta
reaches element n at tau_n = -s_n cos(theta) / c. The conventional beam steered at theta is

    B(f) = (1/N) sum_n exp(+2 pi i f tau_n(theta)) X_n(f),      X_n = rfft(hann * x_n)

and its power is scaled to a one-sided spectral density, P(f) = 2 |B(f)|^2 / (fs sum w^2) (input units^2/Hz):
a single element (N = 1) gives its own periodogram, and a beam on the source keeps the tonal's power while
the element-independent noise drops by N (array gain 10 log10 N, 12.0 dB for 16 elements).

Peaks (:func:`spectral_peaks`) are local maxima of P over a running median background of
``background_hz`` (the median ignores a narrow line, so the background is the broadband level); their SNR
is 10 log10(P / median). The frequency is refined by a parabola through the log powers of the peak bin
and its neighbours, delta = (a - c) / (2 (a - 2b + c)) bins. On a Hann window that parabola is biased
away from the bin centre: up to 0.016 bins at delta ~ 0.29 (0.016 Hz for 1 s windows), which matters at the
0.01 Hz level, so it is removed exactly by inverting the noise-free curve delta_hat(delta) of the
Hann main lobe (:func:`_hann_bias_table`; residual < 1e-4 bins).

:class:`TonalAccumulator` keeps the running mean spectrum (F floats, fixed) and, per window, the time and
at most ``max_candidates`` candidate frequencies: the strongest peaks of the window above
``min_window_snr_db``, with a slot kept for the strongest peak near each of the ``provisional_lines``
strongest lines of the mean spectrum so far (so a weak line is not crowded out by stronger noise peaks
elsewhere in the band, nor by a loud line leaked from another beam). Memory: (1 + max_candidates) floats
per window. :meth:`TonalAccumulator.result` picks the line (:func:`pick_line`: the strongest mean-spectrum
peak above :func:`line_threshold_db`, and, given the other tracks' accumulators, not standing higher above
the background on another track's beam), then walks the windows forward and backward in time
(:func:`follow_line`), assigning to each the candidate nearest the reference within ``tolerance_hz``, where
the reference is the line or, once the line has been seen, the median of the last few estimates (it
follows a slow Doppler drift, paper P2 eq. 3). The measurement noise sigma_hz is estimated from the data
(:func:`frequency_sigma_hz`): residuals from a running median of the estimates, outliers beyond
``outlier_sigmas`` robust (MAD) sigmas set to NaN, RMS of the rest, floored at ``sigma_floor_hz``.

Accuracy: per window, the Hann-window parabola has a standard deviation about 2.8 times the Cramer-Rao
bound of a rectangular window (measured: 0.077 Hz at 20 dB tonal SNR in 1 Hz, 1 s windows; zero padding
gains < 15 %), so sigma_hz is measured, not assumed.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np
from pydantic import model_validator

from sonartrack.acoustics.line_array import LineArray
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting

#: windows between renewals of the accumulator's provisional lines (the mean spectrum changes slowly)
PROVISIONAL_EVERY = 8

#: 1 / Phi^-1(3/4): the standard deviation of a normal from its median absolute deviation
MAD_TO_SIGMA = 1.4826


class TonalSettings(Settings):
    """Tonal-line measurement on a tracked target's beam (acoustics/tonal.py)."""

    band_hz: list[float] = setting(default_factory=lambda: [50.0, 1000.0], doc="band where lines are searched",
                                   unit="Hz", min_length=2, max_length=2)
    window_s: float = setting(1.0, "analysis window (one spectrum per window)", unit="s", gt=0)
    min_line_snr_db: float = setting(2.0, "a line is accepted when its mean-spectrum peak stands this far above "
                                          "the local median background", unit="dB", ge=0)
    line_false_alarm_sigmas: float = setting(6.0, "and also z = this many standard deviations of a T-window mean "
                                                  "of noise above it: 10 log10(1 + z / sqrt(T))", unit="1", ge=0)
    min_window_snr_db: float = setting(3.0, "a window's peak is a candidate when it stands this far above the "
                                            "local median background", unit="dB", ge=0)
    max_candidates: int = setting(8, "candidate peaks kept per window", unit="1", ge=1, le=64)
    provisional_lines: int = setting(3, "per window, a candidate slot is kept for the strongest peak near each "
                                        "of this many strongest lines of the mean spectrum so far", unit="1", ge=0)
    tolerance_hz: float = setting(1.5, "a window's candidate is on the line when within this of the line or of "
                                       "the recent estimates (Doppler drift)", unit="Hz", gt=0)
    background_hz: float = setting(20.0, "width of the running median background", unit="Hz", gt=0)
    follow_windows: int = setting(5, "the reference of the drift follower is the median of this many last "
                                     "estimates", unit="1", ge=1)
    smooth_windows: int = setting(31, "running median of the estimates (sigma_hz and outliers)", unit="1", ge=3)
    outlier_sigmas: float = setting(4.0, "an estimate this many sigma_hz from the running median is a noise "
                                         "peak (set to NaN)", unit="1", gt=0)
    sigma_floor_hz: float = setting(0.005, "floor of the measured frequency noise sigma_hz", unit="Hz", gt=0)

    @model_validator(mode="after")
    def _band(self):
        lo, hi = self.band_hz
        if not 0 <= lo < hi:
            raise ValueError(f"tonal band_hz {self.band_hz} must satisfy 0 <= low < high")
        return self


@dataclass(frozen=True)
class TonalTrack:
    """A target's tonal line: the line of the mean spectrum and its frequency per window (NaN: not seen)."""

    line_hz: float
    line_snr_db: float
    time_s: np.ndarray
    frequency_hz: np.ndarray
    sigma_hz: float


def beam_spectra(block: np.ndarray, fs_hz: float, array: LineArray, cone_deg, settings: TonalSettings
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Conventional beams' power spectral densities of one window (module doc).

    The window is applied in frequency (:func:`_hann_spectra`) and the k beams are summed along the elements by
    Horner's rule (:func:`_beams`). A float32 block (a float32, 16- or 24-bit file's samples, exact in float32) is
    transformed and steered in single precision, two to three times faster than in double (pocketfft's
    single-precision kernels, half the memory traffic): the beams carry a rounding of ~1e-6 of their magnitude
    (1e-5 dB on a power), far below the noise of one window's periodogram (5.6 dB standard deviation), and their
    powers are returned in double. Any other block is transformed in double.

    Parameters
    ----------
    block : ndarray (N, n)
        One window of n samples of the N elements (element 0 = front); float32 or float64.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array: spacing and sound speed of the steering delays (N is the block's rows: the whole array, or
        its first N elements).
    cone_deg : array_like (k,)
        Cone angles of the beams (deg).
    settings : TonalSettings
        ``band_hz``: the frequencies kept.

    Returns
    -------
    freqs_hz : ndarray (F,)
        The band's rfft frequencies (Hz).
    power : ndarray (k, F)
        One-sided power spectral density of each beam (input units^2 / Hz).
    """
    x = np.atleast_2d(np.asarray(block))
    if x.dtype != np.float32:
        x = x.astype(float, copy=False)
    idx, f, scale = _band_of_window(x.shape[1], float(fs_hz), *map(float, settings.band_hz))
    return f, _beam_psd(_hann_spectra(x, idx), f, scale, array, cone_deg)


def beam_spectra_of_rect(rect: np.ndarray, n_samples: int, fs_hz: float, array: LineArray, cone_deg,
                         settings: TonalSettings) -> tuple[np.ndarray, np.ndarray]:
    """:func:`beam_spectra` of a window given by its rectangular rfft spectra instead of its samples: the same
    numbers when they are the rfft of the same samples in the same precision (complex64 for a float32 block).

    Parameters
    ----------
    rect : ndarray (N, F + 2)
        rfft (no window function) of the N elements over :func:`tonal_rect_bins`: the band's F bins and one beyond
        each edge.
    n_samples : int
        The window's length (samples).
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The array (steering delays).
    cone_deg : array_like (k,)
        Cone angles of the beams (deg).
    settings : TonalSettings
        ``band_hz``.

    Returns
    -------
    freqs_hz : ndarray (F,)
        The band's rfft frequencies (Hz).
    power : ndarray (k, F)
        One-sided power spectral density of each beam (input units^2 / Hz).
    """
    _, f, scale = _band_of_window(int(n_samples), float(fs_hz), *map(float, settings.band_hz))
    require(rect.shape[1] == f.size + 2, f"tonal: {rect.shape[1]} rectangular bins, expected {f.size + 2}")
    return f, _beam_psd(_hann_from_rect(rect), f, scale, array, cone_deg)


def tonal_rect_bins(n_samples: int, fs_hz: float, settings: TonalSettings) -> slice | None:
    """The rectangular rfft bins of an n-sample window :func:`beam_spectra_of_rect` takes (the band's and one beyond
    each edge), or None where the band has no bin or reaches bin 0 or the last rfft bin (no bin beyond it).

    Parameters
    ----------
    n_samples : int
        The window's length (samples).
    fs_hz : float
        Sample rate (Hz).
    settings : TonalSettings
        ``band_hz``.

    Returns
    -------
    slice or None
        The bins.
    """
    idx = _band_of_window(int(n_samples), float(fs_hz), *map(float, settings.band_hz))[0]
    if idx.size == 0 or idx[0] < 1 or idx[-1] + 1 >= int(n_samples) // 2 + 1:
        return None
    return slice(int(idx[0]) - 1, int(idx[-1]) + 2)


def _beam_psd(spec: np.ndarray, f_hz: np.ndarray, scale: float, array: LineArray, cone_deg) -> np.ndarray:
    """scale |beam|^2 (k, F) in double of Hann spectra (N, F) steered to the cone angles (:func:`beam_spectra`)."""
    n_el = spec.shape[0]
    offsets = ((n_el - 1) / 2.0 - np.arange(n_el)) * array.spacing_m
    tau = -np.cos(np.deg2rad(np.atleast_1d(np.asarray(cone_deg, dtype=float))))[:, None] * offsets / \
        array.sound_speed_mps  # (k, N)
    beams = _beams(spec, f_hz, tau).astype(complex) / n_el  # (k, F)
    return scale * (beams.real**2 + beams.imag**2)


@cache
def _band_of_window(n: int, fs_hz: float, low_hz: float, high_hz: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(rfft bins of an n-sample window in [low, high] Hz, their frequencies, the one-sided PSD scale
    2 / (fs sum w^2) of the periodic Hann window w), the same for every window of a recording (made once)."""
    f_all = np.fft.rfftfreq(n, 1.0 / fs_hz)
    idx = np.flatnonzero((f_all >= low_hz) & (f_all <= high_hz))
    f = f_all[idx]
    for a in (idx, f):  # shared by every call: read-only
        a.flags.writeable = False
    return idx, f, 2.0 / (fs_hz * np.sum(_hann(n) ** 2))


def _hann_spectra(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """rfft(hann * x_n) at the bins ``idx`` (N, F) (contiguous), the window applied in frequency where the band
    leaves a bin on each side: the periodic Hann is three complex exponentials, so X_w(k) = X(k) / 2 - (X(k - 1) +
    X(k + 1)) / 4 (the DFT's shift theorem; Harris 1978, Proc. IEEE 66(1), sec. IV), which spares the product with
    the window (equal to rounding). In x's precision: complex64 for float32, complex128 otherwise."""
    import scipy.fft

    if idx.size == 0:
        return np.zeros((x.shape[0], 0), dtype=complex)
    if idx[0] >= 1 and idx[-1] + 1 < x.shape[1] // 2 + 1:
        return _hann_from_rect(scipy.fft.rfft(x, axis=1, workers=1)[:, idx[0] - 1: idx[-1] + 2])
    return scipy.fft.rfft(x * _hann(x.shape[1]).astype(x.dtype), axis=1, workers=1)[:, idx[0]: idx[-1] + 1]


def _hann_from_rect(spec: np.ndarray) -> np.ndarray:
    """X(k) / 2 - (X(k - 1) + X(k + 1)) / 4 (N, F) of rectangular spectra (N, F + 2) (:func:`_hann_spectra`), in one
    new array: -(X(k - 1) + X(k + 1)) / 4 + X(k) / 2, the scalings by powers of two exact and adding the negation
    subtracting, so the same bits as the formula written out."""
    out = np.add(spec[:, :-2], spec[:, 2:])
    out *= -0.25
    out += 0.5 * spec[:, 1:-1]
    return out


def _beams(spec: np.ndarray, f_hz: np.ndarray, tau_s: np.ndarray) -> np.ndarray:
    """sum_n exp(+2 pi i f tau_n) X_n(f) (k, F) of spectra (N, F) for delays (k, N) that step uniformly along the
    array, by Horner's rule along the elements, in the spectra's precision (the phases are computed in double).

    tau_n = tau_0 + n (tau_1 - tau_0), so with a = exp(2 pi i f tau_0) and q = exp(2 pi i f (tau_1 - tau_0)) the
    sum is a (X_0 + q (X_1 + q (X_2 + ...))): two complex exponentials per (bin, beam) and N - 1 complex
    multiply-adds, with no (F, k, N) steering array (rounding grows by one unit of the precision per element:
    ~1e-16 in double, ~6e-8 in single, 2e-6 of the beam's magnitude for 32 elements)."""
    a = np.exp(2j * np.pi * f_hz[None, :] * tau_s[:, :1]).astype(spec.dtype)
    if tau_s.shape[1] == 1:
        return a * spec[0]
    q = np.exp(2j * np.pi * f_hz[None, :] * (tau_s[:, 1:2] - tau_s[:, :1])).astype(spec.dtype)
    acc = np.broadcast_to(spec[-1], q.shape).copy()
    for row in spec[-2::-1]:
        acc *= q
        acc += row
    return a * acc


def _median_filter(x: np.ndarray, size: int, mode: str) -> np.ndarray:
    """scipy.ndimage's running median, imported on first use (scipy.ndimage takes ~0.3 s to import, and the
    command line imports this module's settings at start)."""
    from scipy.ndimage import median_filter

    return median_filter(x, size=size, mode=mode)


@cache
def _hann(n: int) -> np.ndarray:
    """The periodic Hann window of n samples, w_m = 1/2 - (1/2) cos(2 pi m / n) (the DFT-even one: its spectrum
    is the three-term main lobe)."""
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)
    w.flags.writeable = False
    return w


@cache
def _hann_bias_table(n_points: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """(parabola offsets delta_hat, true offsets delta) in bins, for a noise-free tone on a Hann window.

    Hann main lobe |W(x)| proportional to |sinc(x) / (1 - x^2)| (x in bins, long windows); the log-power
    parabola through x = delta - 1, delta, delta + 1 gives delta_hat(delta), monotone on [-0.5, 0.5]."""
    delta = np.linspace(-0.5, 0.5, n_points)

    def log_power(x):
        x = np.asarray(x, dtype=float)
        near = np.abs(np.abs(x) - 1.0) < 1e-9
        amp = np.where(near, 0.5, np.sinc(x) / np.where(near, 1.0, 1.0 - x**2))
        return np.log(amp**2)

    a, b, c = log_power(delta + 1.0), log_power(delta), log_power(delta - 1.0)  # bins k-1, k, k+1 of a tone at k+delta
    return 0.5 * (a - c) / (a - 2.0 * b + c), delta


def spectral_peaks(power: np.ndarray, freqs_hz: np.ndarray, settings: TonalSettings, *,
                   min_snr_db: float | None = None, max_peaks: int | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (m,), SNRs (m,)) of the strongest narrowband peaks of ``power`` (module doc), strongest first.

    A peak is a local maximum standing ``min_snr_db`` (default ``settings.min_line_snr_db``) above the
    running median of ``background_hz``; at most ``max_peaks`` (default ``settings.max_candidates``).

    Parameters
    ----------
    power : numpy.ndarray
        (F,) power spectrum (any linear unit).
    freqs_hz : numpy.ndarray
        (F,) bin frequencies (Hz), uniformly spaced.
    settings : TonalSettings
        Background width and defaults.
    min_snr_db : float, optional
        Height above the running median a peak needs (dB).
    max_peaks : int, optional
        Most peaks returned.

    Returns
    -------
    frequencies_hz : numpy.ndarray
        (m,) sub-bin peak frequencies (Hz); empty for fewer than three bins.
    snr_db : numpy.ndarray
        (m,) each peak bin's height above the running median (dB).
    """
    p = np.maximum(np.asarray(power, dtype=float), np.finfo(float).tiny)
    f = np.asarray(freqs_hz, dtype=float)
    if p.size < 3:
        return np.empty(0), np.empty(0)
    k, snr_db = _peak_bins(p, f[1] - f[0], settings, settings.min_line_snr_db if min_snr_db is None else min_snr_db)
    k = k[: settings.max_candidates if max_peaks is None else max_peaks]
    return _refined_hz(p, f, k), snr_db[: k.size]


def _peak_bins(p: np.ndarray, df_hz: float, settings: TonalSettings, min_snr_db: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(bins of the local maxima of p (> 0) standing min_snr_db above the running median, strongest first;
    their SNRs in dB)."""
    snr_db = window_snr_db(p, df_hz, settings)[0]
    inner = np.arange(1, p.size - 1)
    is_peak = (p[inner] > p[inner - 1]) & (p[inner] >= p[inner + 1]) & (snr_db[inner] >= min_snr_db)
    k = inner[is_peak]
    k = k[np.argsort(-snr_db[k], kind="stable")]
    return k, snr_db[k]


def _background_bins(settings: TonalSettings, df_hz: float) -> int:
    """Width of the running median background in bins: ``background_hz`` rounded to an odd count, at least 3."""
    return max(3, int(round(settings.background_hz / df_hz)) | 1)


def window_snr_db(power: np.ndarray, df_hz: float, settings: TonalSettings) -> np.ndarray:
    """Each bin's height above the running median of ``background_hz`` (dB), 10 log10(p / median(p)), for one
    spectrum (F,) or several (k, F) at once (module doc; powers floored at the smallest positive float).

    The rows are filtered in one call: each is padded by its own mirror image (numpy's "symmetric", scipy's
    "reflect") over half the width, and the rows laid end to end, so that every window of the running median
    stays inside its own row; the medians are those of one filter per row (a median selects, it does no
    arithmetic).

    Parameters
    ----------
    power : numpy.ndarray
        (F,) or (k, F) power spectra (any linear unit), F >= 1.
    df_hz : float
        Bin spacing (Hz).
    settings : TonalSettings
        ``background_hz``.

    Returns
    -------
    numpy.ndarray
        (k, F) SNRs (dB); k = 1 for a single spectrum.
    """
    tiny = np.finfo(float).tiny
    p = np.maximum(np.atleast_2d(np.asarray(power, dtype=float)), tiny)
    return 10.0 * np.log10(p / np.maximum(_row_medians(p, _background_bins(settings, df_hz)), tiny))


def _row_medians(p: np.ndarray, width: int) -> np.ndarray:
    """The running median of ``width`` bins (odd) along each row of p (k, F), each row mirrored at its ends
    (:func:`window_snr_db`)."""
    half = width // 2
    n_rows, n = p.shape
    if half > n:  # a mirror longer than the row: scipy repeats the reflection, one row at a time does the same
        return np.array([_median_filter(row, size=width, mode="reflect") for row in p]).reshape(p.shape)
    padded = np.concatenate((p[:, :half][:, ::-1], p, p[:, ::-1][:, :half]), axis=1)
    return _median_filter(padded.ravel(), size=width, mode="reflect").reshape(n_rows, -1)[:, half: half + n]


def window_peak_bins(power: np.ndarray, df_hz: float, settings: TonalSettings,
                     min_snr_db: float | None = None) -> list[np.ndarray]:
    """Per spectrum of (k, F), the bins of its local maxima standing ``min_snr_db`` (default
    ``settings.min_window_snr_db``) above the running median (:func:`window_snr_db`), strongest first (ties in
    bin order): what one spectrum at a time gives, for several beams of a window in a few array operations.

    Parameters
    ----------
    power : numpy.ndarray
        (k, F) power spectra (any linear unit).
    df_hz : float
        Bin spacing (Hz).
    settings : TonalSettings
        ``background_hz`` and ``min_window_snr_db``.
    min_snr_db : float, optional
        Height above the running median a peak needs (dB).

    Returns
    -------
    list of numpy.ndarray
        k arrays of bin indices (int64).
    """
    p = np.maximum(np.atleast_2d(np.asarray(power, dtype=float)), np.finfo(float).tiny)
    n_rows, n = p.shape
    if n < 3:
        return [np.empty(0, np.int64) for _ in range(n_rows)]
    threshold = settings.min_window_snr_db if min_snr_db is None else min_snr_db
    mid = p[:, 1:-1]
    rows, cols = np.nonzero((mid > p[:, :-2]) & (mid >= p[:, 2:]))  # the local maxima: the only bins tested
    cols = cols + 1
    # window_snr_db's formula at those bins only (the same numbers; a log per local maximum, not per bin)
    tiny = np.finfo(float).tiny
    med = _row_medians(p, _background_bins(settings, df_hz))[rows, cols]
    snr = 10.0 * np.log10(p[rows, cols] / np.maximum(med, tiny))
    loud = snr >= threshold
    rows, cols, snr = rows[loud], cols[loud], snr[loud]
    # by row, then strongest first; lexsort is stable, so equal SNRs keep their bin order (argsort "stable" per row)
    order = np.lexsort((-snr, rows))
    rows, cols = rows[order], cols[order]
    bounds = np.searchsorted(rows, np.arange(n_rows + 1))
    return [cols[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _refined_hz(p: np.ndarray, f: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Sub-bin frequencies of peaks at bins k: log-power parabola, Hann bias removed (module doc)."""
    a, b, c = np.log(p[k - 1]), np.log(p[k]), np.log(p[k + 1])
    den = a - 2.0 * b + c
    delta_hat = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, -1.0), 0.0)
    table_hat, table_true = _hann_bias_table()
    delta = np.interp(np.clip(delta_hat, table_hat[0], table_hat[-1]), table_hat, table_true)
    return f[k] + delta * (f[1] - f[0])


def line_threshold_db(settings: TonalSettings, n_windows: int | None) -> float:
    """SNR a mean-spectrum line needs: min_line_snr_db, and above the noise of a mean of T = ``n_windows``
    periodograms (relative standard deviation 1 / sqrt(T) per bin): 10 log10(1 + z / sqrt(T)).

    Parameters
    ----------
    settings : TonalSettings
        ``min_line_snr_db`` (dB) and z = ``line_false_alarm_sigmas``.
    n_windows : int or None
        T, the windows in the mean; None or 0 gives ``min_line_snr_db`` alone.

    Returns
    -------
    float
        The threshold (dB).
    """
    if not n_windows:
        return settings.min_line_snr_db
    noise_db = 10.0 * np.log10(1.0 + settings.line_false_alarm_sigmas / np.sqrt(n_windows))
    return max(settings.min_line_snr_db, float(noise_db))


def pick_line(mean_power: np.ndarray, freqs_hz: np.ndarray, settings: TonalSettings,
              other_powers: np.ndarray | None = None, n_windows: int | None = None) -> tuple[float, float] | None:
    """(frequency, SNR in dB) of the strongest peak of the mean spectrum above :func:`line_threshold_db`, or None.

    ``other_powers`` (j, F): mean spectra of the other tracks' beams. A line is this beam's only when no
    other beam holds more power at its bin (+-1 bin): a loud tonal leaks into every beam through the
    sidelobes, but it stands highest above the background (:func:`_line_excess`) on the beam that points at
    its source.

    Parameters
    ----------
    mean_power : numpy.ndarray
        (F,) mean spectrum of this track's beam.
    freqs_hz : numpy.ndarray
        (F,) bin frequencies (Hz), uniformly spaced.
    settings : TonalSettings
        The tonal settings.
    other_powers : numpy.ndarray, optional
        (j, F) mean spectra of the other tracks' beams.
    n_windows : int, optional
        Windows in the mean (for :func:`line_threshold_db`).

    Returns
    -------
    tuple of (float, float) or None
        Line frequency (Hz) and its SNR above the running median (dB), or None when no peak qualifies.
    """
    f, snr = spectral_peaks(mean_power, freqs_hz, settings, max_peaks=mean_power.size,
                            min_snr_db=line_threshold_db(settings, n_windows))
    if other_powers is None or len(other_powers) == 0 or f.size == 0:
        return (float(f[0]), float(snr[0])) if f.size else None
    df = freqs_hz[1] - freqs_hz[0]
    excess = _line_excess(mean_power, settings, df)
    other_excess = np.array([_line_excess(o, settings, df) for o in np.reshape(other_powers, (-1, mean_power.size))])
    for fk, sk in zip(f, snr, strict=True):
        k = int(np.clip(np.round((fk - freqs_hz[0]) / df), 1, mean_power.size - 2))
        if np.max(excess[k - 1:k + 2]) >= np.max(other_excess[:, k - 1:k + 2]):
            return float(fk), float(sk)
    return None


def _line_excess(power: np.ndarray, settings: TonalSettings, df_hz: float) -> np.ndarray:
    """Power above the running median background (F,): a line's power on this beam, whatever its background."""
    return power - _median_filter(power, size=_background_bins(settings, df_hz), mode="reflect")


def follow_line(candidates_hz: np.ndarray, line_hz: float, settings: TonalSettings) -> np.ndarray:
    """Frequency per window (T,) from candidates (T, M) (NaN padded): NaN where none is on the line (module doc).

    Followed forward in time, then backward to fill the windows the forward pass missed (the start of a
    drifting line lies away from the mean spectrum's line, which sits at its middle).

    Parameters
    ----------
    candidates_hz : numpy.ndarray
        (T, M) candidate peak frequencies of each window (Hz), NaN padded.
    line_hz : float
        The mean spectrum's line (Hz).
    settings : TonalSettings
        ``tolerance_hz`` and ``follow_windows``.

    Returns
    -------
    numpy.ndarray
        (T,) frequency on the line per window (Hz), NaN where none.
    """
    forward = _follow_forward(candidates_hz, line_hz, settings)
    backward = _follow_forward(candidates_hz[::-1], line_hz, settings)[::-1]
    return np.where(np.isfinite(forward), forward, backward)


def _follow_forward(candidates_hz: np.ndarray, line_hz: float, settings: TonalSettings) -> np.ndarray:
    """One pass in window order. The reference is the line until it is first seen, then the median of the
    last ``follow_windows`` estimates; a candidate within ``tolerance_hz`` of the reference is taken (the
    nearest), else one within ``tolerance_hz`` of the line (the nearest to it), else none."""
    tol = settings.tolerance_hz
    out = np.full(candidates_hz.shape[0], np.nan)
    recent: list[float] = []
    # plain floats: a window holds at most max_candidates of them, where numpy's per-call cost would dominate
    # (_median and min give np.median's and np.argmin's values)
    for t, row in enumerate(candidates_hz.tolist()):
        c = [v for v in row if math.isfinite(v)]
        if not c:
            continue
        ref = _median(recent) if recent else line_hz
        for centre in (ref, line_hz):
            best = min(c, key=lambda v, centre=centre: abs(v - centre))
            if abs(best - centre) <= tol:
                out[t] = best
                recent = (recent + [best])[-settings.follow_windows:]
                break
    return out


def _median(values: list[float]) -> float:
    """The median of a short list of floats as np.median gives it: the middle one, or the middle pair's
    (a + b) / 2."""
    v = sorted(values)
    mid = len(v) // 2
    return v[mid] if len(v) % 2 else (v[mid - 1] + v[mid]) / 2.0


def frequency_sigma_hz(frequency_hz: np.ndarray, settings: TonalSettings) -> tuple[float, np.ndarray]:
    """(sigma_hz, estimates with outliers set to NaN) from the estimates themselves (module doc).

    Residuals r from a running median of w = ``smooth_windows`` valid estimates (it follows a linear drift
    exactly). First a robust scale, s0 = 1.4826 MAD(r); estimates with |r| > outlier_sigmas s0 are noise
    peaks and become NaN; then sigma = RMS of the kept r (the tails of the estimator are heavier than a
    normal's, which the MAD would miss), divided by sqrt(1 + (pi/2 - 2) / w) because the running median shares
    the sample, floored at ``sigma_floor_hz``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray
        (T,) frequency per window (Hz), NaN where none.
    settings : TonalSettings
        ``smooth_windows``, ``outlier_sigmas`` and ``sigma_floor_hz``.

    Returns
    -------
    sigma_hz : float
        Standard deviation of one estimate (Hz); the floor when fewer than three are valid.
    frequency_hz : numpy.ndarray
        (T,) a copy of the estimates with the outliers set to NaN (Hz).
    """
    f = np.array(frequency_hz, dtype=float)
    valid = np.flatnonzero(np.isfinite(f))
    if valid.size < 3:
        return settings.sigma_floor_hz, f
    w = settings.smooth_windows
    resid = f[valid] - _median_filter(f[valid], size=min(w, valid.size | 1), mode="nearest")
    scale = max(settings.sigma_floor_hz, MAD_TO_SIGMA * float(np.median(np.abs(resid))))
    outlier = np.abs(resid) > settings.outlier_sigmas * scale
    f[valid[outlier]] = np.nan
    rms = float(np.sqrt(np.mean(resid[~outlier] ** 2)))
    return max(settings.sigma_floor_hz, rms / np.sqrt(1.0 + (np.pi / 2.0 - 2.0) / w)), f


class TonalAccumulator:
    """One track's tonal measurement over a recording, window by window, in memory flat per window (module doc)."""

    def __init__(self, settings: TonalSettings, n_bins: int):
        require(n_bins >= 3, f"tonal: {n_bins} frequency bins in the band; widen tonal band_hz or window_s")
        self.settings = settings
        self.n_bins = int(n_bins)
        self._power_sum = np.zeros(self.n_bins)
        self._freqs_hz: np.ndarray | None = None
        self._times = array("d")
        self._candidates = array("d")  # per window: max_candidates frequencies (NaN padded)
        self._provisional_hz = np.empty(0)

    @property
    def n_windows(self) -> int:
        """Number of windows added so far."""
        return len(self._times)

    def state_nbytes(self) -> int:
        """Bytes held: the mean spectrum and its frequencies (fixed) plus (1 + max_candidates) floats per window.

        Returns
        -------
        int
            Bytes of the accumulated state.
        """
        fixed = self._power_sum.nbytes + (0 if self._freqs_hz is None else self._freqs_hz.nbytes)
        return fixed + self._times.itemsize * (len(self._times) + len(self._candidates))

    def add(self, time_s: float, power: np.ndarray, freqs_hz: np.ndarray, peak_bins: np.ndarray | None = None
            ) -> None:
        """Add one window's beam spectrum (F,) at time ``time_s`` (the window's centre, say).

        Parameters
        ----------
        time_s : float
            Time of the window (s).
        power : numpy.ndarray
            (F,) the beam's power spectrum, F = ``n_bins``.
        freqs_hz : numpy.ndarray
            (F,) bin frequencies (Hz); those of the first window are kept.
        peak_bins : numpy.ndarray, optional
            The spectrum's peaks above ``min_window_snr_db``, strongest first, when found already with other
            beams' (:func:`window_peak_bins`).
        """
        power = np.asarray(power, dtype=float)
        require(power.shape == (self.n_bins,), f"tonal: a spectrum of {power.shape} bins, expected ({self.n_bins},)")
        if self._freqs_hz is None:
            self._freqs_hz = np.asarray(freqs_hz, dtype=float).copy()
        self._power_sum += power
        self._times.append(float(time_s))
        self._candidates.extend(self._window_candidates(power, peak_bins))

    def _window_candidates(self, power: np.ndarray, peak_bins: np.ndarray | None) -> np.ndarray:
        """The window's strongest peaks, with a slot kept for the strongest near each of the provisional lines
        (the ``provisional_lines`` strongest peaks of the mean spectrum so far, renewed every
        ``PROVISIONAL_EVERY`` windows; module doc). Only the kept peaks are refined to sub-bin frequency."""
        s = self.settings
        m = s.max_candidates
        if self.n_windows % PROVISIONAL_EVERY == 1 or PROVISIONAL_EVERY == 1:
            self._provisional_hz = spectral_peaks(self._power_sum, self._freqs_hz, s, min_snr_db=0.0,
                                                  max_peaks=min(s.provisional_lines, m))[0]
        p = np.maximum(power, np.finfo(float).tiny)
        k = _peak_bins(p, self._freqs_hz[1] - self._freqs_hz[0], s, s.min_window_snr_db)[0] if peak_bins is None \
            else np.asarray(peak_bins, dtype=np.int64)
        # per provisional line, the first (strongest) peak within the tolerance: one comparison table for all lines
        close = np.abs(self._freqs_hz[k][None, :] - self._provisional_hz[:, None]) <= s.tolerance_hz
        reserved = list(dict.fromkeys(int(i) for i in np.argmax(close, axis=1)[np.any(close, axis=1)]))
        keep = reserved + [i for i in range(min(k.size, m + len(reserved))) if i not in reserved][: m - len(reserved)]
        out = np.full(m, np.nan)
        out[: len(keep)] = _refined_hz(p, self._freqs_hz, k[keep])
        return out

    def mean_spectrum(self) -> np.ndarray:
        """The running mean of the windows' beam spectra (F,).

        Returns
        -------
        numpy.ndarray
            (F,) mean power spectrum (zeros before the first window).
        """
        return self._power_sum / max(1, self.n_windows)

    def result(self, others: Sequence[TonalAccumulator] = ()) -> TonalTrack | None:
        """The tonal track, or None (no window, or no mean-spectrum line above ``min_line_snr_db``).

        ``others``: the accumulators of the other tracks on the same recording (same band and window); a line
        louder on another track's beam is that track's, leaked through the sidelobes (:func:`pick_line`).

        Parameters
        ----------
        others : sequence of TonalAccumulator
            The other tracks' accumulators (this one and those with other bins or no window are ignored).

        Returns
        -------
        TonalTrack or None
            Line frequency (Hz) and SNR (dB), window times (s), frequency per window (Hz, NaN where not seen) and
            its standard deviation (Hz); None when there is no window or no line.
        """
        if self.n_windows == 0:
            return None
        other = [o.mean_spectrum() for o in others if o is not self and o.n_windows and o.n_bins == self.n_bins]
        line = pick_line(self.mean_spectrum(), self._freqs_hz, self.settings, np.array(other) if other else None,
                         self.n_windows)
        if line is None:
            return None
        cands = np.frombuffer(self._candidates, dtype=float).reshape(self.n_windows, self.settings.max_candidates)
        raw = follow_line(cands, line[0], self.settings)
        sigma, freq = frequency_sigma_hz(raw, self.settings)
        return TonalTrack(line[0], line[1], np.array(self._times), freq, sigma)
