"""Cross-correlation bearing estimator of a two-sensor array (Park, Ryu & Lee 1994, paper P0, sec. II).

Per observation window (1 s by default) of the two channels r1, r2:

    R12(tau) = sum_t r1(t) r2(t + tau) / sqrt(E1 E2)          (FFT: irfft(conj(R1) R2), zero-padded)

restricted to the physical lags |tau| <= d / c. Every local maximum above the threshold is a peak;
its lag is refined by fitting a parabola through the three samples around it (sub-sample accuracy
~ a few per cent of a sample at good SNR), and converted to the cone angle

    theta = arccos(c tau / d)     (0..180 deg from the array axis; clipped to [-1, 1])

Amplitudes are the normalised correlation scaled by ``AMPLITUDE_SCALE`` = 30000, so that a perfect
correlation matches the top of the paper's amplitude range (0..30000) and its threshold of 5000
corresponds to a normalised correlation of 1/6. The bearing resolution is set by the sample rate:
one sample of lag is c / (fs d sin theta) rad of bearing, coarsest near endfire (0 and 180 deg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting

AMPLITUDE_SCALE = 30_000.0
DEFAULT_THRESHOLD = 5_000.0


class BearingSettings(Settings):
    """Settings of the cross-correlation bearing estimator (``sonartrack bearings``; paper P0's values)."""

    spacing_m: float = setting(..., "sensor (or half-array centre) spacing d", unit="m", gt=0, le=1000)
    sound_speed_mps: float = setting(1500.0, "sound speed c at the array", unit="m/s", ge=1300, le=1700)
    window_s: float = setting(1.0, "observation window of one correlation", unit="s", gt=0, le=3600)
    threshold: float = setting(DEFAULT_THRESHOLD, "peak amplitude threshold (amplitudes 0..30000 = normalised "
                               "correlation 0..1; 5000 = 1/6)", unit="1", ge=0)
    max_peaks: int = setting(20, "largest number of peaks kept per window (the highest)", unit="1", ge=1)


@dataclass(frozen=True, slots=True)
class PeakRecord:
    """All peaks, a row per peak: window-centre time (s), cone angle (deg), amplitude."""

    time_s: np.ndarray
    bearing_deg: np.ndarray
    amplitude: np.ndarray

    def by_scan(self) -> list[tuple[float, np.ndarray, np.ndarray]]:
        """(time, bearings deg, amplitudes) per distinct time, in time order.

        Returns
        -------
        list of (float, ndarray, ndarray)
            Window time (s), cone angles (deg from the array axis) and amplitudes (0..30000) of its peaks.
        """
        t = np.asarray(self.time_s)
        out = []
        for tk in np.unique(t):
            m = t == tk
            out.append((float(tk), self.bearing_deg[m], self.amplitude[m]))
        return out


def correlate_window(r1: np.ndarray, r2: np.ndarray, max_lag: int) -> np.ndarray:
    """Normalised cross-correlation R12(tau) for tau = -max_lag..max_lag samples.

    Parameters
    ----------
    r1, r2 : ndarray, shape (n,)
        The two channels of one window (any pressure unit; the result is normalised).
    max_lag : int
        Largest lag (samples).

    Returns
    -------
    ndarray, shape (2 max_lag + 1,)
        R12 at lags -max_lag..max_lag (unnormalised when a channel has zero energy).
    """
    n = len(r1)
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    X1 = np.fft.rfft(r1, nfft)
    X2 = np.fft.rfft(r2, nfft)
    cc = np.fft.irfft(np.conj(X1) * X2, nfft)
    e = np.sqrt(np.dot(r1, r1) * np.dot(r2, r2))
    lags = np.concatenate([cc[nfft - max_lag:], cc[: max_lag + 1]])
    return lags / e if e > 0 else lags


def pick_peaks(cc: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Local maxima of ``cc`` at or above ``threshold``: (fractional index, height), parabolic refinement.

    Parameters
    ----------
    cc : ndarray, shape (L,)
        A correlation function.
    threshold : float
        Smallest peak height (units of ``cc``).

    Returns
    -------
    position : ndarray, shape (p,)
        Fractional indices into ``cc`` (refinement clipped to +-0.5 sample).
    height : ndarray, shape (p,)
        Heights of the fitted parabolas at their vertices.
    """
    if len(cc) < 3:
        return np.zeros(0), np.zeros(0)
    mid = cc[1:-1]
    idx = np.nonzero((mid > cc[:-2]) & (mid >= cc[2:]) & (mid >= threshold))[0] + 1
    y0, y1, y2 = cc[idx - 1], cc[idx], cc[idx + 1]
    den = y0 - 2 * y1 + y2
    delta = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
    delta = np.clip(delta, -0.5, 0.5)
    return idx + delta, y1 - 0.25 * (y0 - y2) * delta


def cone_angle_deg(lag_s, spacing_m: float, sound_speed_mps: float) -> np.ndarray:
    """theta = arccos(c tau / d) in degrees (0..180 from the array axis; c tau / d clipped to [-1, 1]).

    Parameters
    ----------
    lag_s : float or array_like
        Time lag tau (s).
    spacing_m : float
        Sensor spacing d (m).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    ndarray
        Cone angles (deg from the array axis, 0 = ahead), shape of ``lag_s``.
    """
    return np.rad2deg(np.arccos(np.clip(sound_speed_mps * np.asarray(lag_s, dtype=float) / spacing_m, -1.0, 1.0)))


def window_count(n_samples: int, fs_hz: float, window_s: float) -> int:
    """Number of whole observation windows of ``window_s`` in ``n_samples`` samples (a partial last one is dropped).

    Parameters
    ----------
    n_samples : int
        Samples in the recording.
    fs_hz : float
        Sample rate (Hz).
    window_s : float
        Window length (s; rounded to whole samples).

    Returns
    -------
    int
        The number of whole windows.
    """
    return int(n_samples // int(round(window_s * fs_hz)))


def window_peaks(r1: np.ndarray, r2: np.ndarray, max_lag: int, threshold: float,
                 max_peaks: int) -> tuple[np.ndarray, np.ndarray]:
    """(fractional lag index in 0..2 max_lag, normalised height) of the strongest ``max_peaks`` peaks of one window.

    Parameters
    ----------
    r1, r2 : ndarray, shape (n,)
        The two channels of the window (means removed here).
    max_lag : int
        Largest lag (samples).
    threshold : float
        Smallest normalised correlation of a peak.
    max_peaks : int
        Most peaks kept (the highest).

    Returns
    -------
    position : ndarray, shape (p,)
        Fractional lag indices (lag = position - max_lag samples).
    height : ndarray, shape (p,)
        Normalised correlations.
    """
    cc = correlate_window(r1 - r1.mean(), r2 - r2.mean(), max_lag)
    pos, h = pick_peaks(cc, threshold)
    if len(pos) > max_peaks:
        keep = np.argsort(-h)[:max_peaks]
        pos, h = pos[keep], h[keep]
    return pos, h


def _check_recording(x: np.ndarray, fs_hz: float, spacing_m: float, sound_speed_mps: float, window_s: float) -> None:
    require(x.ndim == 2 and x.shape[0] == 2, f"need two channels as a (2, n) array, got shape {x.shape}")
    require(spacing_m > 0, f"sensor spacing must be positive, got {spacing_m:g} m")
    require(sound_speed_mps > 0 and fs_hz > 0 and window_s > 0, "sound speed, sample rate and window must be positive")
    require(bool(np.all(np.isfinite(x))), "the recording contains NaN/inf samples")
    require(x.shape[1] >= window_s * fs_hz, f"the recording is {x.shape[1] / fs_hz:.2f} s long, shorter than one "
                                            f"{window_s:g} s window")


def estimate_peaks(signals, fs_hz: float, spacing_m: float, sound_speed_mps: float = 1500.0, window_s: float = 1.0,
                   threshold: float | None = None, max_peaks: int = 20) -> PeakRecord:
    """Peaks of every window of a (2, n) recording (module doc); ``threshold`` in amplitude units.

    Parameters
    ----------
    signals : array_like, shape (2, n)
        The two channels.
    fs_hz : float
        Sample rate (Hz).
    spacing_m : float
        Sensor spacing d (m).
    sound_speed_mps : float
        Sound speed c (m/s).
    window_s : float
        Observation window (s).
    threshold : float, optional
        Peak threshold in amplitude units 0..30000 (default :data:`DEFAULT_THRESHOLD` = 5000).
    max_peaks : int
        Most peaks kept per window.

    Returns
    -------
    PeakRecord
        Peak times (s, window centres), cone angles (deg from the array axis) and amplitudes (0..30000).
    """
    x = np.asarray(signals, dtype=float)
    _check_recording(x, fs_hz, spacing_m, sound_speed_mps, window_s)
    thr = (DEFAULT_THRESHOLD if threshold is None else float(threshold)) / AMPLITUDE_SCALE
    nw = int(round(window_s * fs_hz))
    require(nw >= 16, f"window of {window_s:g} s holds only {nw} samples at {fs_hz:g} Hz")
    max_lag = int(np.ceil(spacing_m / sound_speed_mps * fs_hz)) + 1
    require(max_lag < nw // 2, "the array is too long for the window: lengthen --window")
    ts, bs, amps = [], [], []
    for k in range(window_count(x.shape[1], fs_hz, window_s)):
        seg = x[:, k * nw:(k + 1) * nw]
        pos, h = window_peaks(seg[0], seg[1], max_lag, thr, max_peaks)
        ts.append(np.full(len(pos), (k + 0.5) * window_s))
        bs.append(cone_angle_deg((pos - max_lag) / fs_hz, spacing_m, sound_speed_mps))
        amps.append(h * AMPLITUDE_SCALE)
    if not ts:
        return PeakRecord(np.zeros(0), np.zeros(0), np.zeros(0))
    return PeakRecord(np.concatenate(ts), np.concatenate(bs), np.concatenate(amps))


def bearings_from_recording(signals, fs_hz: float, settings: BearingSettings) -> PeakRecord:
    """:func:`estimate_peaks` with the declared settings of ``sonartrack bearings``.

    Parameters
    ----------
    signals, fs_hz : array_like (2, n), float
        The two channels and their sample rate (Hz), as :func:`estimate_peaks`'s.
    settings : BearingSettings
        Spacing (m), sound speed (m/s), window (s), threshold, most peaks per window.

    Returns
    -------
    PeakRecord
        As :func:`estimate_peaks`.
    """
    s = settings
    return estimate_peaks(signals, fs_hz, s.spacing_m, s.sound_speed_mps, s.window_s, s.threshold, s.max_peaks)


def peaks_summary(record: PeakRecord, n_samples: int, fs_hz: float, window_s: float) -> str:
    """One line on the peaks ``record`` of a recording of ``n_samples`` samples at ``fs_hz`` (Hz), in windows of
    ``window_s`` (s): windows, peaks, peaks a window and their median amplitude."""
    n_win = window_count(n_samples, fs_hz, window_s)
    n = len(record.time_s)
    median = float(np.median(record.amplitude)) if n else 0.0
    return (f"{n_win} windows of {window_s:g} s at {fs_hz:g} Hz, {n} peaks ({n / max(n_win, 1):.1f} a window, "
            f"median amplitude {median:.0f})")
