"""IPDA track existence: Markov-chain prediction and Bayesian update.

Musicki, Evans, Stankovic 1994, "Integrated probabilistic data association", IEEE TAC 39(6),
eqs. 11 and 29; Park, Song, Lee 2017, eqs. 12 and 21.

    prediction:  P(E)k|k-1 = p11 P(E)k-1 + p21 (1 - P(E)k-1)
    update:      delta_k = P_D P_G - P_D sum_i p_i / rho_i     (= 1 - Lambda, see association/pda.py)
                 P(E)k = (1 - delta_k) P(E)k|k-1 / (1 - delta_k P(E)k|k-1)

With no validated measurement, delta = P_D P_G and P(E)k = (1 - P_D P_G) P / (1 - P_D P_G P).
For IMM-IPDA, 1 - delta = sum_r c_r Lambda_r (predicted mode probabilities c_r).
"""

from __future__ import annotations

import numpy as np


def existence_predict(p_exist, p11: float, p21: float = 0.0):
    """Markov-chain prediction of the existence probability (Musicki et al. 1994, eq. 11).

    ``P(E)k|k-1 = p11 P(E)k-1 + p21 (1 - P(E)k-1)``.

    Parameters
    ----------
    p_exist : float or array_like
        Existence probability at k-1.
    p11 : float
        Probability that an existing target still exists one scan later.
    p21 : float, default 0.0
        Probability that a non-existing target appears.

    Returns
    -------
    ndarray
        Predicted existence probability, same shape as ``p_exist``.
    """
    p = np.asarray(p_exist, float)
    return p11 * p + p21 * (1.0 - p)


def existence_update(p_exist_pred, lam):
    """Posterior existence probability (Musicki et al. 1994, eq. 29; Park, Song, Lee 2017, eq. 21).

    Written as ``Lambda P / (1 - P + Lambda P)``, which equals ``(1 - delta) P / (1 - delta P)``
    and stays in [0, 1] for any Lambda >= 0. The one undefined case, P = 1 with Lambda = 0 (a certain
    target that the scan says cannot be there: P_D P_G = 1 and nothing in the gate), is 0/0; we keep
    P = 1, the prior's certainty.

    Parameters
    ----------
    p_exist_pred : float or array_like
        Predicted existence probability P.
    lam : float or array_like
        ``Lambda = 1 - delta = 1 - P_D P_G + P_D sum_i p_i / rho_i`` (for IMM-IPDA, sum_r c_r Lambda_r).

    Returns
    -------
    ndarray
        Posterior existence probability, broadcast shape of the inputs.
    """
    p = np.asarray(p_exist_pred, float)
    lam = np.asarray(lam, float)
    den = 1.0 - p + lam * p
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0.0, lam * p / np.where(den > 0.0, den, 1.0), p)
