"""Existence part of a tracker: IPDA's Markov chain on the probability that a track's target exists.

    prediction  P(E)- = p11 P(E) + p21 (1 - P(E))
    update      P(E)+ = Lambda P(E)- / (1 - P(E)- + Lambda P(E)-),   Lambda = sum_r c_r Lambda_r = 1 - delta

(Musicki, Evans, Stankovic 1994, eqs. 11 and 29; IMM-IPDA: Lambda from the mode update; Park, Song,
Lee 2017, eqs. 12 and 21; association/ipda.py.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.association.ipda import existence_predict, existence_update


@dataclass(frozen=True)
class IpdaExistence:
    """Existence Markov chain: survival ``p_survive`` (p11), birth ``p_birth`` (p21)."""

    p_survive: float
    p_birth: float

    def predict(self, existence):
        """Existence prediction ``P(E)- = p11 P(E) + p21 (1 - P(E))`` (Musicki et al. 1994, eq. 11).

        Parameters
        ----------
        existence : ndarray, shape (n,)
            Existence probabilities at the previous scan.

        Returns
        -------
        ndarray, shape (n,)
            Predicted existence probabilities.
        """
        return existence_predict(existence, self.p_survive, self.p_birth)

    def update(self, existence_pred, log_lambda_total):
        """Posterior existence from the prediction and ``log Lambda`` (Musicki et al. 1994, eq. 29; module docstring).

        Parameters
        ----------
        existence_pred : ndarray, shape (n,)
            Predicted existence probabilities.
        log_lambda_total : ndarray, shape (n,)
            ``log sum_r c_r Lambda_r`` per track (from the mode update).

        Returns
        -------
        ndarray, shape (n,)
            Posterior existence probabilities.
        """
        return existence_update(existence_pred, np.exp(log_lambda_total))
