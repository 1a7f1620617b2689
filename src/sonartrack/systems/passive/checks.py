"""The recording checked for what it is before the passive chain processes it, from a cheap first pass.

The chain turns any numbers into beams and peaks, so a file that is no array recording still gives "targets"
(a DC offset or a clipped square wave gives targets 100 m away, moving with the ownship). :func:`first_pass`
reads a few excerpts (:data:`EXCERPTS` of :data:`EXCERPT_S` seconds spread over the file, in the chain's
windows; not a second full read) and keeps per-channel statistics, the mean power spectrum and the delay of the
strongest common signal of neighbouring channels; :func:`check_recording` then refuses, in one line each,

* silence (every sample zero) and a constant (DC only, no fluctuation);
* clipping: a share of at least :data:`CLIP_ERROR_SHARE` of the samples sitting at their channel's extremes (a
  square wave), a warning from :data:`CLIP_WARN_SHARE` (levels are wrong, harmonics make false lines);
* a processing band that holds no frequency bin of a window (narrower than the resolution 1 / window_s), or no
  signal: its median power 60 dB (:data:`EMPTY_BAND_RATIO`) below the recording's (a warning from 30 dB);
* channels that hear a common signal further apart in time than the spacing allows: a plane or spherical wave
  reaches two sensors d apart at most d / c apart (the triangle inequality), so a significant cross-correlation
  peak at |lag| > d / c means the sensors are further apart than the spacing given (a 2-channel pair given the
  array's element spacing; a spacing in kilometres);

and :func:`check_aperture` the array implied by the settings: one shorter than a wavelength in the band (beams
wider than :data:`MAX_BEAMWIDTH_DEG`: a spacing in kilometres or millimetres), or so long that a wave takes more
than half a window to cross it (a spacing in centimetres).

The delay of neighbouring channels is the generalised cross-correlation with the phase transform (GCC-PHAT;
Knapp and Carter, "The generalized correlation method for estimation of time delay", IEEE Trans. ASSP 24(4),
1976, eq. 16 with the PHAT weight 1 / |G_12(f)| of their table I):

    R_12(tau) = sum_f  G_12(f) / |G_12(f)|  exp(2 pi i f tau),     G_12(f) = sum_blocks X_1(f) conj(X_2(f))

over the bins that hold signal; its peak is significant when it stands :data:`MIN_LAG_Z` robust standard
deviations (1.4826 MAD) above the median of R_12 over the lags.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.core.errors import InputError
from sonartrack.core.memory import MEMORY_LIMIT_BYTES, refuse_over_limit  # noqa: F401  (the limit re-exported here)

#: the first pass reads this many excerpts, spread from the file's start to its end ...
EXCERPTS = 3
#: ... of this many seconds each
EXCERPT_S = 10.0
#: share of samples at their channel's extremes (within 1e-6 of them) that is refused (a square wave) ...
CLIP_ERROR_SHARE = 0.25
#: ... and that is warned of (clipping)
CLIP_WARN_SHARE = 0.01
#: clipping is judged only on channels whose peak spans this many quantisation steps (a faint integer recording
#: sits at its few levels without being clipped)
MIN_CLIP_LEVELS = 64
#: the band's median power below this fraction of the recording's (95th percentile of the bins) holds no signal
EMPTY_BAND_RATIO = 1e-6
#: ... and below this fraction the band is warned of
FAINT_BAND_RATIO = 1e-3
#: fewer frequency bins than this in the band is warned of (the beams' background is estimated over few bins)
MIN_BAND_BINS = 4
#: a common signal's cross-correlation peak this many robust sd above the median is significant
MIN_LAG_Z = 8.0
#: neighbouring pairs whose delay is measured (from the front)
MAX_PAIRS = 4
#: channels whose spectrum enters the mean power spectrum (spread over the array)
MAX_SPECTRUM_CHANNELS = 16
#: beams wider than this at the band's centre give no bearing
MAX_BEAMWIDTH_DEG = 60.0
#: a wave must cross the array within this fraction of a window for the beams to align
MAX_APERTURE_WINDOW_FRACTION = 0.5
#: a longer line array is no array (the longest towed arrays are 1-2 km)
MAX_APERTURE_M = 10_000.0
#: relative tolerance of "at the extreme"
_EXTREME_TOL = 1e-6
_MAD_TO_SIGMA = 1.4826


@dataclass(frozen=True, slots=True)
class FirstPass:
    """Statistics of the excerpts read by :func:`first_pass` (N channels, F frequency bins, P neighbouring pairs).

    ``seconds``: the time looked at (s); ``mean``, ``ac_rms``, ``peak`` (N,): mean, standard deviation and largest
    |x| of each channel; ``extreme_count`` (N,): samples within 1e-6 of the channel's largest or smallest value;
    ``samples``: samples per channel; ``freq_hz`` (F,) and ``psd`` (F,): mean |X(f)|^2 of a Hann-windowed window over
    the channels and windows; ``lag_s`` (L,) and ``pair_z`` (P, L): the GCC-PHAT of channels (p, p + 1) against
    the lag, in robust standard deviations above its median (:func:`gcc_phat`)."""

    seconds: float
    fs_hz: float
    mean: np.ndarray
    ac_rms: np.ndarray
    peak: np.ndarray
    extreme_count: np.ndarray
    samples: int
    freq_hz: np.ndarray
    psd: np.ndarray
    lag_s: np.ndarray
    pair_z: np.ndarray


class _Accumulator:
    """Running sums of the first pass, fed one window (N, m) at a time."""

    def __init__(self, n: int, m: int, fs_hz: float, max_pairs: int):
        self.n, self.m, self.fs = n, m, fs_hz
        self.s1, self.s2 = np.zeros(n), np.zeros(n)
        self.hi, self.lo = np.full(n, -np.inf), np.full(n, np.inf)
        self.n_hi, self.n_lo = np.zeros(n, int), np.zeros(n, int)
        self.count = 0
        self.spectrum_channels = np.unique(np.linspace(0, n - 1, min(n, MAX_SPECTRUM_CHANNELS)).round().astype(int))
        self.pairs = min(max_pairs, n - 1)
        self.power = np.zeros(m // 2 + 1)
        self.cross = np.zeros((self.pairs, m // 2 + 1), complex)
        # a Hann taper: the sidelobes of a loud line fall as 1 / f^3, so an empty band reads as empty
        self.taper = np.hanning(m)

    def add(self, x: np.ndarray) -> None:
        self.s1 += x.sum(axis=1)
        self.s2 += np.einsum("ij,ij->i", x, x)
        self.count += x.shape[1]
        self.hi, self.n_hi = _extreme_count(x, self.hi, self.n_hi)
        lo, self.n_lo = _extreme_count(-x, -self.lo, self.n_lo)
        self.lo = -lo
        used = np.union1d(self.spectrum_channels, np.arange(self.pairs + 1))
        spectra = dict(zip(used, np.fft.rfft(x[used] * self.taper, axis=1), strict=True))
        self.power += np.mean([np.abs(spectra[k]) ** 2 for k in self.spectrum_channels], axis=0)
        for p in range(self.pairs):
            self.cross[p] += spectra[p] * np.conj(spectra[p + 1])

    def result(self, windows: int) -> FirstPass:
        mean = self.s1 / max(self.count, 1)
        var = np.maximum(self.s2 / max(self.count, 1) - mean**2, 0.0)
        psd = self.power / max(windows, 1)
        lags, z = gcc_phat(self.cross, psd, self.fs)
        return FirstPass(self.count / self.fs, self.fs, mean, np.sqrt(var), np.maximum(self.hi, -self.lo),
                         self.n_hi + self.n_lo, self.count, np.fft.rfftfreq(self.m, 1.0 / self.fs), psd, lags, z)


def _extreme_count(x: np.ndarray, top: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per channel: the largest value so far and how many samples lie within the tolerance of it."""
    new = np.maximum(top, x.max(axis=1))
    with np.errstate(invalid="ignore"):
        raised = np.isneginf(top) | (new > top + _EXTREME_TOL * np.abs(top))
    at = (x >= (new - _EXTREME_TOL * np.abs(new))[:, None]).sum(axis=1)
    return new, np.where(raised, at, count + at)


