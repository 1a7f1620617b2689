"""Probabilistic data association (PDA) and its IPDA / IMM-IPDA generalisation, on arrays.

Tracks are axis ``n``, IMM modes axis ``r`` (r = 1 for a single model), measurements axis ``m``.
Measurements may have their own covariances R_m (bistatic points do), so each validated measurement
has its own Kalman gain; the PDA update is then the Gaussian-mixture reduction of the per-measurement
updates, which equals the textbook combined-innovation form when all R_m are equal.

Equations (parametric PDA, Bar-Shalom & Tse 1975; Bar-Shalom, Daum, Huang 2009, eqs. 36-41;
IPDA: Musicki, Evans, Stankovic 1994, eqs. 22-30; IMM-IPDA: Musicki, Suvorova, Challa 2004;
Park, Song, Lee 2017, eqs. 13-21). For track n, mode r, validated measurement m (likelihoods in
association/likelihood.py):

    Lambda_r = 1 - P_D P_G + P_D sum_m p_rm / rho_m                          (mode likelihood ratio)
    beta_r0 = (1 - P_D P_G) / Lambda_r,   beta_rm = P_D (p_rm / rho_m) / Lambda_r   (sum to 1)
    K_rm = P-_r H^T S^-1,   x_rm = x-_r + K_rm nu,   P_rm = P-_r - K_rm S K_rm^T
    x_r = sum_m beta_rm x_rm (m = 0: x-_r),  P_r = sum_m beta_rm (P_rm + (x_rm - x_r)(x_rm - x_r)^T)

The weights are :func:`pda_weights` (dense, (n, r, m)) or :func:`pda_pair_weights` (the same numbers at the
gated pairs only, what the tracker uses), the update :func:`pda_mixture_update` (which also serves JPDA:
only its weights differ, association/jpda.py). For IPDA, delta = 1 - sum_r c_r Lambda_r and the
existence update is P(E)+ = (1 - delta) P(E)- / (1 - delta P(E)-) (association/ipda.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.association.likelihood import Likelihoods, position_likelihoods
from sonartrack.core.linalg import symmetrize


@dataclass(frozen=True, slots=True)
class AssociationWeights:
    """Association probabilities of n tracks x r modes over m measurements."""

    beta0: np.ndarray  # (n, r) weight of "no measurement is the target's"
    beta: np.ndarray | None  # (n, r, m) weight of measurement m (zero outside the gate); None: only beta_pair
    log_lambda: np.ndarray | None  # (n, r) log Lambda_r (PDA; None where an associator has no such ratio)
    beta_pair: np.ndarray | None = None  # (G, r) the weights of the gated pairs (Likelihoods.pair_track/pair_meas)

    def of_pairs(self, lik: Likelihoods) -> np.ndarray:
        """The weights of the gated pairs of ``lik``.

        Parameters
        ----------
        lik : Likelihoods
            The likelihoods the weights were computed from (their pair order).

        Returns
        -------
        ndarray, shape (G, r)
            ``beta_pair``, or ``beta`` read at the gated pairs.
        """
        return self.beta_pair if self.beta_pair is not None else self.beta[lik.pair_track, :, lik.pair_meas]


@dataclass(frozen=True, slots=True)
class PdaResult:
    """Output of :func:`pda_update_batch` (shapes: n tracks, r modes, m measurements)."""

    x: np.ndarray  # (n, r, d) updated mode-conditioned states
    P: np.ndarray  # (n, r, d, d)
    log_lambda: np.ndarray  # (n, r) log Lambda_r, the mode likelihood ratio
    gated: np.ndarray  # (n, m) bool: measurement m validated by track n (union over modes)
    beta0: np.ndarray  # (n, r) weight of "no measurement is the target's"
    beta: np.ndarray  # (n, r, m) association weights (zero outside the gate)


def pda_weights(lik: Likelihoods) -> AssociationWeights:
    """PDA weights beta_r0, beta_rm and Lambda_r of every track and mode, each track on its own (module docstring).

    ``Lambda_r = 1 - P_D P_G + P_D sum_m p_rm / rho_m``, ``beta_r0 = (1 - P_D P_G) / Lambda_r``,
    ``beta_rm = P_D (p_rm / rho_m) / Lambda_r`` (Bar-Shalom, Daum, Huang 2009, eqs. 36-41).

    Parameters
    ----------
    lik : Likelihoods
        Log likelihood ratios against clutter, gates, P_D and the miss weight 1 - P_D P_G.

    Returns
    -------
    AssociationWeights
        beta0 (n, r), dense beta (n, r, m) (zero outside the gate) and log Lambda_r (n, r).
    """
    # p_rm / rho_m in log space, then linear: ratios near 1 are the interesting range
    ratio = np.where(lik.gated[:, None, :], np.exp(np.minimum(lik.log_ratio, 700.0)), 0.0)
    pd = lik.pd if np.isscalar(lik.pd) else lik.pd[:, None]  # one value, or (n, 1)
    lam = lik.miss + pd * ratio.sum(axis=-1)  # (n, r)
    beta = (pd if np.isscalar(pd) else pd[..., None]) * ratio / lam[..., None]
    return AssociationWeights(lik.miss / lam, beta, np.log(lam))


def pda_pair_weights(lik: Likelihoods) -> AssociationWeights:
    """:func:`pda_weights` from the gated pairs alone: ``beta`` None, ``beta_pair (G, r)`` instead.

    The same numbers bit for bit (the sum over m is NumPy's dense row sum, association/pda_mixture_kernel.py),
    at a cost in the gated pairs G, not in n x r x m.

    Parameters
    ----------
    lik : Likelihoods
        Likelihoods of the scan.

    Returns
    -------
    AssociationWeights
        beta0 (n, r), beta_pair (G, r) and log Lambda_r (n, r).
    """
    from sonartrack.association.pda_mixture_kernel import dense_row_sums  # numba: loaded on first use

    n, r, m = lik.shape
    ratio = np.exp(np.minimum(lik.pair_log_ratio, 700.0))  # (G, r), as pda_weights
    # C-contiguous int64 pairs (some callers pass column views): one compiled specialisation, not one per layout
    pairs = (np.ascontiguousarray(lik.pair_track, dtype=np.int64), np.ascontiguousarray(lik.pair_meas, dtype=np.int64))
    ratio_sum = dense_row_sums(*pairs, np.ascontiguousarray(ratio), n, m)
    scalar_pd = np.isscalar(lik.pd)
    lam = lik.miss + (lik.pd if scalar_pd else lik.pd[:, None]) * ratio_sum  # (n, r)
    beta_pair = (lik.pd if scalar_pd else lik.pd[lik.pair_track, None]) * ratio / lam[lik.pair_track]
    return AssociationWeights(lik.miss / lam, None, np.log(lam), beta_pair)


def pda_mixture_update(x_pred, P_pred, lik: Likelihoods, beta0, beta, cross=None):
    """Gaussian-mixture reduction of the per-measurement Kalman updates with weights ``beta0``, ``beta``.

    x = x- + sum_m beta_m K_m nu_m;  P = beta_0 P- + sum_m beta_m (P- - K_m C_m^T + dx_m dx_m^T) - dx dx^T
    with C_m = P- H_m^T, K_m = C_m S_m^-1, dx_m = K_m nu_m and dx = sum_m beta_m dx_m (module doc), over the
    gated pairs (K_m C_m^T = K_m S_m K_m^T, the optimal gain's covariance reduction).

    Parameters
    ----------
    x_pred : ndarray, shape (n, r, d)
        Predicted mode-conditioned states of n tracks in r modes.
    P_pred : ndarray, shape (n, r, d, d)
        Their covariances.
    lik : Likelihoods
        The gated pairs' innovations nu and inverse innovation covariances S^-1 (association/likelihood.py).
    beta0 : ndarray, shape (n, r)
        Weight of "no measurement is the target's".
    beta : ndarray, shape (n, r, m)
        Weight of each measurement (zero outside the gate).
    cross : ndarray, shape (G, r, d, k), optional
        Cross-covariances C = P- H^T of the gated pairs, for a measurement model of its own per pair (a Stone
        Soup detection's, linearised for a nonlinear one). None: H = [I_k 0], the first k state entries measured.

    Returns
    -------
    x : ndarray, shape (n, r, d)
        Updated mode-conditioned states.
    P : ndarray, shape (n, r, d, d)
        Their covariances (symmetrised).
    """
    n, r, d = x_pred.shape
    k = lik.nu.shape[-1]
    if lik.gated.shape[1] == 0:
        return x_pred.copy(), P_pred.copy()
    P_upd = beta0[..., None, None] * P_pred
    ti, mi = lik.pair_track, lik.pair_meas
    if not len(ti):
        return x_pred.copy(), symmetrize(P_upd)
    Pg = P_pred[ti]  # (G, r, d, d)
    PHt = Pg[..., :, :k] if cross is None else cross  # P H^T (H = [I 0]: the first k columns of P)
    K = PHt @ lik.S_inv  # (G, r, d, k)
    dx = np.einsum("grij,grj->gri", K, lik.nu)  # (G, r, d)
    b = beta[ti, :, mi]  # (G, r)
    # P_rm + dx dx^T  with  P_rm = P - K S K^T = P - K C^T  (optimal gain)
    term = Pg - K @ np.swapaxes(PHt, -1, -2) + dx[..., :, None] * dx[..., None, :]
    acc_x = np.zeros((n, r, d))
    acc_P = np.zeros((n, r, d, d))
    np.add.at(acc_x, ti, b[..., None] * dx)
    np.add.at(acc_P, ti, b[..., None, None] * term)
    return x_pred + acc_x, symmetrize(P_upd + acc_P - acc_x[..., :, None] * acc_x[..., None, :])


def pda_update_batch(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density) -> PdaResult:
    """PDA / IPDA / IMM-IPDA measurement update of n tracks x r modes with m position measurements.

    A measurement is validated for a track when it falls in the gate of any of its modes (module docstring).

    Parameters
    ----------
    x_pred : array_like, shape (n, r, d)
        Predicted mode-conditioned states, position [x, y] (m) in the first two entries.
    P_pred : array_like, shape (n, r, d, d)
        Their covariances.
    z : array_like, shape (m, 2)
        Measured positions (m).
    R : array_like, shape (m, 2, 2) or (2, 2)
        Measurement covariances (m^2).
    pd, pg : float
        Detection probability P_D, and the gate probability P_G that goes with ``gamma``.
    gamma : float
        Chi-square gate size.
    clutter_density : float or array_like, shape (m,)
        Clutter density (per m^2).

    Returns
    -------
    PdaResult
        Updated states and covariances, log Lambda_r, gates and association weights.
    """
    x_pred = np.asarray(x_pred, float)
    P_pred = np.asarray(P_pred, float)
    lik = position_likelihoods(x_pred, P_pred, z, R, pd=pd, pg=pg, gamma=gamma, clutter_density=clutter_density)
    w = pda_weights(lik)
    x, P = pda_mixture_update(x_pred, P_pred, lik, w.beta0, w.beta)
    return PdaResult(x, P, w.log_lambda, lik.gated, w.beta0, w.beta)


def pda_update(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density):
    """Single-track, single-model PDA update (module docstring).

    Parameters
    ----------
    x_pred : array_like, shape (d,)
        Predicted state, position [x, y] (m) first.
    P_pred : array_like, shape (d, d)
        Its covariance.
    z, R, pd, pg, gamma, clutter_density
        Measured positions (m), their covariances (m^2; (2, 2) shared or (m, 2, 2)), P_D, P_G, the chi-square gate
        and the clutter density (per m^2): as :func:`pda_update_batch`.

    Returns
    -------
    x : ndarray, shape (d,)
        Updated state.
    P : ndarray, shape (d, d)
        Updated covariance.
    beta0 : float
        Weight of "no measurement is the target's".
    beta : ndarray, shape (m,)
        Weight of each measurement (zero outside the gate).
    """
    res = pda_update_batch(np.asarray(x_pred, float)[None, None], np.asarray(P_pred, float)[None, None], z, R,
                           pd=pd, pg=pg, gamma=gamma, clutter_density=clutter_density)
    return res.x[0, 0], res.P[0, 0], float(res.beta0[0, 0]), res.beta[0, 0]
