"""Track-level quality per true target: time to confirm, fragmentation and identity switches.

Association (one per time step, the GOSPA assignment of metrics/ospa.py): at time t_k the confirmed tracks
are assigned to the true targets present by the optimal assignment of least sum of min(g, distance)^p, and a
pair at or beyond the gate g is no association. a_k(i) is then the track id held by target i at t_k, or none
(∅). Over the times K_i at which target i is present (in order), following the track-level measures of
Gorji, Tharmarasa, Kirubarajan 2011 ("Performance measures for multiple target tracking problems", 14th Int.
Conf. Information Fusion, sec. III: track latency, fragmentation, ID swaps) and the mismatch count of CLEAR
MOT (Bernardin & Stiefelhagen 2008, "Evaluating multiple object tracking performance: the CLEAR MOT
metrics", EURASIP J. Image Video Process., sec. 2.1, mme_t)::

    time to confirm     T_i = min{t_k : k in K_i, a_k(i) != ∅} - min{t_k : k in K_i}       (NaN: never held)
    segments            F_i = #{k in K_i : a_k(i) != ∅ and (k first in K_i or a_k(i) != a_k'(i))}
                              (k' the previous time in K_i: a gap or a new id starts a new segment)
    identity switches   W_i = #{k in K_i : a_k(i) != ∅ and a_k(i) != a_l(i)},
                              l the last time before k with a_l(i) != ∅ (the last id is remembered over gaps)

A target held by one track from confirmation to its end has F = 1 and W = 0; a track lost and
re-confirmed under a new id adds one to both, a track that drops out and comes back under its own id
adds one segment and no switch.

:func:`time_to_confirm`, :func:`track_segments` and :func:`identity_switches` take the association ``assoc`` (a
:class:`TrackAssociation` from :func:`associate_tracks`) and return one value per target, shape (T,), in
``assoc.truth_ids`` order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.metrics.ospa import gospa, time_steps

NONE = -1  # no track


@dataclass(frozen=True, slots=True)
class TrackAssociation:
    """Which track holds each true target at each time (module doc)."""

    time_s: np.ndarray  # (K,) distinct times of the truth and track tables (s)
    truth_ids: np.ndarray  # (T,) the true targets' ids, sorted
    present: np.ndarray  # (K, T) bool: target i is in the truth table at time k
    track_of: np.ndarray  # (K, T) int: id of the confirmed track that holds target i at time k, NONE (-1) for none


def associate_tracks(truth_time, truth_id, truth_pos, track_time, track_id, track_pos, gate: float,
                     confirmed=None, p: float = 2.0) -> TrackAssociation:
    """Assign the confirmed tracks to the true targets at every time (module doc).

    Parameters
    ----------
    truth_time, truth_id, truth_pos : array_like, shapes (M,), (M,), (M, d)
        True targets: time (s), target id, position (m).
    track_time, track_id, track_pos : array_like, shapes (N,), (N,), (N, d)
        Track estimates: time (s), integer track id (>= 0), position (m).
    gate : float
        Association gate g (m): a track farther than this from a target does not hold it.
    confirmed : array_like of bool, shape (N,), optional
        Which track rows are confirmed (default: all); the others take no part.
    p : float, default 2
        Order of the assignment cost min(g, distance)^p.

    Returns
    -------
    TrackAssociation
        The times, target ids, presence and the track id holding each target at each time.
    """
    track_id = np.asarray(track_id).ravel()
    require(track_id.size == 0 or (np.issubdtype(track_id.dtype, np.integer) and track_id.min() >= 0),
            "track ids must be non-negative integers (map other ids to 0, 1, ... first)")
    keep = np.ones(len(track_id), bool) if confirmed is None else np.asarray(confirmed, bool).ravel()
    track_time, track_pos = np.asarray(track_time, float).ravel()[keep], np.asarray(track_pos, float)[keep]
    track_id = track_id[keep]
    truth_id = np.asarray(truth_id).ravel()
    truth_pos = np.asarray(truth_pos, float)
    ids = np.unique(truth_id)
    times, t_rows, e_rows = time_steps(truth_time, track_time)
    present = np.zeros((len(times), len(ids)), bool)
    track_of = np.full((len(times), len(ids)), NONE, dtype=np.int64)
    for k, (i, j) in enumerate(zip(t_rows, e_rows, strict=True)):
        col = np.searchsorted(ids, truth_id[i])
        present[k, col] = True
        a = gospa(truth_pos[i], track_pos[j], gate, p)
        held = a.truth_to_estimate >= 0
        track_of[k, col[held]] = track_id[j[a.truth_to_estimate[held]]]
    return TrackAssociation(times, ids, present, track_of)


def time_to_confirm(assoc: TrackAssociation) -> np.ndarray:
    """T_i: time (s) from a target's first appearance to the first time a confirmed track holds it, per target
    (module doc); NaN for a target never held."""
    held = assoc.track_of != NONE
    k_first = np.argmax(assoc.present, axis=0)
    k_held = np.argmax(held, axis=0)
    t = assoc.time_s
    out = np.full(len(assoc.truth_ids), np.nan)
    ok = held.any(axis=0)
    out[ok] = t[k_held[ok]] - t[k_first[ok]]
    return out


def _present_sequences(assoc: TrackAssociation):
    """Per target, the track ids over the times it is present (NONE where no track holds it)."""
    return [assoc.track_of[assoc.present[:, i], i] for i in range(len(assoc.truth_ids))]


def track_segments(assoc: TrackAssociation) -> np.ndarray:
    """F_i: the number of track segments that hold each target (module doc; fragmentation), int per target
    (0: never held; 1: held by one track without a break)."""
    out = []
    for a in _present_sequences(assoc):
        prev = np.concatenate([[NONE], a[:-1]])
        out.append(int(np.count_nonzero((a != NONE) & (a != prev))))
    return np.array(out, dtype=np.int64)


def identity_switches(assoc: TrackAssociation) -> np.ndarray:
    """W_i: the number of times the track holding each target changes id, gaps bridged (module doc), int per
    target."""
    out = []
    for a in _present_sequences(assoc):
        held = a[a != NONE]  # the ids in order; a gap keeps the last one
        out.append(int(np.count_nonzero(held[1:] != held[:-1])))
    return np.array(out, dtype=np.int64)
