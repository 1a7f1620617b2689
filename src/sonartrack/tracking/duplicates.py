"""Duplicate tracks: two tracks that follow one target, found by the track-to-track test and merged into one.

An IPDA track updates on every measurement in its own gate, whatever other tracks take from the same gate
(PDA, not JIPDA). A one-point track started on a stray contact a few hundred metres off a confirmed track (a
sidelobe echo, reverberation, a displaced multi-ping detection) drifts into that target's measurements, and
from then on the two tracks see the same contacts, their states coalesce and both are confirmed: one target,
two or more tracks, which a track-to-truth assignment takes in turn (fragments and identity switches). Measured
on the active chain's default scene (seed 9101, one hour): 3-4 confirmed tracks per strong target at once,
states within 50 m of each other.

The test is the track-to-track association test of Bar-Shalom (1981, "On the track-to-track correlation
problem", IEEE Trans. Automatic Control 26(2), 571-572; also Bar-Shalom, Willett & Tian 2011, "Tracking and
Data Fusion", track-to-track association): the difference of two estimates of one target,

    Delta = x_i - x_j,   T_ij = P_i + P_j - P_ij - P_ji,   d^2 = Delta^T T_ij^-1 Delta  ~  chi^2(n_x),

is accepted as "same target" when d^2 < chi^2_{n_x}(p). The cross-covariance P_ij is not tracked here and is
taken as zero: T is then too large for two tracks fed the same contacts (their errors are positively
correlated), so the test accepts more readily - the wanted direction for duplicates, and the velocity
components (4 of the state's entries) still keep two crossing targets apart (their velocities differ by
several m/s against a confirmed track's velocity sd of < 1 m/s).

Of a duplicate pair, the kept track is the confirmed one, then the older one (the track whose identity a user
has seen longest; ties: the higher existence); the other is deleted. Only pairs with at least one confirmed
track are tested (a tentative duplicate of a tentative track is caught once either is confirmed), which keeps
the cost at (confirmed x live) pairs per scan.

:class:`DuplicateMerger` wraps a deleter part (tracking/deleters.py) and runs after it, so it plugs into
:class:`~sonartrack.tracking.multi_target.MultiTargetTracker` unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sonartrack.tracking.tracks import TrackArrays, TrackSnapshot


def duplicate_mask(x, P, confirmed, born_s, existence, gamma: float) -> np.ndarray:
    """Which tracks to keep (bool (n,)) after deleting duplicates by the track-to-track test (module doc):
    ``duplicate_of(...) < 0``."""
    return duplicate_of(x, P, confirmed, born_s, existence, gamma) < 0


def duplicate_of(x, P, confirmed, born_s, existence, gamma: float) -> np.ndarray:
    """The kept track each track duplicates (index, (n,) int; -1: kept) by the track-to-track test (module doc).

    Parameters
    ----------
    x : array (n, d)
        Combined track states (any units, consistent with ``P``).
    P : array (n, d, d)
        Their covariances.
    confirmed : array (n,) bool
        Confirmed tracks (only pairs with at least one confirmed track are tested).
    born_s : array (n,)
        Initiation time of each track (s): the older of two confirmed duplicates is kept.
    existence : array (n,)
        Existence probabilities (tie-break: the higher is kept).
    gamma : float
        Gate on d^2 = Delta^T (P_i + P_j)^-1 Delta (chi-square with d degrees of freedom).

    Returns
    -------
    numpy.ndarray
        (n,) int: for each track that duplicates a kept, higher-ranked track, that track's index; -1 for a kept one.
    """
    x, P = np.asarray(x, float), np.asarray(P, float)
    n = len(x)
    into = np.full(n, -1, np.int64)
    conf = np.nonzero(np.asarray(confirmed, bool))[0]
    if n < 2 or not len(conf):
        return into
    nu = x[None, :, :] - x[conf, None, :]  # (c, n, d)
    S = P[None, :, :, :] + P[conf, None, :, :]
    d2 = np.einsum("cni,cni->cn", nu, np.linalg.solve(S, nu[..., None])[..., 0])
    d2[np.arange(len(conf)), conf] = np.inf
    # rank: confirmed first, then older, then more likely to exist; a track is dropped when a better-ranked kept
    # track is its duplicate
    order = np.lexsort((-np.asarray(existence, float), np.asarray(born_s, float), ~np.asarray(confirmed, bool)))
    rank = np.empty(n, np.int64)
    rank[order] = np.arange(n)
    row = {int(c): k for k, c in enumerate(conf)}
    for i in order:
        if into[i] >= 0 or i not in row:
            continue
        dup = (d2[row[i]] < gamma) & (rank > rank[i]) & (into < 0)
        into[dup] = i
    return into


@dataclass(frozen=True)
class DuplicateMerger:
    """A deleter part that runs ``inner`` and then deletes duplicate tracks (module doc); ``merged`` records, for each
    deleted track that had been confirmed, the id of the track it duplicated (the same target: its listing joins
    them, systems/active/targets.py).

    Parameters
    ----------
    inner : deleter part
        The tracker's own deleter (e.g. :class:`~sonartrack.tracking.deleters.ExistenceDeleter`).
    gamma : float
        Gate of the track-to-track test on the combined state (chi-square, state dimension degrees of freedom).
    confirmed_scans : int
        A confirmed track is deleted as the duplicate of another confirmed one only once the pair has passed the test
        on this many consecutive scans (a tentative duplicate at once). Two crossing targets pass it on the scans
        around their crossing, when their tracks' velocities are still uncertain, and a merge there joins two targets
        into one row (measured on the active chain's default scene: LFM seed 2 at ping 57, CW seeds 1 and 2); two
        tracks on one target keep passing it. 1: P4's merger, at once (the active chain's default: 2 and 3 measured
        worse on benchmarks/bench_active_rows.py, the merges of two targets' tracks only came a scan or two later).
    """

    inner: object
    gamma: float
    confirmed_scans: int = 1
    merged: dict = field(default_factory=dict)
    streak: dict = field(default_factory=dict)  # (kept id, duplicate id) -> consecutive scans passing the test

    def new_track_attrs(self, k: int) -> dict:
        """The inner deleter's per-track counters of ``k`` new tracks (the deleter-part protocol:
        tracking/deleters.py)."""
        return self.inner.new_track_attrs(k)

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """The inner deleter's confirmation and deletion (``hit`` passed to it), then the duplicates' deletion;
        returns the kept tracks."""
        T = self.inner.manage(T, hit)
        if len(T) < 2 or not T.confirmed.any():
            self.streak.clear()
            return T
        snap = TrackSnapshot.of(0.0, T)
        into = duplicate_of(snap.x, snap.P, T.confirmed, T.born_s, T.existence, self.gamma)
        ids = T.track_id
        both = np.nonzero((into >= 0) & T.confirmed)[0]
        pairs = {(int(ids[into[k]]), int(ids[k])): self.streak.get((int(ids[into[k]]), int(ids[k])), 0) + 1
                 for k in both}
        self.streak.clear()
        self.streak.update(pairs)
        for k in both:
            if pairs[(int(ids[into[k]]), int(ids[k]))] < self.confirmed_scans:
                into[k] = -1  # not yet: the pair must keep passing the test
            else:
                self.merged[int(ids[k])] = int(ids[into[k]])
        return T.select(into < 0)
