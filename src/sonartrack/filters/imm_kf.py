"""IMM with linear Kalman mode filters: one full IMM cycle on arrays.

The cycle (filters/imm.py for the shared pieces; Bar-Shalom, Li, Kirubarajan 2001, sec. 11.6.6):
mixing -> per-mode KF predict (F_r, Q_r) -> per-mode KF update (Joseph form, filters/kalman.py) ->
mode probabilities from the mode likelihoods N(nu_r; 0, S_r) -> combination.

Modes are a batch axis, so the cost is one set of NumPy calls whatever the number of modes.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.gaussian import LOG_2PI, inv_and_logdet
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update
from sonartrack.filters.kalman import joseph_update, kf_innovation


def imm_kf_step(x, P, mu, z, F, Q, H, R, Pi):
    """One IMM cycle with linear Kalman mode filters (mixing, KF predict/update per mode, mode update, combination).

    Parameters
    ----------
    x : ndarray, shape (r, n)
        Mode-conditioned states at k-1 (e.g. [x, y, vx, vy] in m and m/s).
    P : ndarray, shape (r, n, n)
        Their covariances.
    mu : ndarray, shape (r,)
        Mode probabilities at k-1.
    z : ndarray, shape (m,)
        Measurement at k.
    F : ndarray, shape (r, n, n) or (n, n)
        Per-mode (or shared) transition matrix over the step.
    Q : ndarray, shape (r, n, n)
        Per-mode process noise covariance over the step.
    H : ndarray, shape (m, n)
        Measurement matrix.
    R : ndarray, shape (m, m)
        Measurement noise covariance.
    Pi : ndarray, shape (r, r)
        Pi[i, j] = P(mode j at k | mode i at k-1).

    Returns
    -------
    x_r : ndarray, shape (r, n)
        Updated mode-conditioned states.
    P_r : ndarray, shape (r, n, n)
        Their covariances.
    mu : ndarray, shape (r,)
        Updated mode probabilities.
    x_comb : ndarray, shape (n,)
        Combined state.
    P_comb : ndarray, shape (n, n)
        Combined covariance.
    """
    c, w = imm_mixing(mu, Pi)
    x0, P0 = imm_mix(x, P, w)
    x_pred = np.einsum("...ij,...j->...i", F, x0)
    P_pred = F @ P0 @ np.swapaxes(F, -1, -2) + Q
    nu, S = kf_innovation(x_pred, P_pred, z, H, R)
    S_inv, logdet = inv_and_logdet(S)
    K = P_pred @ H.T @ S_inv
    x_upd, P_upd = joseph_update(x_pred, P_pred, nu, K, H, R)
    log_lik = -0.5 * (len(z) * LOG_2PI + logdet + np.einsum("ri,rij,rj->r", nu, S_inv, nu))
    mu_new, _ = imm_mode_update(c, log_lik)
    xc, Pc = imm_combine(mu_new, x_upd, P_upd)
    return x_upd, P_upd, mu_new, xc, Pc
