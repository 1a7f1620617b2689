"""Synthetic cross-correlation peaks from the stochastic model of Park, Ryu & Lee 1994 (paper P0, sec. III).

Per scan (1 s) over a bearing sector:

* each target's true peak is present with probability ``p_detect`` (we take 1 at threshold 0: the
  correlation of a tracked source always peaks somewhere), at N(true bearing, sigma_p^2), with
  amplitude N(z_a, sigma_a^2) (clipped at 0);
* false peaks are Poisson with ``false_rate`` per gate of ``gate_deg`` (the paper's lambda V counted
  at threshold 0; we read the background lambda V = 2 as false peaks only), uniform in bearing over
  the sector, with exponential amplitudes of rate alpha;
* an amplitude threshold then removes every peak below it (the tracker's input).

The paper's fits: strong track lambda V = 2, z_a = 21000, sigma_a = 2500, sigma_p = 1.3 deg; weak track
lambda V = 3, z_a = 12000, sigma_a = 3500, sigma_p = 1.8 deg; background lambda V = 2, alpha = 4e-4;
tracking threshold 5000. The per-track lambda V values (which include the true peak and multipath
near it) are not used to add clutter: the background rate applies everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class TrackPeaks:
    """A target's peak statistics: amplitude mean and spread, position spread (deg)."""

    amplitude_mean: float
    amplitude_sd: float
    sigma_p_deg: float


STRONG = TrackPeaks(21_000.0, 2_500.0, 1.3)
WEAK = TrackPeaks(12_000.0, 3_500.0, 1.8)


@dataclass(frozen=True, slots=True)
class PeakModel:
    """Background false peaks, detection and the amplitude threshold (module doc)."""

    false_rate: float = 2.0  # false peaks per gate, at threshold 0
    gate_deg: float = 10.0
    false_amplitude_rate: float = 4e-4  # alpha (1 / amplitude unit)
    amplitude_threshold: float = 5_000.0
    p_detect: float = 1.0
    sector_deg: tuple[float, float] = (0.0, 180.0)

    @property
    def false_density_per_deg(self) -> float:
        """Clutter density above the threshold, per degree: lambda exp(-alpha tau)."""
        return self.false_rate / self.gate_deg * np.exp(-self.false_amplitude_rate * self.amplitude_threshold)


@dataclass(frozen=True, slots=True)
class Scan:
    """One scan's peaks after the threshold: bearings (deg), amplitudes, origin (target index or -1)."""

    bearing_deg: np.ndarray
    amplitude: np.ndarray
    origin: np.ndarray


def generate_scans(rng: np.random.Generator, model: PeakModel, true_bearing_deg: np.ndarray,
                   targets: list[TrackPeaks]) -> list[Scan]:
    """Synthetic thresholded cross-correlation peaks, scan by scan, from paper P0's model (module docstring).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    model : PeakModel
        Background false peaks, detection and the amplitude threshold.
    true_bearing_deg : array_like, shape (K, n_targets)
        True bearing of each target at each scan (deg).
    targets : list of TrackPeaks
        Peak statistics of each target (amplitude mean and spread, position spread in deg).

    Returns
    -------
    list of Scan
        K scans: peak bearings (deg), amplitudes (correlator output unit) and origin (target index, -1 false).
    """
    tb = np.atleast_2d(np.asarray(true_bearing_deg, dtype=float))
    K, n = tb.shape
    lo, hi = model.sector_deg
    rate = model.false_rate / model.gate_deg * (hi - lo)
    n_false = rng.poisson(rate, K)
    det = rng.random((K, n)) < model.p_detect
    pos_noise = rng.normal(size=(K, n))
    amp_noise = rng.normal(size=(K, n))
    out = []
    for k in range(K):
        fb = rng.uniform(lo, hi, n_false[k])
        fa = rng.exponential(1.0 / model.false_amplitude_rate, n_false[k])
        tb_k = np.array([tb[k, i] + targets[i].sigma_p_deg * pos_noise[k, i] for i in range(n)])
        ta_k = np.array([max(targets[i].amplitude_mean + targets[i].amplitude_sd * amp_noise[k, i], 0.0)
                         for i in range(n)])
        b = np.concatenate([tb_k[det[k]], fb])
        a = np.concatenate([ta_k[det[k]], fa])
        o = np.concatenate([np.nonzero(det[k])[0], np.full(n_false[k], -1)])
        keep = (a >= model.amplitude_threshold) & (b >= lo) & (b <= hi)
        out.append(Scan(b[keep], a[keep], o[keep]))
    return out
