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


def confirm_threshold_for_rate(false_tracks_per_scan, tracks_started_per_scan, initial_existence):
    """Existence threshold whose false confirmed tracks stay below a stated rate (Ville's inequality on IPDA's odds).

    IPDA's existence is a posterior (Musicki, Evans, Stankovic 1994, eq. 29): with p11 = 1 and p21 = 0 its odds
    after k scans are O_k = O_0 prod_j Lambda_j, and prod_j Lambda_j = p(Z^k | E) / p(Z^k | not E) is the
    likelihood ratio of the track's measurements, a non-negative martingale of mean 1 on a track with no target
    when the clutter model is right. Ville's inequality bounds the chance that it ever reaches a level a:
    P(sup_k prod Lambda >= a) <= 1 / a. So a track started on clutter ever reaches the odds O_c with probability
    at most O_0 / O_c; p11 < 1 only lowers the odds (the prediction shrinks P(E) and the update is increasing in
    it). With n tracks started per scan, false confirmed tracks per scan are at most n O_0 / O_c; a stated rate f
    is kept by

        O_c = n O_0 / f,     threshold = O_c / (1 + O_c)

    (Musicki & Evans 2004 discriminate false tracks by this existence probability; they set the threshold by
    simulation, this sets it from the rate). The bound assumes the tracker's clutter density and detection model:
    where the clutter is denser or correlated across scans (streaks of MFTD false detections), the measured rate
    can exceed it (tests/tracking/test_confirm_rate.py measures it on the model; the benchmarks on other worlds).

    Parameters
    ----------
    false_tracks_per_scan : float
        The stated rate f of false confirmed tracks per scan (> 0).
    tracks_started_per_scan : float or ndarray
        Tracks started per scan n (measured: the initiator's running mean).
    initial_existence : float
        Existence P_0 of a new track (its odds O_0 = P_0 / (1 - P_0)).

    Returns
    -------
    float or ndarray
        The confirmation threshold on the existence probability, at least ``initial_existence``.
    """
    odds_0 = initial_existence / (1.0 - initial_existence)
    odds_c = np.maximum(np.asarray(tracks_started_per_scan, float) * odds_0 / false_tracks_per_scan, odds_0)
    return odds_c / (1.0 + odds_c)
