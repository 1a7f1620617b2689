"""Probabilistic data association (PDA) and its IPDA / IMM-IPDA generalisation, on arrays.

One routine serves single-track PDA, IPDA and IMM-IPDA for a whole batch of tracks: tracks are axis
``n``, IMM modes axis ``r`` (r = 1 for a single model), measurements axis ``m``. Measurements may
have their own covariances R_m (bistatic points do), so each validated measurement has its own
Kalman gain; the PDA update is then the Gaussian-mixture reduction of the per-measurement
updates, which equals the textbook combined-innovation form when all R_m are equal.

Equations (parametric PDA, Bar-Shalom & Tse 1975; Bar-Shalom, Daum, Huang 2009, eqs. 36-41;
IPDA: Musicki, Evans, Stankovic 1994, eqs. 22-30; IMM-IPDA: Musicki, Suvorova, Challa 2004;
Park, Song, Lee 2017, eqs. 13-21). For track n, mode r, validated measurement m:

    nu      = z_m - H x-_r,   S = H P-_r H^T + R_m,   p_rm = N(nu; 0, S)      (likelihood)
    Lambda_r = 1 - P_D P_G + P_D sum_m p_rm / rho_m                          (mode likelihood ratio)
    beta_r0 = (1 - P_D P_G) / Lambda_r,   beta_rm = P_D (p_rm / rho_m) / Lambda_r   (sum to 1)
    K_rm = P-_r H^T S^-1,   x_rm = x-_r + K_rm nu,   P_rm = P-_r - K_rm S K_rm^T
    x_r = sum_m beta_rm x_rm (m = 0: x-_r),  P_r = sum_m beta_rm (P_rm + (x_rm - x_r)(x_rm - x_r)^T)

rho_m is the clutter density at measurement m. For IPDA, delta = 1 - sum_r c_r Lambda_r and the
existence update is P(E)+ = (1 - delta) P(E)- / (1 - delta P(E)-) (association/ipda.py).
Plain PDA's weights are the same beta (its normalisation is the same expression).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.gaussian import LOG_2PI, inv_and_logdet
from sonartrack.core.linalg import symmetrize


@dataclass(frozen=True, slots=True)
class PdaResult:
    """Output of :func:`pda_update_batch` (shapes: n tracks, r modes, m measurements)."""

    x: np.ndarray  # (n, r, d) updated mode-conditioned states
    P: np.ndarray  # (n, r, d, d)
    log_lambda: np.ndarray  # (n, r) log Lambda_r, the mode likelihood ratio
    gated: np.ndarray  # (n, m) bool: measurement m validated by track n (union over modes)
    beta0: np.ndarray  # (n, r) weight of "no measurement is the target's"
    beta: np.ndarray  # (n, r, m) association weights (zero outside the gate)


def pda_update_batch(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density):
    """PDA/IPDA/IMM-IPDA measurement update of n tracks x r modes with m position measurements.

    ``x_pred (n, r, d)``, ``P_pred (n, r, d, d)`` with position in the first two state entries;
    ``z (m, 2)``; ``R (m, 2, 2)`` or ``(2, 2)``; ``clutter_density`` scalar or ``(m,)`` (per m^2).
    A measurement is validated for a track when it falls in the gate of any of its modes.
    """
    x_pred = np.asarray(x_pred, float)
    P_pred = np.asarray(P_pred, float)
    n, r, d = x_pred.shape
    z = np.asarray(z, float).reshape(-1, 2)
    m = len(z)
    R = np.broadcast_to(np.asarray(R, float), (m, 2, 2))
    rho = np.broadcast_to(np.asarray(clutter_density, float), (m,))
    miss = 1.0 - pd * pg
    if m == 0 or n == 0:
        lam = np.full((n, r), miss)
        return PdaResult(x_pred.copy(), P_pred.copy(), np.log(lam), np.zeros((n, m), bool),
                         np.ones((n, r)), np.zeros((n, r, m)))

    S = P_pred[:, :, None, :2, :2] + R[None, None]  # (n, r, m, 2, 2)
    S_inv, logdet = inv_and_logdet(S)
    nu = z[None, None] - x_pred[:, :, None, :2]  # (n, r, m, 2)
    d2 = np.einsum("...i,...ij,...j->...", nu, S_inv, nu)
    gated = (d2 < gamma).any(axis=1)  # (n, m)
    # p_rm / rho_m in log space, then linear: ratios near 1 are the interesting range
    log_ratio = -0.5 * (2 * LOG_2PI + logdet + d2) - np.log(rho)
    ratio = np.where(gated[:, None, :], np.exp(np.minimum(log_ratio, 700.0)), 0.0)
    lam = miss + pd * ratio.sum(axis=-1)  # (n, r)
    beta = pd * ratio / lam[..., None]
    beta0 = miss / lam

    x_upd = x_pred.copy()
    P_upd = beta0[..., None, None] * P_pred
    ti, mi = np.nonzero(gated)
    if len(ti):
        Pg = P_pred[ti]  # (G, r, d, d)
        PHt = Pg[..., :, :2]  # P H^T for H = [I 0]
        K = PHt @ S_inv[ti, :, mi]  # (G, r, d, 2)
        dx = np.einsum("grij,grj->gri", K, nu[ti, :, mi])  # (G, r, d)
        b = beta[ti, :, mi]  # (G, r)
        # P_rm + dx dx^T  with  P_rm = P - K S K^T = P - K H P  (optimal gain)
        term = Pg - K @ np.swapaxes(PHt, -1, -2) + dx[..., :, None] * dx[..., None, :]
        acc_x = np.zeros((n, r, d))
        acc_P = np.zeros((n, r, d, d))
        np.add.at(acc_x, ti, b[..., None] * dx)
        np.add.at(acc_P, ti, b[..., None, None] * term)
        x_upd = x_pred + acc_x
        P_upd = P_upd + acc_P - acc_x[..., :, None] * acc_x[..., None, :]
    return PdaResult(x_upd, symmetrize(P_upd), np.log(lam), gated, beta0, beta)


def pda_update(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density):
    """Single-track, single-model PDA update: returns ``(x, P, beta0, beta)``.

    ``x_pred (d,)``, ``P_pred (d, d)``, ``z (m, 2)``, ``R (2, 2)`` or ``(m, 2, 2)``.
    ``beta`` has one entry per measurement (zero outside the gate).
    """
    res = pda_update_batch(np.asarray(x_pred, float)[None, None], np.asarray(P_pred, float)[None, None], z, R,
                           pd=pd, pg=pg, gamma=gamma, clutter_density=clutter_density)
    return res.x[0, 0], res.P[0, 0], float(res.beta0[0, 0]), res.beta[0, 0]