def gcc_phat(cross: np.ndarray, psd: np.ndarray, fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """The GCC-PHAT of each pair's summed cross-spectrum, in robust standard deviations (module doc).

    Parameters
    ----------
    cross : ndarray, complex, shape (P, F)
        Summed cross-spectra G_12(f) of P channel pairs over the rfft bins of a window of m samples.
    psd : ndarray, shape (F,)
        Mean power spectrum: only bins within 60 dB of its 95th percentile enter (and never DC).
    fs_hz : float
        Sample rate (Hz).

    Returns
    -------
    lag_s : ndarray (L,)
        The lags (s), within a quarter window either way.
    z : ndarray (P, L)
        (R_12 - median) / (1.4826 MAD) over those lags; zeros when fewer than 8 bins hold signal.
    """
    n_pairs, n_freq = cross.shape
    m = 2 * (n_freq - 1)
    q = m // 4
    lag_s = np.arange(-q, q + 1) / fs_hz
    ref = np.percentile(psd[1:], 95) if n_freq > 1 else 0.0
    use = (psd > EMPTY_BAND_RATIO * ref) & (np.arange(n_freq) > 0) & (ref > 0)
    if use.sum() < 8:
        return lag_s, np.zeros((n_pairs, lag_s.size))
    g = np.where(use, cross / np.maximum(np.abs(cross), 1e-300), 0.0)
    r = np.fft.fftshift(np.fft.irfft(g, m, axis=1), axes=1)[:, m // 2 - q: m // 2 + q + 1]
    med = np.median(r, axis=1, keepdims=True)
    mad = _MAD_TO_SIGMA * np.median(np.abs(r - med), axis=1, keepdims=True)
    return lag_s, np.where(mad > 0, (r - med) / np.where(mad > 0, mad, 1.0), 0.0)


def first_pass(excerpts: Iterable[Iterable[np.ndarray]], fs_hz: float, *, max_pairs: int = MAX_PAIRS) -> FirstPass:
    """Statistics of a recording's excerpts, window by window (module doc).

    Parameters
    ----------
    excerpts : iterable of iterables of ndarray (N, m)
        The excerpts, each as windows of m samples (the chain's windows).
    fs_hz : float
        Sample rate (Hz).
    max_pairs : int
        Neighbouring channel pairs whose delay is measured.

    Returns
    -------
    FirstPass
        The statistics (per-channel moments, extremes, mean spectrum, pair delays).
    """
    acc, windows = None, 0
    for excerpt in excerpts:
        for x in excerpt:
            acc = acc or _Accumulator(x.shape[0], x.shape[1], fs_hz, max_pairs)
            acc.add(np.asarray(x, float))
            windows += 1
    if acc is None:
        raise InputError("the recording has no whole window to check: it is shorter than one window_s")
    return acc.result(windows)


def excerpt_starts(n_windows: int, window_frames: int, fs_hz: float) -> list[tuple[int, int]]:
    """Where the first pass reads: :data:`EXCERPTS` runs of whole windows from the start to the end of the file.

    Parameters
    ----------
    n_windows : int
        Whole windows in the recording.
    window_frames : int
        Frames per window.
    fs_hz : float
        Sample rate (Hz).

    Returns
    -------
    list of (int, int)
        (start frame, stop frame) of each excerpt, in order, not overlapping.
    """
    per = max(1, min(int(round(EXCERPT_S * fs_hz / window_frames)), n_windows))
    if EXCERPTS * per >= n_windows:
        return [(0, n_windows * window_frames)]
    firsts = np.linspace(0, n_windows - per, EXCERPTS).round().astype(int)
    return [(int(w) * window_frames, (int(w) + per) * window_frames) for w in firsts]


def _check_level(fp: FirstPass, name: str, quantum: float | None) -> list[str]:
    """Silence, DC only, clipping; dead channels are a warning."""
    where = f"{name} ({fp.seconds:.0f} s read in {EXCERPTS} excerpts)"
    if not np.any(fp.peak > 0):
        raise InputError(f"{where} holds only zeros: there is no recording in it; check the file (a recorder "
                         "started without its hydrophones, or the wrong file)")
    live = fp.ac_rms > _EXTREME_TOL * np.maximum(np.abs(fp.mean), 1e-300)
    if not np.any(live):
        raise InputError(f"{where} holds a constant on every channel (mean {np.abs(fp.mean).max():.3g}, no "
                         "fluctuation): a DC offset is no sound; check the file and its channels")
    warnings = []
    if not np.all(live):
        dead = ", ".join(str(k + 1) for k in np.flatnonzero(~live))
        warnings.append(f"warning: {name}: channel(s) {dead} of {live.size} hold a constant (dead hydrophones?): "
                        "they lower the array gain and raise the beams' sidelobes")
    judged = live & (fp.peak >= MIN_CLIP_LEVELS * quantum if quantum else live)
    if np.any(judged):
        share = float(np.minimum(fp.extreme_count[judged] / fp.samples, 1.0).mean())
        if share >= CLIP_ERROR_SHARE:
            raise InputError(f"{where}: {100 * share:.0f} % of the samples sit at their channel's extremes (a clipped "
                             "or square-wave signal): its spectrum is made by the clipping, not by the sea; record "
                             "with less gain")
        if share >= CLIP_WARN_SHARE:
            warnings.append(f"warning: {name}: {100 * share:.1f} % of the samples sit at their channel's extremes "
                            "(clipping): levels are too low and clipping harmonics can show as tonal lines")
    return warnings


def _check_band(fp: FirstPass, name: str, band: Band, window_s: float) -> list[str]:
    """A band that holds no bin of a window, or no signal."""
    lo, hi = band.as_tuple()
    step = 1.0 / window_s
    n_bins = int(np.sum((fp.freq_hz >= lo) & (fp.freq_hz < hi) & (fp.freq_hz > 0)))
    if n_bins == 0 or hi - lo < step:
        raise InputError(f"the processing band {lo:g}-{hi:g} Hz is narrower than the frequency resolution of a "
                         f"{window_s:g} s window ({step:g} Hz; it holds {n_bins} bin(s)): widen band_hz to at least "
                         f"{MIN_BAND_BINS * step:g} Hz, or lengthen window_s")
    warnings = []
    if n_bins < MIN_BAND_BINS:
        warnings.append(f"warning: the processing band {lo:g}-{hi:g} Hz holds {n_bins} frequency bin(s) of a "
                        f"{window_s:g} s window: the beams' background is judged on few bins; widen band_hz")
    in_band = fp.psd[(fp.freq_hz >= lo) & (fp.freq_hz < hi) & (fp.freq_hz > 0)]
    ref = float(np.percentile(fp.psd[1:], 95))
    ratio = float(np.median(in_band)) / ref if ref > 0 else 0.0
    occupied = fp.freq_hz[1:][fp.psd[1:] > FAINT_BAND_RATIO * ref]
    span = f"{occupied.min():.0f}-{occupied.max():.0f} Hz" if occupied.size else "no band"
    db = -10 * np.log10(max(ratio, 1e-30))
    if ratio < EMPTY_BAND_RATIO:
        raise InputError(f"the processing band {lo:g}-{hi:g} Hz of {name} holds no signal ({db:.0f} dB below the "
                         f"recording's spectrum, which lies in {span}): choose band_hz within {span}")
    if ratio < FAINT_BAND_RATIO:
        warnings.append(f"warning: the processing band {lo:g}-{hi:g} Hz of {name} lies {db:.0f} dB below the "
                        f"recording's spectrum ({span}): a filter's skirt or quantisation noise, little sea")
    return warnings


def _check_delays(fp: FirstPass, name: str, array: LineArray) -> None:
    """Neighbouring channels that hear a common signal further apart in time than the spacing allows."""
    limit = array.spacing_m / array.sound_speed_mps
    outside = np.abs(fp.lag_s) > limit + 1.5 / fp.fs_hz
    if not np.any(outside):
        return
    z = np.where(outside, fp.pair_z, -np.inf)
    p, k = np.unravel_index(int(np.argmax(z)), z.shape)
    lag = abs(float(fp.lag_s[k]))
    # a band-limited correlation has sidelobes about 1 / bandwidth from its peak: only a peak outside the allowed
    # lags that stands above every one inside them says the channels are further apart
    inside = float(np.max(np.where(outside, -np.inf, fp.pair_z[p]))) if not np.all(outside) else -np.inf
    if z[p, k] >= MIN_LAG_Z and z[p, k] > inside:
        raise InputError(f"{name}: channels {p + 1} and {p + 2} hear a common signal {1e3 * lag:.2f} ms apart, more "
                         f"than the {1e3 * limit:.2f} ms a spacing of {array.spacing_m:g} m allows: they are at least "
                         f"{lag * array.sound_speed_mps:.3g} m apart; give their spacing in metres (--spacing; a "
                         "2-channel file is a pair, with the pair's spacing)")


def check_recording(fp: FirstPass, *, name: str, array: LineArray, band: Band, window_s: float,
                    quantum: float | None = None) -> list[str]:
    """Refuse a recording that is not what the chain needs, or warn where the run can still say something true.

    Parameters
    ----------
    fp : FirstPass
        The first pass over the recording (:func:`first_pass`).
    name : str
        The file's name (for the messages).
    array : LineArray
        The array as set (elements, spacing in m, sound speed in m/s).
    band : Band
        The processing band (Hz).
    window_s : float
        The chain's window (s): the band's frequency resolution is 1 / window_s.
    quantum : float, optional
        One quantisation step of the samples (2^-15 for 16-bit PCM scaled to [-1, 1)); None for float samples.

    Returns
    -------
    list of str
        Warning lines (empty when all is well). Raises :class:`~sonartrack.core.errors.InputError` with the fix
        for silence, DC only, a square wave, a band without bins or signal, or delays the spacing cannot give.
    """
    warnings = _check_level(fp, name, quantum)
    warnings += _check_band(fp, name, band, window_s)
    _check_delays(fp, name, array)
    return warnings


def check_aperture(array: LineArray, band: Band, window_s: float) -> None:
    """Refuse an array that the spacing makes implausible for its element count (module doc).

    Parameters
    ----------
    array : LineArray
        Elements, spacing (m), sound speed (m/s).
    band : Band
        The processing band (Hz).
    window_s : float
        The chain's window (s).

    Raises
    ------
    InputError
        When the beams at the band's centre are wider than :data:`MAX_BEAMWIDTH_DEG` (an array shorter than a
        wavelength), when a wave takes more than half a window to cross the array, or when it is longer than
        :data:`MAX_APERTURE_M`.
    """
    n, d, c = array.elements, array.spacing_m, array.sound_speed_mps
    length = (n - 1) * d
    what = f"{n} elements {d:g} m apart ({length:.3g} m)"
    width = array.beamwidth_deg(band.centre_hz)
    if width > MAX_BEAMWIDTH_DEG:
        raise InputError(f"an array of {what} is shorter than a wavelength in the band ({c / band.centre_hz:.3g} m at "
                         f"{band.centre_hz:.0f} Hz): its beams are {min(width, 999):.0f} deg wide and give no bearing; "
                         "is --spacing in metres (not kilometres)?")
    if length > MAX_APERTURE_M or length / c > MAX_APERTURE_WINDOW_FRACTION * window_s:
        raise InputError(f"an array of {what} takes a wave {length / c:.3g} s to cross, more than half a {window_s:g} "
                         "s window, so its beams cannot form: is --spacing in metres (not centimetres)? (or "
                         "lengthen window_s)")


#: one quantisation step of integer samples scaled to [-1, 1)
QUANTUM = {"int16": 2.0**-15, "int24": 2.0**-23, "int32": 2.0**-31}




def memory_needs(stages, n_windows: int) -> list[tuple[float, str, str]]:
    """The chain's largest working arrays for a recording: bytes, what sizes them, and the fix.

    With N elements, B beams, F band bins of a window of m samples, Q distinct lag-bin products of the band
    (acoustics/beamforming.py ``lag_bin_products``: 43-50 % of (N - 1) F), K = 32 windows a batch and c bytes a
    complex spectrum value (8 for ``fft_precision`` single, 16 for double): the CBF steering matrix, cosine and sine
    halves of ceil(B / 2) x Q float64 each; a batch's band spectra and lag vectors, c N F + 16 Q bytes a window,
    and the working arrays of the few windows whose lags are made together (``LAG_CHUNK_WINDOWS``: the 2N-point
    transform along the elements, its power, the lags), 7 c N F bytes a window (the peak measured with tracemalloc,
    within 30 % for 16 to 64 elements); the bearing-time record T x B (float32, and the picture's float64 copy); with
    the narrowband pass (acoustics/lofar.py), its real weights F_l x (B_l + 1) x N of the beams' mirror pairs
    (float64 and a float32 copy) and the gram of T / L periods x B_l beams x F_l bins at 20 bytes a cell: each period
    is normalised as it completes and kept as float64 power and float32 statistic (12 bytes), and the float32 gram
    stacked from them at the end (8 more; the line search then works through the gram in chunks of periods).

    Parameters
    ----------
    stages : PassiveStages
        The chain's built settings (array, band, window, beams, narrowband).
    n_windows : int
        Windows T of the recording.

    Returns
    -------
    list of (float, str, str)
        Bytes (an estimate), what needs them (with the settings), how to need less.
    """
    from sonartrack.acoustics.beamforming import BATCH_WINDOWS, LAG_CHUNK_WINDOWS, lag_bin_products

    n, b = stages.array.elements, stages.front_end.beams
    window_s = stages.settings.window_s
    f = max(int((stages.band.high_hz - stages.band.low_hz) * window_s) + 1, 1)
    first = max(int(np.ceil(stages.band.low_hz * window_s)), 1)
    q = lag_bin_products(n, np.arange(first, first + f)).size
    c = 8.0 if stages.front_end.fft_precision == "single" else 16.0
    needs = [
        (16.0 * ((b + 1) // 2) * q, f"the beams' steering matrix ({b} [front_end] beams x {n} elements x "
         f"{f} bins of band_hz in a {window_s:g} s window)", "fewer [front_end] beams, a narrower band_hz or a "
                                                              "shorter window_s"),
        (BATCH_WINDOWS * (16.0 * q + c * n * f) + LAG_CHUNK_WINDOWS * 7.0 * c * n * f, f"a batch of {BATCH_WINDOWS} "
         f"windows' band spectra ({n} channels x {f} bins of window_s {window_s:g} s)",
         "a narrower band_hz or a shorter window_s"),
        (12.0 * n_windows * b, f"the bearing-time record ({n_windows} windows x {b} [front_end] beams)",
         "fewer [front_end] beams, or a longer window_s"),
    ]
    nb = stages.settings.narrowband
    if nb.enabled:
        needs += _lofar_needs(stages, n_windows)
    return needs


def _lofar_needs(stages, n_windows: int) -> list[tuple[float, str, str]]:
    """The narrowband pass's steering and gram (:func:`memory_needs`)."""
    from sonartrack.acoustics.lofar import lofar_band

    nb, n, window_s = stages.settings.narrowband, stages.array.elements, stages.settings.window_s
    lo, hi = lofar_band(stages.array, stages.fs_hz, nb)
    f = max(int((hi - lo) * window_s) + 1, 1)
    periods = n_windows // nb.integration
    return [(12.0 * f * (nb.beams + 1) * n, f"the narrowband beams' steering ({nb.beams} [narrowband] beams x {n} "
             f"elements x {f} bins)", "fewer [narrowband] beams or a narrower [narrowband] band_hz"),
            (20.0 * periods * nb.beams * f, f"the LOFAR gram ({periods} periods of {nb.integration} windows x "
             f"{nb.beams} [narrowband] beams x {f} bins)", "a shorter recording (split it), a longer [narrowband] "
                                                           "integration, fewer beams or a narrower band_hz")]


def check_memory(stages, n_windows: int) -> None:
    """Refuse settings whose working arrays (:func:`memory_needs`) together exceed
    :data:`~sonartrack.core.memory.MEMORY_LIMIT_BYTES` (they are held at once: the steering matrix while a batch of
    spectra is beamformed, the record and the gram as they grow), naming the largest and how to shrink it.

    Parameters
    ----------
    stages : PassiveStages
        The chain's built settings.
    n_windows : int
        Windows of the recording.

    Raises
    ------
    InputError
        Naming the array, its size in GB and the settings that make it.
    """
    refuse_over_limit(memory_needs(stages, n_windows), "the chain's")


# the residual tests of a fit moved to the tma layer, where ``sonartrack tma`` uses them too (one mechanism);
# re-exported here for the chain's modules and tests that import them from this one
from sonartrack.tma.record_checks import (  # noqa: E402, F401
    MAX_RESIDUAL_SCALE,
    PROFILE_FAR_FACTOR,
    PROFILE_MIN_RISE,
    PROFILE_SIGMAS,
    RESIDUAL_ALPHA,
    RESIDUAL_BLOCK_S,
    ResidualCheck,
    range_profile_rise,
    residual_check,
    residual_scale,
)
