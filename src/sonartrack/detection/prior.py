"""The Kalman-predictor track prior of MFTD (Im & Kim 1996, paper P1, eqs. 16-19 and 21).

A track theta = (theta_1 .. theta_K) picks one cell per frame; its prior comes from a Kalman
predictor driven by the cell centres v (the covariances do not depend on the track):

    w_k = Phi { w_{k-1} + B_{k-1} (B_{k-1} + R)^-1 (v_{theta_{k-1}} - w_{k-1}) } + u_{k-1}   (eq. 16)
    B_k = Phi { I - B_{k-1} (B_{k-1} + R)^-1 } B_{k-1} Phi^T + Q                             (eq. 17)
    c_theta = c A^K prod_k N(v_{theta_k}; w_k, B_k)                                          (eq. 19)

"w_1 arbitrary, B_1 large": by default we take the limit B_1 -> infinity, in which the first update
returns the cell centre with covariance R, so w_2 = Phi v_{theta_1} + u_1 and B_2 = Phi R Phi^T + Q,
and the first frame's prior is flat; we set it to 1/M (a uniform first cell), which fixes c so that
the c_theta sum to about 1. Passing ``b1`` and ``w1`` runs the literal recursion instead.

``prior_density``: "centre" evaluates N(v; w_k, B_k) at the cell centre (eq. 19 as printed);
"smoothed" uses N(v; w_k, B_k + R), the cell average of the density to second order (see the module
doc of ``detection/mftd.py`` for why).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.gaussian import LOG_2PI, inv_and_logdet
from sonartrack.models.range_doppler import (
    RangeDopplerGrid,
    ar_input_gain,
    ar_process_noise,
    ar_transition,
    own_accel_array,
)

PRIOR_DENSITIES = ("centre", "smoothed")


@dataclass(frozen=True, slots=True)
class KalmanPrior:
    """The track-independent part of the Kalman-predictor prior for K frames (eqs. 16, 17, 19).

    For frame k (0-based): ``B[k]`` prediction covariance (NaN for k = 0 in the B_1 -> infinity
    limit), ``S_inv[k]`` / ``log_norm[k]`` the inverse covariance and log normaliser of the density
    used in eq. 19 (``log_norm[0] = -log M`` in the limit), and the predictor step
    ``w_{k+1} = F[k] w_k + L[k] v_{theta_k} + u[k]`` with ``F = Phi (I - G)``, ``L = Phi G``,
    ``G = B (B + R)^-1``; ``w1`` is the prediction for frame 0. ``S_cov[k]`` is ``S_inv[k]^-1``
    (zeros where ``S_inv[k]`` is: the flat first frame), which bounds the restricted branching.
    """

    B: np.ndarray
    S_inv: np.ndarray
    S_cov: np.ndarray
    log_norm: np.ndarray
    F: np.ndarray
    L: np.ndarray
    u: np.ndarray
    w1: np.ndarray

    @property
    def n_frames(self) -> int:
        """K, the number of frames the prior is for."""
        return len(self.log_norm)


def _check_prior_args(period_s: float, sigma_a_mps2: float, n_frames: int, prior_density: str) -> None:
    require(n_frames >= 1, f"K (frames) must be at least 1, got {n_frames}")
    require(prior_density in PRIOR_DENSITIES, f"prior_density must be one of {PRIOR_DENSITIES}, got '{prior_density}'")
    require(period_s > 0, f"frame period must be positive, got {period_s}")
    require(sigma_a_mps2 >= 0, f"sigma_a must be non-negative, got {sigma_a_mps2}")


def _density(B: np.ndarray, R: np.ndarray, log_area: float, smooth: bool) -> tuple[np.ndarray, float]:
    """Inverse covariance S^-1 and log A N-normaliser of eq. 19's density: S = B (printed) or B + R (smoothed).

    log_norm = log A - log 2 pi - log|S| / 2 (the 2-D normaliser; the paper prints |B_k| without the root).
    """
    inv, logdet = inv_and_logdet(B + R if smooth else B)
    return inv, log_area - LOG_2PI - 0.5 * logdet


def _predictor_step(B: np.ndarray, R: np.ndarray, Phi: np.ndarray):
    """Gains of eq. 16, F = Phi (I - G) and L = Phi G with G = B (B + R)^-1, and the updated
    covariance P = (I - G) B of eq. 17 (before Phi . Phi^T + Q), symmetrised."""
    I2 = np.eye(2)
    G = B @ np.linalg.inv(B + R)
    P = (I2 - G) @ B
    return Phi @ (I2 - G), Phi @ G, 0.5 * (P + P.T)


def _inverse_where_set(S_inv: np.ndarray) -> np.ndarray:
    """S_inv[k]^-1 for every frame whose S_inv is not all zero; zeros elsewhere."""
    S_cov = np.zeros_like(S_inv)
    for k in range(len(S_inv)):
        if np.any(S_inv[k]):
            S_cov[k] = np.linalg.inv(S_inv[k])
    return S_cov


def kalman_prior(grid: RangeDopplerGrid, period_s: float, sigma_a_mps2: float, n_frames: int,
                 own_accel_mps2=None, prior_density: str = "centre", b1=None, w1=None) -> KalmanPrior:
    """Covariances and predictor gains of paper P1's eqs. 16-17 (and eq. 19's density) for ``n_frames`` frames.

    Parameters
    ----------
    grid : RangeDopplerGrid
        The plane (cell area A and quantisation covariance R).
    period_s : float
        Frame period T (s), > 0.
    sigma_a_mps2 : float
        Standard deviation of the target's range acceleration (m/s^2), >= 0.
    n_frames : int
        K, >= 1.
    own_accel_mps2 : float or sequence of float, optional
        Known inputs u_1..u_{K-1} (m/s^2), entering as g u_k with g = [T^2/2, T] (eq. 23).
    prior_density : {"centre", "smoothed"}, default "centre"
        N(v; w_k, B_k) at the cell centre (eq. 19 as printed), or N(v; w_k, B_k + R).
    b1 : array_like, shape (2, 2), optional
        A finite B_1 (m^2, m^2/s, m^2/s^2), run with the literal eqs. 16-19; None: the B_1 -> infinity
        limit with a uniform first cell.
    w1 : array_like, shape (2,), optional
        w_1 = [range (m), range-rate (m/s)] that goes with ``b1``; default zeros.

    Returns
    -------
    KalmanPrior
        Per-frame covariances, density inverses and log normalisers, and predictor gains.

    Raises
    ------
    InputError
        If an argument is out of range.
    """
    _check_prior_args(period_s, sigma_a_mps2, n_frames, prior_density)
    K = int(n_frames)
    Phi, Q, R = ar_transition(period_s), ar_process_noise(period_s, sigma_a_mps2), grid.R
    u = np.zeros((K, 2))
    u[: K - 1] = np.outer(own_accel_array(own_accel_mps2, K), ar_input_gain(period_s))
    B = np.full((K, 2, 2), np.nan)
    S_inv, log_norm = np.zeros((K, 2, 2)), np.zeros(K)
    F, L = np.zeros((K, 2, 2)), np.zeros((K, 2, 2))
    w_first = np.zeros(2) if w1 is None else np.asarray(w1, dtype=float)
    if b1 is None:  # B_1 -> infinity: a uniform first cell, and lim (I - B_1 (B_1 + R)^-1) B_1 = R
        log_norm[0], P, first = -np.log(grid.n_cells), R, 1
        F[0], L[0] = 0.0, Phi
    else:
        B[0], P, first = np.asarray(b1, dtype=float), None, 0
    log_area = np.log(grid.cell_area)
    for k in range(first, K):
        if k > 0:
            B[k] = Phi @ P @ Phi.T + Q  # eq. 17
        S_inv[k], log_norm[k] = _density(B[k], R, log_area, prior_density == "smoothed")
        F[k], L[k], P = _predictor_step(B[k], R, Phi)
    return KalmanPrior(B, S_inv, _inverse_where_set(S_inv), log_norm, F, L, u, w_first)


@functools.lru_cache(maxsize=64)
def cached_prior(grid: RangeDopplerGrid, period_s: float, sigma_a_mps2: float, n_frames: int,
                 prior_density: str = "centre") -> KalmanPrior:
    """:func:`kalman_prior` without own-sensor input, memoised (Monte Carlo trials reuse it).

    Parameters
    ----------
    grid : RangeDopplerGrid
        The plane (hashable: a frozen dataclass).
    period_s : float
        Frame period (s).
    sigma_a_mps2 : float
        Range acceleration standard deviation (m/s^2).
    n_frames : int
        K.
    prior_density : {"centre", "smoothed"}, default "centre"
        Density of eq. 19.

    Returns
    -------
    KalmanPrior
        The (shared, read-only) prior.
    """
    return kalman_prior(grid, period_s, sigma_a_mps2, n_frames, None, prior_density)


def prior_constant(prior: KalmanPrior, snr: float) -> float:
    """The track-independent part of paper P1's eq. 21 log weight.

        const = -K log(1 + rho) + sum_k log_norm[k]
              = -K log(1 + rho) - log M + sum_{k>=2} [ log A - log 2 pi - log|B_k| / 2 ],

    so that ``log c_theta LR_theta = J_theta / 2 + const``.

    Parameters
    ----------
    prior : KalmanPrior
        The prior.
    snr : float
        Design SNR rho (linear).

    Returns
    -------
    float
        const (natural log).
    """
    return float(np.sum(prior.log_norm) - prior.n_frames * np.log1p(snr))
