"""Frame normalisation: put a user's cell values on the noise model's scale (paper P1, eq. 8).

The detector's design SNR and its log-likelihood weights assume noise-only cells exponential with
mean 2 (eq. 8), whose median is 2 ln 2. A receiver's gain is arbitrary, so by default the frames are
scaled so that their median is 2 ln 2: the median is robust to a target occupying a few cells, and
after it the design SNR means what it says whatever the gain.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require
from sonartrack.models.swerling import NOISE_MEAN

#: the ways frames can be normalised: by their median, or left as given
NORMALISATIONS = ("median", "none")
#: median of a noise-only square-law cell, exponential with mean 2 (eq. 8): 2 ln 2
NOISE_MEDIAN = NOISE_MEAN * np.log(2.0)


def normalise_to_noise_median(frames) -> np.ndarray:
    """Scale frames so that their median is a noise cell's: ``y * (2 ln 2 / median(y))`` (paper P1, eq. 8).

    Parameters
    ----------
    frames : array_like
        Square-law cell values (any gain).

    Returns
    -------
    ndarray
        Scaled values, on the noise model's scale (noise mean 2).

    Raises
    ------
    InputError
        If the median is 0.
    """
    y = np.asarray(frames, dtype=float)
    med = float(np.median(y))
    require(med > 0, "the median cell value is 0: cannot normalise by it; set normalisation = 'none' and give "
                     "frames on the noise model's scale (noise mean 2)")
    return y * (NOISE_MEAN * np.log(2.0) / med)


def normalise_frames(frames, how: str = "median") -> np.ndarray:
    """Frames normalised ``how``: "median" (:func:`normalise_to_noise_median`) or "none" (as given).

    Parameters
    ----------
    frames : array_like
        Square-law cell values.
    how : {"median", "none"}, default "median"
        Normalisation.

    Returns
    -------
    ndarray of float
        The normalised frames.

    Raises
    ------
    InputError
        If ``how`` is unknown (or as :func:`normalise_to_noise_median`).
    """
    require(how in NORMALISATIONS, f"normalisation must be one of {NORMALISATIONS}, got '{how}'")
    return normalise_to_noise_median(frames) if how == "median" else np.asarray(frames, dtype=float)


#: the false-alarm level at which the K shape of a ping's statistic is measured (:func:`k_shape_from_exceedance`):
#: common enough that 1e5 cells give +-3 % on it, deep enough to see the tail
SHAPE_PFA = 1e-2


def k_shape_from_exceedance(statistic, n: int, k: int, pfa0: float = SHAPE_PFA) -> float:
    """The K shape nu whose OS-CFAR law gives the observed exceedance of the threshold for ``pfa0`` in exponential
    noise: solve P_K(s >= alpha_0; nu) = (share of cells with s >= alpha_0), alpha_0 = os_threshold(pfa0, N, k)
    (detection/cfar.py :func:`k_os_pfa`; infinity, i.e. exponential, when the share is no larger than pfa0).

    A moment estimate of nu (Watts 1987: <x^2> / <x>^2 = 2 (1 + 1 / nu)) is swayed by the few largest cells; this one
    fits the tail where the detector works, on the statistic the detector thresholds (its CFAR's own estimate
    included), and a few target cells among 1e5 barely move it.

    Parameters
    ----------
    statistic : array_like
        OS-normalised cells s (cells <= 0, blanked, are left out).
    n, k : int
        The CFAR's reference cells N and rank k.
    pfa0 : float
        The level of the fit.

    Returns
    -------
    float
        nu in 0.1 .. 100, or inf.
    """
    from sonartrack.detection.cfar import K_SHAPES, k_os_log_pfa, os_threshold

    s = np.asarray(statistic)
    s = s[s > 0]
    if s.size < 100 / pfa0:
        return float("inf")
    alpha0 = os_threshold(pfa0, n, k)
    share = float(np.mean(s >= alpha0))
    if share <= pfa0:
        return float("inf")
    log_p = np.array([float(k_os_log_pfa(alpha0, v, n, k)) for v in K_SHAPES])  # falls as nu grows
    if np.log(share) >= log_p[0]:
        return K_SHAPES[0]
    return float(np.exp(np.interp(-np.log(share), -log_p, np.log(K_SHAPES))))


def k_to_exponential(statistic, nu: float, n: int, k: int) -> np.ndarray:
    """The statistic mapped so that in K clutter of shape nu it has the law it has in exponential noise:
    s' = a_exp(P_K(s; nu)), with P_K the OS-CFAR exceedance in K clutter (detection/cfar.py :func:`k_os_pfa`) and
    a_exp its inverse in exponential noise (Rohling's closed form), so that every threshold set for exponential
    noise (the single-ping closed form, the MFTD's calibration on noise) keeps its false-alarm rate in the clutter.
    Monotone: the order of the cells is kept; identity for nu = inf.

    Parameters
    ----------
    statistic : array_like
        OS-normalised cells s >= 0.
    nu : float
        K shape (inf: none).
    n, k : int
        The CFAR's reference cells N and rank k.

    Returns
    -------
    numpy.ndarray
        s' (float32), same shape.
    """
    from sonartrack.detection.cfar import k_os_log_pfa, os_pfa

    s = np.asarray(statistic, np.float32)
    if not np.isfinite(nu):
        return s
    grid = np.exp(np.linspace(np.log(0.5), np.log(1e5), 600))
    log_pk = k_os_log_pfa(grid, nu, n, k)  # ln P_K(s >= grid), falling
    log_pe = np.log(np.maximum(os_pfa(grid, n, k), 1e-300))  # ln P_exp(s >= grid), falling
    mapped = np.interp(-log_pk, -log_pe, grid)  # the exponential threshold of the same exceedance
    out = np.interp(np.log(np.maximum(s, 1e-30)), np.log(grid), np.log(mapped))
    return np.where(s > grid[0], np.exp(out) * 1.0, s * mapped[0] / grid[0]).astype(np.float32)
