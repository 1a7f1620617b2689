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


def duplicate_of(x, P, confirmed, born_s, existence, gamma: float, coasting=None) -> np.ndarray:
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
    coasting : array (n,) bool, optional
        Tracks coasting through missed scans (:class:`DuplicateMerger`): ranked below the confirmed tracks that are
        not, so of a pair the track holding its target is kept (default: none).

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
    # rank: confirmed first, then not coasting, then older, then more likely to exist; a track is dropped when a
    # better-ranked kept track is its duplicate
    lost = np.zeros(n, bool) if coasting is None else np.asarray(coasting, bool)
    order = np.lexsort((-np.asarray(existence, float), np.asarray(born_s, float), lost,
                        ~np.asarray(confirmed, bool)))
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

    A confirmed track coasting through missed scans (its existence below ``lost_existence`` at this scan or the last)
    has a covariance that grows with every miss, and the test, whose T = P_i + P_j then accepts almost any pair,
    loses its power: on the active chain's default scene as CW (seeds 1 and 2, pings 93-103) crossing-b's track
    coasted 8-9 pings (existence 1 -> 0.15, position sd 50 -> 840 m), reached the approacher's contacts 1.2 km away
    and passed the test against the approacher's own track, which the merger then deleted as the older one's
    duplicate: one row for two targets. So a coasting track ranks below one holding its target (the latter is
    kept), and its deletion is recorded as the same target only when the pair also passes the test at the last
    scan the coaster held its target (existence >= ``held_existence``, both states of that scan, when the kept
    track existed then): track-to-track association over the pair's history (Bar-Shalom, Willett & Tian 2011,
    track-to-track association with the tracks' histories), which separates two targets that were apart and
    meet (crossing) from two tracks of one target. Otherwise the coaster is deleted as lost (not merged).

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
    lost_existence : float
        A track whose existence is below this at this scan or the last is coasting (0.5: more likely gone than
        there); None: no track is (P4's merger).
    held_existence : float
        A track holds its target at a scan when its existence is at least this (0.9: a track of existence ~1 falls
        below it after two misses in a row at the CW pd 0.4, tracking/existence.py).
    history_scans : int
        A confirmed duplicate of a confirmed track is recorded as the same target only when the pair also passed the
        test on each of the last this many scans on which both were confirmed (a window of the pair's history); 0:
        this scan's test only.
    keep_apart : bool
        Two confirmed tracks that failed the test at any scan on which both held their targets (existence >=
        ``held_existence``) are two targets: neither is deleted as the other's duplicate later (when they cross),
        the whole common history as the track-to-track association over the pairs' histories (Bar-Shalom, Willett
        & Tian 2011) in its simplest form, a pair once told apart stays apart. False: P4's merger. Measured on the
        active chain's default scene as CW (benchmarks/bench_active_rows.py, seeds 1 and 2, with contacts shared
        by rank, systems/active/contact_tracker.py ``claims``): the merges that joined two targets' tracks were all
        of pairs held apart before (the approacher's 16-ping track deleted as crossing-b's duplicate at ping 52).
    reunite_scans : int
        A told-apart pair (``keep_apart``) is merged after all when, on this many scans in a row, it passes the test
        on the whole state, on the velocity alone (``velocity_gamma``) and both tracks' nearest contact of the scan
        (``contacts``, set in place before each scan) is one and the same, within both gates: two tracks fed by the same
        echoes at the same velocity follow one target; two crossing targets share contacts only for the scan or
        two of their crossing, at different velocities. 0: never (told apart stays apart). Measured
        (benchmarks/bench_active_rows.py, cached contacts; rows for 4 or 5 targets, 0 -> 8 scans): default scene as
        CW seeds 1/2/5 7/5/6 -> 6/4/5, bench_cw_held.py's scene b seeds 3/4 9/8 -> 7/8; no reunion joined two
        targets' tracks (rows holding two targets 0/0/0 and 0/2 either way, seed 4's through side twins), no
        target's held % lower (seed 5's crossing-a 67 -> 75); LFM seeds 1-2 unchanged. 3 and 5 scans joined two
        targets (CW seed 5, scene b seed 3).
    velocity_gamma : float
        Gate of the velocity-only test and of a contact in a track's gate (chi-square, 2 degrees of freedom).
    """

    inner: object
    gamma: float
    confirmed_scans: int = 1
    lost_existence: float | None = 0.5
    held_existence: float = 0.9
    history_scans: int = 0
    keep_apart: bool = False
    reunite_scans: int = 0
    velocity_gamma: float = 9.21
    contacts: list = field(default_factory=list)  # this scan's [xy (m, 2) m, R (m, 2, 2) m^2], for ``reunite_scans``
    together: dict = field(default_factory=dict)  # told-apart pair -> consecutive scans reunited (class doc)
    merged: dict = field(default_factory=dict)
    apart: set = field(default_factory=set)  # (lower id, higher id) of confirmed pairs told apart while both held
    streak: dict = field(default_factory=dict)  # (lower id, higher id) -> consecutive scans passing the test
    held: dict = field(default_factory=dict)  # track id -> its last scan with existence >= held_existence
    states: dict = field(default_factory=dict)  # scan -> {confirmed track id: (x, P)} of the scans ``held`` names
    last_existence: dict = field(default_factory=dict)  # track id -> existence at the last scan

    def new_track_attrs(self, k: int) -> dict:
        """The inner deleter's per-track counters of ``k`` new tracks (the deleter-part protocol:
        tracking/deleters.py)."""
        return self.inner.new_track_attrs(k)

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """The inner deleter's confirmation and deletion (``hit`` passed to it), then the duplicates' deletion;
        returns the kept tracks."""
        T = self.inner.manage(T, hit)
        scan = max(self.states, default=-1) + 1
        if len(T) < 2 or not T.confirmed.any():
            self.streak.clear()
            return self._remember(T, scan)
        snap = TrackSnapshot.of(0.0, T)
        coasting = self._coasting(T)
        into = duplicate_of(snap.x, snap.P, T.confirmed, T.born_s, T.existence, self.gamma, coasting)
        ids = T.track_id
        both = np.nonzero((into >= 0) & T.confirmed)[0]
        key = {k: tuple(sorted((int(ids[into[k]]), int(ids[k])))) for k in both}  # the pair, whichever is kept
        pairs = {key[k]: self.streak.get(key[k], 0) + 1 for k in both}
        self.streak.clear()
        self.streak.update(pairs)
        together = self._reunited(snap, [(into[k], k, key[k]) for k in both if key[k] in self.apart])
        for k in both:
            if key[k] in self.apart and together.get(key[k], 0) < max(self.reunite_scans, 1):
                into[k] = -1  # two targets told apart before (keep_apart): not a duplicate
            elif pairs[key[k]] < self.confirmed_scans:
                into[k] = -1  # not yet: the pair must keep passing the test
            elif self._same_target(int(ids[into[k]]), int(ids[k]), bool(coasting[k]), scan):
                self.merged[int(ids[k])] = int(ids[into[k]])
        return self._remember(T.select(into < 0), scan)

    def _reunited(self, snap, candidates) -> dict:
        """Update and return ``together``: the told-apart pairs (kept index, other index, key) that pass the velocity
        test and share their nearest contact at this scan (``reunite_scans``), with their streaks."""
        now = {}
        if self.reunite_scans > 0 and self.contacts and len(self.contacts[0]):
            z, R = (np.asarray(a, float) for a in self.contacts)
            for i, j, key in candidates:
                dv = snap.x[i, 2:] - snap.x[j, 2:]
                near = [self._nearest(z, R, snap.x[t, :2], snap.P[t, :2, :2]) for t in (i, j)]
                if dv @ np.linalg.solve(snap.P[i, 2:, 2:] + snap.P[j, 2:, 2:], dv) < self.velocity_gamma and \
                        near[0] >= 0 and near[0] == near[1]:
                    now[key] = self.together.get(key, 0) + 1
        self.together.clear()
        self.together.update(now)
        return now

    def _nearest(self, z, R, xy, P_xy) -> int:
        """Index of the contact nearest a track's position in its gate (Mahalanobis, ``velocity_gamma``); -1: none."""
        nu = z - xy
        d2 = np.einsum("mi,mi->m", nu, np.linalg.solve(R + P_xy, nu[..., None])[..., 0])
        k = int(np.argmin(d2))
        return k if d2[k] < self.velocity_gamma else -1

    def _coasting(self, T: TrackArrays) -> np.ndarray:
        """Which tracks coast (existence below ``lost_existence`` at this scan or the last; class doc)."""
        if self.lost_existence is None:
            return np.zeros(len(T), bool)
        last = np.array([self.last_existence.get(int(i), 1.0) for i in T.track_id])
        return np.minimum(np.asarray(T.existence, float), last) < self.lost_existence

    def _same_target(self, kept: int, gone: int, coasting: bool, scan: int) -> bool:
        """Is the deleted confirmed duplicate ``gone`` recorded as ``kept``'s target (class doc)?"""
        if coasting and self._apart_when_held(kept, gone) is True:
            return False
        for s in range(scan - self.history_scans, scan):
            at = self.states.get(s, {})
            if kept in at and gone in at and self._d2(at[kept], at[gone]) >= self.gamma:
                return False
        return True

    @staticmethod
    def _d2(a, b) -> float:
        nu = a[0] - b[0]
        return float(nu @ np.linalg.solve(a[1] + b[1], nu))

    def _apart_when_held(self, kept: int, lost: int) -> bool | None:
        """Did the pair fail the test at the last scan ``lost`` held its target (None: no such scan with both)?"""
        at = self.states.get(self.held.get(lost, -1), {})
        if kept not in at or lost not in at:
            return None
        return self._d2(at[kept], at[lost]) >= self.gamma

    def _tell_apart(self, T: TrackArrays, snap) -> None:
        """Add to ``apart`` the confirmed pairs holding their targets that fail the test now (``keep_apart``); forget
        the pairs of deleted tracks."""
        alive = {int(i) for i in T.track_id}
        self.apart.intersection_update({p for p in self.apart if p[0] in alive and p[1] in alive})
        h = np.nonzero(T.confirmed & (np.asarray(T.existence, float) >= self.held_existence))[0]
        if len(h) < 2:
            return
        x, P, ids = snap.x[h], snap.P[h], T.track_id[h]
        nu = x[:, None, :] - x[None, :, :]
        d2 = np.einsum("abi,abi->ab", nu, np.linalg.solve(P[:, None] + P[None, :], nu[..., None])[..., 0])
        for a, b in zip(*np.nonzero(np.triu(d2 >= self.gamma, 1)), strict=True):
            self.apart.add(tuple(sorted((int(ids[a]), int(ids[b])))))

    def _remember(self, T: TrackArrays, scan: int) -> TrackArrays:
        """Record this scan's confirmed states and existences (for :meth:`_apart_when_held`); returns ``T``."""
        snap = TrackSnapshot.of(0.0, T) if len(T) else None
        self.states[scan] = {} if snap is None else {int(i): (snap.x[k], snap.P[k])
                                                     for k, i in enumerate(T.track_id) if T.confirmed[k]}
        for k, i in enumerate(T.track_id):
            if T.existence[k] >= self.held_existence:
                self.held[int(i)] = scan
        if self.keep_apart and snap is not None:
            self._tell_apart(T, snap)
        self.last_existence.clear()
        self.last_existence.update({int(i): float(e) for i, e in zip(T.track_id, T.existence, strict=True)})
        for i in [i for i in self.held if i not in self.last_existence]:
            del self.held[i]
        keep = set(self.held.values()) | set(range(scan - self.history_scans, scan + 1))
        for s in [s for s in self.states if s not in keep]:
            del self.states[s]
        return T
