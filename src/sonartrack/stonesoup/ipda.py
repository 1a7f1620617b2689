"""IPDA and JIPDA for Stone Soup: data association with the probability that each track's target exists.

Hypothesiser (:class:`IPDAHypothesiser`, a ``PDAHypothesiser``): the track's existence P(E), kept in its
metadata (stonesoup/tracks.py), is predicted by the Markov chain of Musicki, Evans & Stankovic 1994
(IPDA, IEEE TAC 39(6), eq. 11)

    P(E)- = p11 P(E) + p21 (1 - P(E))

and the single-target weights are left unnormalised, w_t0 = 1 - P_D P_G, w_tj = P_D N(z_j; z_hat, S) / lambda.

:class:`IPDA` (each track on its own; Musicki et al. 1994, eqs. 22-30, association/ipda.py):

    Lambda = w_t0 + sum_j w_tj,   beta_tj = w_tj / Lambda,   P(E)+ = Lambda P(E)- / (1 - P(E)- + Lambda P(E)-)

:class:`JIPDA` (Musicki & Evans 2004, "Joint integrated probabilistic data association: JIPDA", IEEE
TAES 40(3), sec. III): a joint event chi gives each track at most one detection and each detection at
most one track; a track that takes detection j exists (P(E)- w_tj), a track that takes none either does
not exist or was missed (1 - P_D P_G P(E)-). With these weights

    w'_tj = P(E)-_t w_tj,   w'_t0 = 1 - P(E)-_t (1 - w_t0)                                  (joint events)
    beta'_tj = sum_{chi: chi(t) = j} prod_s w'_{s, chi(s)} / Z                          (exact JPDA marginals)
    P(E_t | Z) = sum_{j >= 1} beta'_tj + beta'_t0 P(E)-_t w_t0 / w'_t0                   (posterior existence)
    beta_tj = beta'_tj / P(E_t | Z),   beta_t0 = beta'_t0 P(E)-_t w_t0 / (w'_t0 P(E_t | Z))   (given existence)

the marginals beta' being computed by our exact JPDA (stonesoup/jpda.py). The weights beta_t. given
existence go to the state update (Stone Soup's ``PDAUpdater`` or a mixture reduction), as in IPDA. With
one track JIPDA is IPDA; with P(E)- = 1 for every track it is JPDA. Both associators return an
:class:`ExistenceMultipleHypothesis` per track and stage P(E | Z) on the track (stonesoup/tracks.py).
"""

from __future__ import annotations

import numpy as np
from stonesoup.base import Property
from stonesoup.dataassociator.base import DataAssociator
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability

from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.core.errors import InputError
from sonartrack.stonesoup.defaults import tracker_default
from sonartrack.stonesoup.hypotheses import tabulate, weighted_hypotheses
from sonartrack.stonesoup.jpda import exact_log_marginals
from sonartrack.stonesoup.tracks import EXISTENCE, existence_of, stage


class ExistenceMultipleHypothesis(MultipleHypothesis):
    """A track's hypotheses with its existence probability: predicted (from the hypothesiser) and, once
    associated, posterior P(E | Z)."""

    existence_prediction: Probability = Property(default=None, doc="P(E)-, the predicted existence probability")
    existence_probability: Probability = Property(default=None, doc="P(E | Z), set by the IPDA / JIPDA associators")


class IPDAHypothesiser(PDAHypothesiser):
    """PDA hypothesiser that also predicts the track's existence probability (module doc, eq. 11).

    Its weights are left unnormalised by default: IPDA and JIPDA need their sum Lambda (they refuse a
    hypothesiser with ``normalise=True``). Otherwise its hypotheses are exactly a ``PDAHypothesiser``'s."""

    prob_survive: Probability = Property(default=Probability(tracker_default("p_survive")),
                                         doc="p11: a target that exists still exists at the next scan (per scan)")
    prob_birth: Probability = Property(default=Probability(tracker_default("p_birth")),
                                       doc="p21: a target that does not exist appears by the next scan (per scan)")
    default_existence: Probability = Property(default=None, doc="P(E) of a track with none in its metadata; None: "
                                              "such a track is an error (1: IPDA acts as PDA, JIPDA as JPDA)")
    normalise: bool = Property(default=False, doc="Normalise the weights (IPDA and JIPDA need False)")

    def hypothesise(self, track, detections, timestamp, **kwargs):
        """The PDA hypotheses of ``track`` with its predicted existence P(E)- (module doc).

        Parameters
        ----------
        track : Track
            The track (its last state the prior).
        detections : set of Detection
            The scan's detections.
        timestamp : datetime.datetime
            Time of the scan.
        **kwargs
            Passed to Stone Soup's ``PDAHypothesiser.hypothesise``.

        Returns
        -------
        ExistenceMultipleHypothesis
            Stone Soup's PDA hypotheses with ``existence_prediction`` = p11 P(E) + p21 (1 - P(E)).
        """
        multi = super().hypothesise(track, detections, timestamp, **kwargs)
        p_pred = existence_predict(existence_of(track, self.default_existence), float(self.prob_survive),
                                   float(self.prob_birth))
        return ExistenceMultipleHypothesis(multi.single_hypotheses, existence_prediction=Probability(float(p_pred)))


