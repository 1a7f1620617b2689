"""Stone Soup's OSPA and GOSPA metric generators over sonartrack's outputs (tables of time, id, position).

sonartrack computes both metrics itself (metrics/ospa.py, without Stone Soup); these adapters give the same
tables to Stone Soup's ``OSPAMetric`` and ``GOSPAMetric`` (Schuhmacher, Vo, Vo 2008; Rahmathullah,
Garcia-Fernandez, Svensson 2017), for a user who evaluates in Stone Soup or wants its numbers beside ours.
Each distinct id becomes one ``Track`` (estimates) or ``GroundTruthPath`` (truth) of ``State``s holding the
position, so Stone Soup's default Euclidean measure is the position distance; times are seconds from
``epoch`` (stonesoup/convert.py). The generators run exactly as a ``MetricManager`` runs them
(``compute_over_time`` on the states the generator itself extracts).
"""

from __future__ import annotations

import datetime

import numpy as np
from stonesoup.metricgenerator.ospametric import GOSPAMetric, OSPAMetric
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState
from stonesoup.types.state import State
from stonesoup.types.track import Track

from sonartrack.core.errors import require
from sonartrack.metrics.ospa import GospaSeries
from sonartrack.stonesoup.convert import EPOCH, to_seconds, to_timestamp


def position_paths(time_s, ids, pos, *, truth: bool, epoch: datetime.datetime = EPOCH) -> list:
    """One Stone Soup path per distinct id of a table: ``GroundTruthPath``s (``truth``) or ``Track``s.

    Parameters
    ----------
    time_s : array_like, shape (M,)
        Time of each row (s after ``epoch``).
    ids : array_like, shape (M,)
        Target or track id of each row.
    pos : array_like, shape (M, d)
        Position of each row (m).
    truth : bool
        True: ground-truth paths of ``GroundTruthState``s; False: tracks of ``State``s.
    epoch : datetime.datetime
        The datetime of time 0.

    Returns
    -------
    list
        The paths in sorted id order, each with its states in time order and ``id`` the id as a string (Stone
        Soup's metrics read one state per path and time: give each (time, id) once).
    """
    t, ids = np.asarray(time_s, float).ravel(), np.asarray(ids).ravel()
    x = np.asarray(pos, float).reshape(len(t), -1)
    require(len(ids) == len(t), f"one id per row: {len(ids)} ids for {len(t)} times")
    kind, path = (GroundTruthState, GroundTruthPath) if truth else (State, Track)
    out = []
    for i in np.unique(ids):
        rows = np.nonzero(ids == i)[0]
        rows = rows[np.argsort(t[rows], kind="stable")]
        out.append(path([kind(x[r].reshape(-1, 1), timestamp=to_timestamp(t[r], epoch)) for r in rows], id=str(i)))
    return out


def _run(generator, truths, tracks):
    """The generator's metric as a MetricManager would compute it: a list of SingleTimeMetric in time order."""
    metric = generator.compute_over_time(*generator.extract_states(tracks, True),
                                         *generator.extract_states(truths, True))
    return list(metric.value) if isinstance(metric.value, list) else [metric]


def stonesoup_ospa(truth_time, truth_pos, est_time, est_pos, c: float, p: float = 1.0, *,
                   epoch: datetime.datetime = EPOCH) -> tuple[np.ndarray, np.ndarray]:
    """Stone Soup's ``OSPAMetric(c, p)`` over two position tables (metrics/ospa.py's ``ospa_over_time``).

    Parameters
    ----------
    truth_time, truth_pos : array_like, shapes (M,), (M, d)
        True positions (m) and their times (s).
    est_time, est_pos : array_like, shapes (N,), (N, d)
        Estimated positions (m) and their times (s).
    c : float
        Cut-off distance (m).
    p : float, default 1
        Order.
    epoch : datetime.datetime
        The datetime of time 0.

    Returns
    -------
    times : ndarray, shape (K,)
        The distinct times (s).
    ospa : ndarray, shape (K,)
        Stone Soup's OSPA distance at each (m).
    """
    # OSPA has no identities: a path per row (a path holds one state per time)
    truths = position_paths(truth_time, np.arange(len(np.ravel(truth_time))), truth_pos, truth=True, epoch=epoch)
    tracks = position_paths(est_time, np.arange(len(np.ravel(est_time))), est_pos, truth=False, epoch=epoch)
    values = _run(OSPAMetric(c=c, p=p), truths, tracks)
    return (np.array([to_seconds(v.timestamp, epoch) for v in values]),
            np.array([float(v.value) for v in values]))


def stonesoup_gospa(truth_time, truth_id, truth_pos, est_time, est_id, est_pos, c: float, p: float = 1.0,
                    switching_penalty: float = 0.0, *, epoch: datetime.datetime = EPOCH) -> GospaSeries:
    """Stone Soup's ``GOSPAMetric(c, p, switching_penalty)`` over two tables, as metrics/ospa.py's record.

    Parameters
    ----------
    truth_time, truth_id, truth_pos : array_like, shapes (M,), (M,), (M, d)
        True targets: time (s), id, position (m).
    est_time, est_id, est_pos : array_like, shapes (N,), (N,), (N, d)
        Tracks: time (s), id, position (m).
    c : float
        Cut-off distance (m).
    p : float, default 1
        Order.
    switching_penalty : float, default 0
        Stone Soup's ``switching_penalty`` (m).
    epoch : datetime.datetime
        The datetime of time 0.

    Returns
    -------
    GospaSeries
        Per time: Stone Soup's distance (with switching), the GOSPA distance without it (recomputed from the
        parts), localisation, missed, false and switching; ``switches`` is NaN (Stone Soup keeps no count).
    """
    truths = position_paths(truth_time, truth_id, truth_pos, truth=True, epoch=epoch)
    tracks = position_paths(est_time, est_id, est_pos, truth=False, epoch=epoch)
    values = _run(GOSPAMetric(c=c, p=p, switching_penalty=switching_penalty), truths, tracks)
    part = {k: np.array([float(v.value[k]) for v in values])
            for k in ("distance", "localisation", "missed", "false", "switching")}
    gospa = (part["localisation"] + part["missed"] + part["false"]) ** (1.0 / p)
    return GospaSeries(np.array([to_seconds(v.timestamp, epoch) for v in values]), part["distance"], gospa,
                       part["localisation"], part["missed"], part["false"], part["switching"],
                       np.full(len(values), np.nan))


def ospa_generator(c: float, p: float = 1.0, **kwargs) -> OSPAMetric:
    """Stone Soup's OSPA generator for a ``MetricManager`` over paths from :func:`position_paths` (kwargs: its
    other properties, e.g. ``tracks_key``).

    Parameters
    ----------
    c : float
        Cut-off distance (m for position paths).
    p : float
        Order.
    **kwargs
        Further properties of Stone Soup's OSPAMetric.

    Returns
    -------
    OSPAMetric
        The generator.
    """
    return OSPAMetric(c=c, p=p, **kwargs)


def gospa_generator(c: float, p: float = 1.0, switching_penalty: float = 0.0, **kwargs) -> GOSPAMetric:
    """Stone Soup's GOSPA generator (alpha = 2) for a ``MetricManager`` over paths from :func:`position_paths`.

    Parameters
    ----------
    c, p : float
        As :func:`ospa_generator`.
    switching_penalty : float
        Penalty of a track switch.
    **kwargs
        Further properties of Stone Soup's GOSPAMetric.

    Returns
    -------
    GOSPAMetric
        The generator.
    """
    return GOSPAMetric(c=c, p=p, switching_penalty=switching_penalty, **kwargs)
