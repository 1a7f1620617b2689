"""Drop-in exact JPDA for Stone Soup: the hypotheses of its ``JPDA`` / ``JPDAwithEHM2``, our marginals.

Stone Soup's ``JPDA`` enumerates every joint event and ``JPDAwithEHM2`` builds an EHM2 tree in Python;
both compute the exact marginals (Bar-Shalom & Fortmann 1988, ch. 9; paper P0, appendix A)

    P(chi) = prod_t w_{t, chi(t)} / Z,       beta_tj = sum_{chi: chi(t) = j} P(chi)

over the joint events chi that give each track at most one detection and each detection at most one
track, from the single-target weights w_tj of the hypothesiser (w_t0 the missed detection). :class:`JPDA`
asks the same hypothesiser, puts the weights into arrays (stonesoup/hypotheses.py) and computes beta
with sonartrack's compiled forward-backward pass over track clusters (association/jpda.py), then
returns Stone Soup hypotheses built exactly as Stone Soup's ``JPDA.associate`` builds them.

Our kernel holds at most 62 gated detections per cluster. A detection that only one track of a scan
gates ("private") cannot conflict with another track, so all of track t's private detections act as one
option with weight W_t = sum_j w_tj; :func:`exact_log_marginals` merges them when a scan has more than
62 detections and splits the merged marginal back, beta_tj = beta_t,merged w_tj / W_t -- exact, not an
approximation (a single track with 500 detections is then one column).
"""

from __future__ import annotations

import numpy as np
from stonesoup.base import Property
from stonesoup.dataassociator.base import DataAssociator
from stonesoup.hypothesiser.probability import PDAHypothesiser

from sonartrack.association.jpda import MAX_CLUSTER_MEASUREMENTS, jpda_log_weights
from sonartrack.stonesoup.hypotheses import tabulate, weighted_hypotheses


def _merge_private(log_lik):
    """(reduced log_lik, shared column indices, owner of each merged column, log W per track)."""
    gated = np.isfinite(log_lik)
    shared = gated.sum(axis=0) > 1
    private = gated & ~shared
    with np.errstate(divide="ignore"):
        m = np.where(private, log_lik, -np.inf).max(axis=1, initial=-np.inf)
        safe = np.where(np.isfinite(m), m, 0.0)
        log_w = safe + np.log(np.where(private, np.exp(log_lik - safe[:, None]), 0.0).sum(axis=1))
    owners = np.nonzero(private.any(axis=1))[0]
    merged = np.full((len(log_lik), len(owners)), -np.inf)
    merged[owners, np.arange(len(owners))] = log_w[owners]
    return np.hstack([log_lik[:, shared], merged]), np.nonzero(shared)[0], owners, log_w


def exact_log_marginals(log_lik, log_miss) -> np.ndarray:
    """log beta (n, m + 1) of :func:`sonartrack.association.jpda.jpda_log_weights`, for any number of detections.

    Above 62 detections the private detections of each track are merged first (module doc):
    log beta_tj = log beta_t,merged + log w_tj - log W_t.

    Parameters
    ----------
    log_lik : array_like, shape (n, m)
        log w_tj of the single-target weights (-inf where not gated).
    log_miss : array_like, shape (n,)
        log w_t0.

    Returns
    -------
    ndarray, shape (n, m + 1)
        Exact JPDA marginals, log beta_t0 in column 0.
    """
    ll = np.asarray(log_lik, dtype=float)
    if ll.shape[1] <= MAX_CLUSTER_MEASUREMENTS:
        return jpda_log_weights(ll, log_miss)
    reduced, shared, owners, log_w = _merge_private(ll)
    lb = jpda_log_weights(reduced, log_miss)
    out = np.full((ll.shape[0], ll.shape[1] + 1), -np.inf)
    out[:, 0] = lb[:, 0]
    out[:, shared + 1] = lb[:, 1:len(shared) + 1]
    merged_beta = np.full(len(ll), -np.inf)
    merged_beta[owners] = lb[owners, len(shared) + 1 + np.arange(len(owners))]
    private = np.isfinite(ll)
    private[:, shared] = False
    ti, mj = np.nonzero(private)
    out[ti, mj + 1] = merged_beta[ti] + ll[ti, mj] - log_w[ti]
    return out


def associate_exact(associator, tracks, detections, timestamp, **kwargs):
    """Hypothesise, table, exact marginals: (hypotheses, table, log beta (n, m + 1)).

    Parameters
    ----------
    associator : DataAssociator
        Gives ``generate_hypotheses`` (its hypothesiser).
    tracks, detections, timestamp, **kwargs
        As :meth:`JPDA.associate`.

    Returns
    -------
    hypotheses : dict of Track to MultipleHypothesis
        The single-target hypotheses.
    table : HypothesisTable
        Their weights as arrays (stonesoup/hypotheses.py).
    log_beta : ndarray, shape (n, m + 1)
        The exact marginals.
    """
    hypotheses = associator.generate_hypotheses(tracks, detections, timestamp, **kwargs)
    table = tabulate(tracks, hypotheses)
    return hypotheses, table, exact_log_marginals(table.log_lik, table.log_miss)


class JPDA(DataAssociator):
    """Exact JPDA, a drop-in for Stone Soup's ``JPDA`` / ``JPDAwithEHM`` / ``JPDAwithEHM2`` (module doc).

    Same property (``hypothesiser``), same call, same result: a mapping track -> ``MultipleHypothesis``
    whose first hypothesis is the missed detection, each with its marginal probability beta_tj."""

    hypothesiser: PDAHypothesiser = Property(
        doc="Generate a set of hypotheses for each prediction-detection pair")

    def associate(self, tracks, detections, timestamp, **kwargs):
        """Mapping track -> MultipleHypothesis with the exact JPDA marginals as probabilities.

        Parameters
        ----------
        tracks : set of Track
            The live tracks.
        detections : set of Detection
            The scan's detections.
        timestamp : datetime.datetime
            Time of the scan.
        **kwargs
            Passed to the hypothesiser.

        Returns
        -------
        dict of Track to MultipleHypothesis
            Missed detection first, then each detection hypothesis with its marginal.
        """
        hypotheses, table, log_beta = associate_exact(self, tracks, detections, timestamp, **kwargs)
        return {track: weighted_hypotheses(hypotheses[track], table.columns[t], _row(log_beta, t), timestamp)
                for t, track in enumerate(table.tracks)}


def _row(log_beta, t):
    """log beta_t as a list indexable by column + 1 (plain floats: cheap to wrap in Probability)."""
    return log_beta[t].tolist()
