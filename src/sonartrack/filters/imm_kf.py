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
    """One IMM-KF cycle. Returns ``(x_r, P_r, mu, x_comb, P_comb)``.

    x (r, n), P (r, n, n), mu (r,) -- mode-conditioned estimates and mode probabilities at k-1;
    z (m,), F (r, n, n) or (n, n), Q (r, n, n), H (m, n), R (m, m), Pi (r, r) with
    Pi[i, j] = P(mode j at k | mode i at k-1).
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
