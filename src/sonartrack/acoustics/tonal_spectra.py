"""Power spectra of one beam, window by window, and their peaks with the Hann-window frequency refinement.

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

The tonal line followed over these windows is acoustics/tonal.py's.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING

import numpy as np

from sonartrack.acoustics.line_array import LineArray
from sonartrack.core.errors import require

if TYPE_CHECKING:  # the settings' module (acoustics/tonal.py) imports this one
    from sonartrack.acoustics.tonal import TonalSettings


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
    freqs_hz, power : ndarray (F,), ndarray (k, F)
        As :func:`beam_spectra`'s: the band's frequencies (Hz) and each beam's PSD (input units^2 / Hz).
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
