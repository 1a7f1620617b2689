"""Stone Soup hypotheses <-> our association arrays: the one place the two representations meet.

A hypothesiser gives each track a :class:`~stonesoup.types.multihypothesis.MultipleHypothesis`: one
missed-detection hypothesis (weight w_t0 = 1 - P_D P_G for a PDA hypothesiser) and one per detection
it validated (w_tj = P_D N(z_j; z_hat_t, S_t) / lambda). :func:`tabulate` turns them into the arrays
of association/jpda.py, ``log_lik (n, m)`` = log w_tj (-inf where track t has no hypothesis for
detection j) and ``log_miss (n,)`` = log w_t0; :func:`weighted_hypotheses` turns the marginals
beta_tj back into Stone Soup hypotheses, shaped exactly as Stone Soup's own ``JPDA.associate`` shapes
them (missed detection first, then the detections in the hypothesiser's order, normalised to 1).

Only ratios of weights within a track matter to the JPDA marginals (each joint event holds one
hypothesis per track), so normalised and unnormalised hypothesisers give the same beta.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleProbabilityHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability


def log_probability(p) -> float:
    """log of a Stone Soup :class:`Probability` (kept in log space) or of a plain number.

    Parameters
    ----------
    p : Probability or float
        The probability or weight.

    Returns
    -------
    float
        Its natural log (-inf for 0).
    """
    log_value = getattr(p, "log_value", None)
    if log_value is not None:
        return float(log_value)
    with np.errstate(divide="ignore"):
        return float(np.log(float(p)))


@dataclass(frozen=True, slots=True)
class HypothesisTable:
    """The hypotheses of n tracks over the m distinct detections they mention, as arrays."""

    tracks: list  # (n,) the tracks, in the order of the rows
    detections: list  # (m,) the detections, in order of first mention
    log_lik: np.ndarray  # (n, m) log w_tj, -inf where track t has no hypothesis for detection j
    log_miss: np.ndarray  # (n,) log w_t0, -inf where the track has no missed-detection hypothesis
    columns: list  # (n,) per track: the column j of each of its hypotheses, -1 for the missed detection


def tabulate(tracks, hypotheses) -> HypothesisTable:
    """Arrays of the single-target weights (module doc); detections are matched by identity, as Stone Soup does.

    Parameters
    ----------
    tracks : iterable of Track
        The tracks (the rows, in this order).
    hypotheses : dict of Track to MultipleHypothesis
        Each track's hypotheses.

    Returns
    -------
    HypothesisTable
        log w_tj (n, m), log w_t0 (n,), the detections in order of first mention and each hypothesis' column.
    """
    tracks = list(tracks)
    index: dict[int, int] = {}
    detections: list = []
    rows, columns = [], []
    log_miss = np.full(len(tracks), -np.inf)
    for t, track in enumerate(tracks):
        row, cols = {}, []
        for hyp in hypotheses[track]:
            if not hyp:  # the missed-detection hypothesis
                log_miss[t] = log_probability(hyp.probability)
                cols.append(-1)
                continue
            j = index.setdefault(id(hyp.measurement), len(detections))
            if j == len(detections):
                detections.append(hyp.measurement)
            row[j] = log_probability(hyp.probability)
            cols.append(j)
        rows.append(row)
        columns.append(cols)
    log_lik = np.full((len(tracks), len(detections)), -np.inf)
    for t, row in enumerate(rows):
        if row:
            log_lik[t, list(row)] = list(row.values())
    return HypothesisTable(tracks, detections, log_lik, log_miss, columns)


def weighted_hypotheses(multi, columns, log_beta_row, timestamp, multiple_type=MultipleHypothesis,
                        **properties) -> MultipleHypothesis:
    """One track's hypotheses re-weighted by ``log_beta_row`` (m + 1,: column 0 = missed detection).

    As Stone Soup's ``JPDA.associate``: a new missed-detection hypothesis at ``timestamp`` on the
    prediction of the track's first hypothesis, then a copy of each detection hypothesis with its
    marginal; the marginals must sum to 1 (the result is marked normalised to total weight 1, as Stone Soup's).
    ``properties`` go to ``multiple_type``.

    Parameters
    ----------
    multi : MultipleHypothesis
        The track's hypotheses.
    columns : list of int
        The table column of each hypothesis (-1: missed detection).
    log_beta_row : sequence of float, length m + 1
        The track's log marginals.
    timestamp : datetime.datetime
        Time of the scan.
    multiple_type : type
        The MultipleHypothesis class to build.
    **properties
        Its further properties.

    Returns
    -------
    MultipleHypothesis (or ``multiple_type``)
        The re-weighted hypotheses.
    """
    first = multi[0]
    out = [SingleProbabilityHypothesis(first.prediction, MissedDetection(timestamp=timestamp),
                                       measurement_prediction=first.measurement_prediction,
                                       probability=Probability(log_beta_row[0], log_value=True))]
    for hyp, j in zip(multi, columns, strict=True):
        if j < 0:
            continue
        out.append(SingleProbabilityHypothesis(hyp.prediction, hyp.measurement,
                                               measurement_prediction=hyp.measurement_prediction,
                                               probability=Probability(log_beta_row[j + 1], log_value=True)))
    multi_out = multiple_type(out, False, 1, **properties)
    # the marginals already sum to 1 (log space): mark the result normalised, as Stone Soup's, without
    # re-normalising in Probability arithmetic (half the cost of the association step, 1e-16 changes)
    multi_out.normalise = True
    return multi_out
