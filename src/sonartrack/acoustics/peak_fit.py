"""Fitting the stochastic peak model (paper P0, sec. III) to peaks around reference tracks.

Given scans of peaks and, per scan, reference bearings of the tracks (the truth in simulation, or
confirmed tracks on real data), each track's gate is the window of ``gate_deg`` centred on it:

* sigma_p (per track): the standard deviation of (nearest peak - reference) within +-3 sigma_p,
  divided by 0.9866 (the standard deviation of a normal truncated at 3 sigma), iterated from the whole
  gate: clutter peaks in the gate then barely inflate it;
* z_a, sigma_a (per track): mean and standard deviation of the amplitude of the strongest peak within
  those +-3 sigma_p (the true peak; choosing the nearest instead would pick clutter in ~5 % of scans
  and bias z_a low by ~3 %); that same peak gives the position residual;
* lambda V: the mean number of the *other* peaks per gate-width of bearing, counted away from every
  track (background), rescaled from the threshold tau back to threshold 0 by exp(alpha tau);
* alpha: maximum likelihood for the shifted exponential above the threshold, 1 / mean(z - tau), from
  the background peaks.

The paper's histograms of these quantities are drawn by report/figures/jpda_amplitude.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require


@dataclass(frozen=True, slots=True)
class FittedPeakModel:
    """Paper P0's peak model as fitted (module docstring).

    ``false_rate`` lambda V at threshold 0 (false peaks per gate width); ``false_amplitude_rate`` alpha
    (1 / amplitude unit); per track ``sigma_p_deg`` (deg), ``amplitude_mean`` z_a and ``amplitude_sd``
    sigma_a (amplitude units); ``n_background`` the number of background peaks behind alpha.
    """
    false_rate: float  # lambda V at threshold 0
    false_amplitude_rate: float  # alpha
    sigma_p_deg: np.ndarray  # per track
    amplitude_mean: np.ndarray
    amplitude_sd: np.ndarray
    n_background: int


def fit_peak_model(scans, reference_deg, gate_deg: float = 10.0, threshold: float = 5000.0,
                   sector_deg: tuple[float, float] = (0.0, 180.0)) -> FittedPeakModel:
    """Estimate paper P0's stochastic peak model from peaks around reference tracks (module docstring).

    Parameters
    ----------
    scans : sequence of (array_like, array_like)
        Per scan, the peak bearings (deg) and amplitudes.
    reference_deg : array_like, shape (K, n)
        Reference bearing of each of n tracks at each of the K scans (deg).
    gate_deg : float, default 10.0
        Gate width V (deg), centred on each reference.
    threshold : float, default 5000.0
        Amplitude threshold tau the peaks passed.
    sector_deg : tuple of float, default (0.0, 180.0)
        Bearing sector searched (deg).

    Returns
    -------
    FittedPeakModel
        lambda V, alpha, and per track sigma_p, z_a, sigma_a (NaN where a track had no peak). InputError if
        the references do not match the scans or the gates cover the whole sector.
    """
    ref = np.atleast_2d(np.asarray(reference_deg, dtype=float))
    require(len(scans) == len(ref) and len(scans) > 0, "need one reference row per scan, and at least one scan")
    n = ref.shape[1]
    resid = [[] for _ in range(n)]
    amps = [[] for _ in range(n)]
    bg_amp = []
    bg_count, bg_width = 0, 0.0
    half = gate_deg / 2
    lo, hi = sector_deg
    first = _first_pass_sigma(scans, ref, half)
    for (b, a), r in zip(scans, ref, strict=True):
        b = np.asarray(b, dtype=float)
        a = np.asarray(a, dtype=float)
        near_any = np.zeros(len(b), dtype=bool)
        for i in range(n):
            d = b - r[i]
            near_any |= np.abs(d) <= half
            inside = np.abs(d) <= min(half, 3.0 * first[i])
            if inside.any():
                j = np.argmax(np.where(inside, a, -np.inf))  # the strongest: clutter is rarely as strong
                resid[i].append(d[j] / TRUNCATED_SD_3)
                amps[i].append(a[j])
        # background: the sector minus the gates of the tracks
        covered = sum(min(hi, ri + half) - max(lo, ri - half) for ri in r if ri + half > lo and ri - half < hi)
        bg_width += (hi - lo) - covered
        bg_count += int(np.sum(~near_any))
        bg_amp.extend(a[~near_any].tolist())
    require(bg_width > 0, "no bearing sector is left outside the tracks' gates")
    bg_amp = np.asarray(bg_amp)
    alpha = 1.0 / np.mean(bg_amp - threshold) if len(bg_amp) else np.nan
    rate_above = bg_count / bg_width * gate_deg
    return FittedPeakModel(float(rate_above * np.exp(alpha * threshold)) if np.isfinite(alpha) else np.nan,
                           float(alpha), np.array([np.std(v) if v else np.nan for v in resid]),
                           np.array([np.mean(v) if v else np.nan for v in amps]),
                           np.array([np.std(v, ddof=1) if len(v) > 1 else np.nan for v in amps]), len(bg_amp))


#: standard deviation of a unit normal truncated to +-3
TRUNCATED_SD_3 = 0.98657


def _first_pass_sigma(scans, ref, half, iterations: int = 4) -> np.ndarray:
    out = []
    for i in range(ref.shape[1]):
        sig, k = half, None
        for _ in range(iterations):
            win = half if k is None else min(half, 3.0 * sig)
            d_all = []
            for (b, _), r in zip(scans, ref, strict=True):
                d = np.asarray(b, dtype=float) - r[i]
                d = d[np.abs(d) <= win]
                if len(d):
                    d_all.append(d[np.argmin(np.abs(d))])
            if not d_all:
                break
            sig = np.std(d_all) / (1.0 if k is None else TRUNCATED_SD_3)
            k = 3.0
        out.append(sig)
    return np.array(out)
