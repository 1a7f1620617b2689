"""Swerling-1 target, square-law detector: cell statistics and the closed-form reference ROCs.

Im & Kim 1996 (paper P1), eqs. 7, 8 and 10. A cell's square-law output y (noise power 1 per
quadrature, so the noise mean is 2) is exponential:

    h0(y) = exp(-y / 2) / 2                          (noise only, eq. 8)
    h1(y) = exp(-y / (2 (1 + rho))) / (2 (1 + rho))  (Swerling-1 target at SNR rho, eq. 7)

so the log likelihood ratio of one cell is  a y - log(1 + rho)  with  a = rho / (2 (1 + rho)),
and that of a track through K cells is (eq. 10)

    log LR_theta = a * sum_k y_{k, theta_k} - K log(1 + rho).

Reference detectors (closed form, used as bounds in the mftd study):

* single cell, single frame (the target cell known): threshold y > t gives Pfa = exp(-t/2),
  Pd = exp(-t / (2 (1 + rho))) = Pfa ** (1 / (1 + rho)).
* clairvoyant known track over K frames: s = sum of the K cells on the true track is
  2 * Gamma(K, 1) under H0 and 2 (1 + rho) * Gamma(K, 1) under H1, so
  Pfa = Q(K, t/2) and Pd = Q(K, t / (2 (1 + rho))), with Q the regularised upper incomplete gamma
  function. It knows the track, so it bounds every detector that does not.
"""

from __future__ import annotations

import numpy as np

#: mean of a noise-only square-law cell in the paper's units (eq. 8)
NOISE_MEAN = 2.0


def db_to_ratio(snr_db):
    """Power ratio from decibels: ``10 ** (dB / 10)``.

    Parameters
    ----------
    snr_db : float or array_like
        Power ratio (dB).

    Returns
    -------
    ndarray
        Linear power ratio.
    """
    return 10.0 ** (np.asarray(snr_db, dtype=float) / 10.0)


def log_h0(y):
    """Log-density of a noise-only square-law cell, ``log h0(y) = -y/2 - log 2`` (paper P1, eq. 8).

    Parameters
    ----------
    y : float or array_like
        Square-law cell values (noise power 1 per quadrature: noise mean 2).

    Returns
    -------
    ndarray
        log h0(y).
    """
    y = np.asarray(y, dtype=float)
    return -0.5 * y - np.log(2.0)


def log_h1(y, snr):
    """Log-density of a Swerling-1 target cell, ``log h1(y) = -y / (2 (1 + rho)) - log(2 (1 + rho))`` (paper P1, eq. 7).

    Parameters
    ----------
    y : float or array_like
        Square-law cell values (noise mean 2).
    snr : float
        Target SNR rho (linear power ratio, not dB).

    Returns
    -------
    ndarray
        log h1(y).
    """
    y = np.asarray(y, dtype=float)
    s = 2.0 * (1.0 + float(snr))
    return -y / s - np.log(s)


def cell_llr_slope(snr) -> float:
    """Weight ``a = rho / (2 (1 + rho))`` of a cell value in the log likelihood ratio (paper P1, eq. 10).

    Parameters
    ----------
    snr : float
        Target SNR rho (linear).

    Returns
    -------
    float
        a (per unit of cell value).
    """
    snr = float(snr)
    return snr / (2.0 * (1.0 + snr))


def track_log_lr(y_sum, snr, n_frames: int):
    """Log likelihood ratio of a track through K cells, ``a * sum y - K log(1 + rho)`` (paper P1, eq. 10).

    Parameters
    ----------
    y_sum : float or array_like
        Sum of the track's K cell values.
    snr : float
        Target SNR rho (linear).
    n_frames : int
        K, the number of frames (cells) on the track.

    Returns
    -------
    ndarray
        log LR.
    """
    return cell_llr_slope(snr) * np.asarray(y_sum, dtype=float) - n_frames * np.log1p(float(snr))


def sample_cells(rng: np.random.Generator, shape, snr=0.0) -> np.ndarray:
    """Draw square-law cell values: exponential with mean ``2 (1 + rho)`` (paper P1, eqs. 7, 8).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    shape : int or tuple of int
        Shape of the draw.
    snr : float, default 0.0
        Target SNR rho (linear); 0 gives noise cells.

    Returns
    -------
    ndarray
        Cell values of ``shape``.
    """
    return rng.exponential(NOISE_MEAN * (1.0 + float(snr)), size=shape)


def single_cell_pd(pfa, snr):
    """Swerling-1 single-cell, single-frame ROC: ``Pd = Pfa ** (1 / (1 + rho))`` (module docstring).

    Parameters
    ----------
    pfa : float or array_like
        False-alarm probability of the cell.
    snr : float
        Target SNR rho (linear).

    Returns
    -------
    ndarray
        Detection probability.
    """
    return np.asarray(pfa, dtype=float) ** (1.0 / (1.0 + float(snr)))


def clairvoyant_threshold(pfa, n_frames: int):
    """Threshold t on the known-track sum ``s = sum_k y_k`` with ``P(s > t | H0) = pfa``: ``t = 2 Q^-1(K, pfa)``.

    Parameters
    ----------
    pfa : float or array_like
        False-alarm probability.
    n_frames : int
        K, frames summed.

    Returns
    -------
    ndarray
        Threshold t (cell-value units; noise mean 2 per cell).
    """
    from scipy.special import gammainccinv

    return NOISE_MEAN * gammainccinv(int(n_frames), np.asarray(pfa, dtype=float))


def clairvoyant_pd(pfa, snr, n_frames: int):
    """Known-track K-frame ROC: ``Pd = Q(K, t / (2 (1 + rho)))``, t = :func:`clairvoyant_threshold` (module docstring).

    Parameters
    ----------
    pfa : float or array_like
        False-alarm probability.
    snr : float
        Target SNR rho per cell (linear).
    n_frames : int
        K, frames summed.

    Returns
    -------
    ndarray
        Detection probability: an upper bound for any detector that does not know the track.
    """
    from scipy.special import gammaincc

    t = clairvoyant_threshold(pfa, n_frames)
    return gammaincc(int(n_frames), t / (NOISE_MEAN * (1.0 + float(snr))))


def single_frame_plane_pd(pfa, snr, n_cells: int):
    """Conventional single-frame detector over a plane of M cells (declare if any cell exceeds t).

    Per-cell false-alarm p from the system one, Pfa = 1 - (1 - p)^M; then a Swerling-1 target in
    one cell is detected if its cell or any of the M - 1 noise cells exceeds t:
    Pd = 1 - (1 - p^(1/(1+rho))) (1 - p)^(M-1). With M = 1 this is :func:`single_cell_pd`.

    Parameters
    ----------
    pfa : float or array_like
        System (whole-plane) false-alarm probability.
    snr : float
        Target SNR rho (linear).
    n_cells : int
        M, cells in the plane.

    Returns
    -------
    ndarray
        Detection probability.
    """
    pfa = np.asarray(pfa, dtype=float)
    M = int(n_cells)
    p = -np.expm1(np.log1p(-pfa) / M)
    return 1.0 - (1.0 - p ** (1.0 / (1.0 + float(snr)))) * (1.0 - p) ** (M - 1)
