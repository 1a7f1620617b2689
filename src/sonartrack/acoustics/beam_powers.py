"""Beam powers of a uniform line array over a band: conventional beamforming by lag products, and the split array.

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

The array (N, d, c) is one :class:`~sonartrack.acoustics.line_array.LineArray`; the processing band is
resolved and checked once per recording (:func:`front_end_band`) and handed to the power functions.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from sonartrack.acoustics.beamformer_settings import BeamformerSettings
from sonartrack.acoustics.blas_threads import blas_reachable, one_blas_thread
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.xcorr_bearing import correlate_window
from sonartrack.core.errors import require

#: windows whose lag vectors are computed together (:func:`_lag_vectors`): the element transforms' arrays of a few
#: windows stay in the core's cache (measured at 32 x 8 kHz, whitening included: 0.31 s per 10 minutes against 0.57 s
#: for whole batches)
LAG_CHUNK_WINDOWS = 4


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
    block, fs_hz, array : ndarray (N, M), float, LineArray
        As :func:`split_array_powers`'s: one window of the N elements, the sample rate (Hz), the array.
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
