"""Amplitude-aided association for JPDA_A (Park, Ryu & Lee 1994, paper P0, appendix A, eq. 9).

Peaks pass an amplitude threshold tau before tracking. Above it:

* a false peak's amplitude is exponential, alpha exp(-alpha z) on [0, inf), so above tau it is
  alpha exp(-alpha (z - tau)) (memoryless), and the clutter density scales by exp(-alpha tau);
* a true peak of a track with strength z_hat and spread sigma_a is N(z; z_hat, sigma_a^2), detected
  only if z > tau: its P_D becomes P_D0 Phi((z_hat - tau) / sigma_a) and its density above tau is
  N(z; z_hat, sigma_a^2) / Phi(...), so P_D x density = P_D0 N(z; z_hat, sigma_a^2) (the Phi cancel).

JPDA_A multiplies each pair weight of JPDA by the amplitude likelihood ratio

    log r_tj = log N(z_j; z_hat_t, sigma_a,t^2) - log(alpha exp(-alpha (z_j - tau)))

(with the thresholded P_D used in the miss weight). Equal amplitude densities give r = 1: JPDA.

Track strength (eq. 9): z_hat(k) = 0.7 z_hat(k-1) + 0.3 max_j z(k, j) over the track's gate, from 15000.
"""

from __future__ import annotations

import functools

import numpy as np

#: eq. 9 smoothing and initial strength
STRENGTH_MEMORY = 0.7
STRENGTH_INITIAL = 15_000.0


def detection_probability_above(pd0, strength, sigma_a, threshold):
    """Detection probability after the amplitude threshold: P_D0 Phi((z_hat - tau) / sigma_a) (paper P0, app. A).

    Parameters
    ----------
    pd0 : float or array_like
        Detection probability before the threshold.
    strength : float or array_like, shape (n,)
        Track strength z_hat (peak amplitude, the unit of the correlator output).
    sigma_a : float or array_like
        Spread of a true peak's amplitude (same unit).
    threshold : float
        Amplitude threshold tau (same unit).

    Returns
    -------
    ndarray
        Thresholded P_D, broadcast shape of the inputs.
    """
    z = (np.asarray(strength, dtype=float) - threshold) / np.asarray(sigma_a, dtype=float)
    return np.asarray(pd0, dtype=float) * _ndtr()(z)


@functools.cache
def _ndtr():
    """scipy.special.ndtr, imported on first use (``import sonartrack`` stays fast), then looked up once."""
    from scipy.special import ndtr

    return ndtr


def amplitude_log_ratio(amplitudes, strength, sigma_a, alpha, threshold) -> np.ndarray:
    """Amplitude log likelihood ratio of JPDA_A (paper P0, appendix A).

    ``log r_tj = log N(z_j; z_hat_t, sigma_a,t^2) - log(alpha exp(-alpha (z_j - tau)))``.

    Parameters
    ----------
    amplitudes : array_like, shape (n_meas,)
        Peak amplitudes z_j (correlator output unit), all above ``threshold``.
    strength : array_like, shape (n_tracks,)
        Track strengths z_hat_t (same unit).
    sigma_a : array_like, shape (n_tracks,)
        Spread of a true peak's amplitude (same unit).
    alpha : float
        Rate of the false peaks' exponential amplitude density (1 / amplitude unit).
    threshold : float
        Amplitude threshold tau.

    Returns
    -------
    ndarray, shape (n_tracks, n_meas)
        log r_tj.
    """
    z = np.asarray(amplitudes, dtype=float)[None, :]
    mu = np.asarray(strength, dtype=float)[:, None]
    s = np.asarray(sigma_a, dtype=float)[:, None]
    log_true = -0.5 * ((z - mu) / s) ** 2 - np.log(np.sqrt(2 * np.pi) * s)
    log_false = np.log(alpha) - alpha * (z - threshold)
    return log_true - log_false


def update_strength(strength, gated_amplitudes_max):
    """Track strength update, paper P0 eq. 9: ``z_hat(k) = 0.7 z_hat(k-1) + 0.3 max_j z(k, j)``.

    Parameters
    ----------
    strength : array_like, shape (n,)
        Strengths z_hat(k-1) (correlator output unit).
    gated_amplitudes_max : array_like, shape (n,)
        Largest amplitude in each track's gate at k; NaN or inf for an empty gate.

    Returns
    -------
    ndarray, shape (n,)
        Updated strengths; tracks with an empty gate keep theirs.
    """
    s = np.asarray(strength, dtype=float)
    mx = np.asarray(gated_amplitudes_max, dtype=float)
    return np.where(np.isfinite(mx), STRENGTH_MEMORY * s + (1 - STRENGTH_MEMORY) * mx, s)