def _check_hypothesiser(hypothesiser) -> None:
    if getattr(hypothesiser, "normalise", False):
        raise InputError("IPDA / JIPDA need the hypothesiser's unnormalised weights: set normalise=False")


def _existence_prediction(multi) -> float:
    if not isinstance(multi, ExistenceMultipleHypothesis) or multi.existence_prediction is None:
        raise InputError("IPDA / JIPDA need an IPDAHypothesiser (hypotheses with a predicted existence probability)")
    return float(multi.existence_prediction)


class _ExistenceAssociator(DataAssociator):
    """An associator on an :class:`IPDAHypothesiser`'s hypotheses (IPDA and JIPDA)."""

    hypothesiser: IPDAHypothesiser = Property(doc="Hypothesiser that predicts the existence probability")


class IPDA(_ExistenceAssociator):
    """Integrated PDA, each track on its own (module doc; Musicki, Evans & Stankovic 1994)."""

    def associate(self, tracks, detections, timestamp, **kwargs):
        """Mapping track -> ExistenceMultipleHypothesis: per track the weights beta_tj = w_tj / Lambda given
        existence, with the predicted and posterior existence (arguments as
        :meth:`sonartrack.stonesoup.jpda.JPDA.associate`); stages P(E | Z) on the track."""
        _check_hypothesiser(self.hypothesiser)
        hypotheses = self.generate_hypotheses(tracks, detections, timestamp, **kwargs)
        out = {}
        for track, multi in hypotheses.items():
            p_pred = _existence_prediction(multi)
            table = tabulate([track], {track: multi})
            log_w = np.concatenate([table.log_miss, table.log_lik[0]])
            log_lambda = np.logaddexp.reduce(log_w)
            p_post = float(existence_update(p_pred, np.exp(log_lambda)))
            out[track] = weighted_hypotheses(multi, table.columns[0], (log_w - log_lambda).tolist(), timestamp,
                                             ExistenceMultipleHypothesis, existence_prediction=Probability(p_pred),
                                             existence_probability=Probability(p_post))
            stage(track, **{EXISTENCE: p_post})
        return out


def jipda_log_weights(log_lik, log_miss, p_pred):
    """JIPDA on arrays (module doc): (log beta given existence (n, m + 1), posterior existence (n,)).

    ``log_lik (n, m)`` log w_tj, ``log_miss (n,)`` log w_t0 (unnormalised PDA weights), ``p_pred (n,)`` P(E)-.

    Parameters
    ----------
    log_lik : array_like, shape (n, m)
        log w_tj (-inf where not gated).
    log_miss : array_like, shape (n,)
        log w_t0.
    p_pred : array_like, shape (n,)
        Predicted existence P(E)- of each track.

    Returns
    -------
    log_beta : ndarray, shape (n, m + 1)
        log beta_t0 (missed, given existence), then log beta_tj.
    existence : ndarray, shape (n,)
        Posterior existence P(E_t | Z).
    """
    p_pred = np.clip(np.asarray(p_pred, dtype=float), 1e-300, 1.0)  # P(E)- = 0 would leave beta 0/0
    w0 = np.exp(np.asarray(log_miss, dtype=float))
    with np.errstate(divide="ignore"):
        log_p = np.log(p_pred)
        log_miss_joint = np.log1p(-p_pred * (1.0 - w0))
        lb = exact_log_marginals(np.asarray(log_lik, dtype=float) + log_p[:, None], log_miss_joint)
        # beta'_t0 split into "exists but missed" (kept) and "does not exist" (dropped)
        log_missed = lb[:, 0] + log_p + np.log(w0) - log_miss_joint
    log_exist = np.logaddexp(np.logaddexp.reduce(lb[:, 1:], axis=1, initial=-np.inf), log_missed)
    out = np.column_stack([log_missed, lb[:, 1:]]) - log_exist[:, None]
    return out, np.exp(log_exist)


class JIPDA(_ExistenceAssociator):
    """Joint IPDA with exact marginals (module doc; Musicki & Evans 2004)."""

    def associate(self, tracks, detections, timestamp, **kwargs):
        """Mapping track -> ExistenceMultipleHypothesis of the JIPDA weights given existence, with the predicted
        and posterior existence (arguments as :meth:`sonartrack.stonesoup.jpda.JPDA.associate`); stages P(E | Z) on
        each track."""
        _check_hypothesiser(self.hypothesiser)
        hypotheses = self.generate_hypotheses(tracks, detections, timestamp, **kwargs)
        table = tabulate(tracks, hypotheses)
        p_pred = np.array([_existence_prediction(hypotheses[t]) for t in table.tracks])
        log_beta, p_post = jipda_log_weights(table.log_lik, table.log_miss, p_pred)
        out = {}
        for t, track in enumerate(table.tracks):
            out[track] = weighted_hypotheses(hypotheses[track], table.columns[t], log_beta[t].tolist(), timestamp,
                                             ExistenceMultipleHypothesis,
                                             existence_prediction=Probability(p_pred[t]),
                                             existence_probability=Probability(p_post[t]))
            stage(track, **{EXISTENCE: float(p_post[t])})
        return out

