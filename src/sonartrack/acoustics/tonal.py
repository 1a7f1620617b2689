"""A tracked target's tonal line, measured on its beam window by window (the frequency input of paper P2).

Each window's beam spectrum and its peaks are acoustics/tonal_spectra.py's (public names importable from here).

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

import numpy as np
from pydantic import model_validator

from sonartrack.acoustics.beam_peaks import MAD_TO_SIGMA
from sonartrack.acoustics.tonal_spectra import (
    _background_bins,
    _median_filter,
    _peak_bins,
    _refined_hz,
    beam_spectra,
    beam_spectra_of_rect,
    spectral_peaks,
    tonal_rect_bins,
    window_peak_bins,
    window_snr_db,
)
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting

__all__ = [
    "MAD_TO_SIGMA", "PROVISIONAL_EVERY", "TonalAccumulator", "TonalSettings", "TonalTrack", "beam_spectra",
    "beam_spectra_of_rect", "follow_line", "frequency_sigma_hz", "line_threshold_db", "pick_line", "spectral_peaks",
    "tonal_rect_bins", "window_peak_bins", "window_snr_db",
]

#: windows between renewals of the accumulator's provisional lines (the mean spectrum changes slowly)
PROVISIONAL_EVERY = 8



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
