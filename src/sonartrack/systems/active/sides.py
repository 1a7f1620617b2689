"""Left/right decision of the active chain's confirmed tracks: a likelihood ratio of the two mirror hypotheses.

A line array cannot tell port from starboard, so each detection gives two mirror contacts (contacts.py).
While the array runs straight, the mirror of a constant-velocity (CV) target about its axis is again a CV
target, and the two hypotheses explain the contacts equally well; after a turn of the array the reflection
axis has moved, and only the true side's contacts stay on one CV track. As the passive chain does for
bearings (tma/sides.py), each confirmed track's side is decided by a generalised likelihood ratio: the
contacts z_k the track gates (one per ping, the nearest in the Mahalanobis sense) and their mirrors z'_k (the
other contact of the same detection) are each fitted by a CV motion z = p0 + (t_k - t_0) v with the contacts'
own covariances R_k (J Sigma J^T, paper P4 eqs. 3-6), by weighted least squares:

    A_k = [I, (t_k - t_0) I],   I = sum A_k^T R_k^-1 A_k,   b = sum A_k^T R_k^-1 z_k
    chi2_min = sum z_k^T R_k^-1 z_k - b^T I^-1 b
    ln L = -(chi2_min + sum ln det(2 pi R_k)) / 2,      ln LR = ln L(track's side) - ln L(mirror side)

(Gaussian likelihood maximised over the 4 CV parameters; both hypotheses have 4, so no dimension penalty).
The ratio is computed at every ping, once the track has lived through the turn (before it, it is 0).
Each contact's share of chi2_min is capped at c, the chi-square(2) quantile of 1 - ``STRAY_PROBABILITY`` (27.6):

    r_k = (z_k - A_k p)^T R_k^-1 (z_k - A_k p),     chi2_min = min_p sum_k min(r_k, c)

(a truncated quadratic: the log of a Gaussian-plus-uniform-clutter mixture taken as its larger term, the
clutter level set at c, so a contact that far off the fit counts as a stray one; no source among the project's
papers: the truncated-quadratic M-estimator of robust regression, Hampel et al., Robust Statistics, 1986).
Its minimum over p is searched from the fit of the track's own contacts and from the fit of all: the kept
contact of the largest r_k >= c is left out and the rest refitted, one at a time, then every contact under the
cap is taken back, until the kept set repeats (a local minimum; on small sets within 1 of the brute-force global
one, tests). Without the cap one stray contact (clutter, another target's echo) adds a chi-square of 10^3-10^5
to either hypothesis at random, and that decides the ratio, not the turn; with it a stray contact and its mirror
cost c each and cancel, and a contact moves ln LR by about c / 2 at most. The cap is not the 99 % gate (9.2):
near the turn the contacts are off by more than R says (a 24-element array: the approacher's 60-140 m off, sd
50-60 m), and at 9.2 a target's own contacts counted as strays, the turn's evidence was lost and once (seed 8) a
true track was called a ghost for two pings.
A track confirmed after the turn has no turn in its own life, so when a track is first confirmed the last
``lookback`` pings are searched backwards for its target (retrodiction), under both hypotheses alike: the
track's state x (its side) and its mirror M x about the array's axis at confirmation (the other side: M
reflects positions about the axis through the midpoint of a mirror pair, velocities about its direction) are
each run back ping by ping with the CV model, x_k = F(t_k - t_k+1) x_k+1, P_k = F P F^T + Q(|t_k - t_k+1|);
per ping each takes the contact nearest it (chi-square distance with P_k + R) inside its gate, is updated
with it (Kalman), and the two contacts of that detection enter the two sequences (the one on the track's side,
taken by the track's hypothesis or the mirror of the one the mirror hypothesis took, and the other);
the search stops after ``MAX_MISSES`` pings in a row with no contact in either gate. A track on its target's
side so finds the target's contacts from before the turn, whose mirrors no CV motion explains; a ghost's
mirror hypothesis finds them, and the ghost's own side holds only their mirrors about the old axis. Both
hypotheses are searched alike and the chi-squares capped because a gate run back over many pings is kilometres
wide: the nearest contact in it is often stray, chosen for lying near that hypothesis's line; a search of the
track's side alone, uncapped, gave a ghost a made-up past that fitted its line and a ratio in the tens of
thousands (a ghost of the approacher on a 24-element array, seed 7, called its target's side at ln LR +38807).
A target's track is often lost and a new one confirmed later (re-joined to it), or two tracks hold it and one is
deleted as the other's duplicate (tracking/duplicates.py): the chain lists them as one target (``ActiveTracks.joins``,
targets.py), and the evidence goes with the join (:meth:`SideTracker.carry`): the earlier segment's contacts, at the
pings the later track holds none, become a piece of its evidence. Each hypothesis's log-likelihood is then the larger,
less Schwarz's penalty (k / 2) ln n (Schwarz, "Estimating the dimension of a model", Ann. Statist. 6, 1978; k = 4
parameters per CV motion, n = 2 per contact), of one CV motion through every piece and one per piece (a maneuver
while no track held the target); a piece over which the array turned less than ``min_turn`` fits both hypotheses
alike. So two segments before and after the turn decide once joined, up to the evidence ~(k / 2) ln n that a
maneuver in the gap could also explain, and a segment that decided keeps deciding after a maneuver. Before, a
track re-joined after the turn began undecided (ln LR 0): at full size (study active-chain, e4c2ec6) 3 of the 9
targets judged wrong ended so (benchmarks/bench_active_sides.py).
The side is decided when |ln LR| >= ``min_log_lr`` (ln 100 by default, the passive chain's 100:1) once the
track has lived through ``min_turn_rad`` of change of the array's heading: ln LR > 0 says the track is on
its target's side; < 0 that the track is the mirror of a target on the other side (a ghost).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.systems.active.side_fit import CvFit as _CvFit  # noqa: N814 - its name here
from sonartrack.systems.active.side_fit import _kalman_update, _predict  # noqa: F401 - _predict: contact_tracker.py
from sonartrack.systems.active.side_fit import reachable as _reachable

#: the side is decided at a likelihood ratio of 100:1 (the passive chain's threshold, tma/sides.py)
MIN_LOG_LR = float(np.log(100.0))
#: fewest contacts of a track before its ratio is computed (the CV fit has 4 parameters; 2 per contact)
MIN_CONTACTS = 3
#: the retrodiction looks for a target detected on at least this share of pings (the study's hardest targets: trial 2,
#: K clutter, 0.41 of its echoes detected on the pings counted, KDIAG)
RETRO_DETECTION_PROBABILITY = 0.4
#: ... and stops early on such a target with at most this probability. 0.22 (3 misses), measured against 0.08 (5) and
#: 0.02 (8): each ping looked back is one more chance of taking a stray into the fit (benchmarks/bench_side_errors.py,
#: 60 worlds a setting, Pd 0.4, confirmed after the turn, clutter 2 and 6 a ping: wrong decisions 0 of 72 at 3
#: misses, 2 of 168 at 5, 7 of 185 at 8), and through a maneuvering target's own turn the one-CV fit decides wrong:
#: at 5, the full-size study active-chain (20 runs) had sides right 0.83 of 29 (session 12's run: 0.70) but lost
#: real CW tracks to the ghost and merge deleters (trial 9 crossing-a held 21 -> 11 counted pings, RMSE after the
#: turn 503 -> 912 m; trial 11's maneuvering target 45 -> 34 and its turn; CW held 0.82 -> 0.77 on trials 9 and 11).
#: An undecided side is the honest answer; a real track deleted is not. A maneuver-aware fit would look further.
RETRO_STOP_PROBABILITY = 0.22
#: the retrodiction stops at this many pings in a row with no contact in either hypothesis's gate: the fewest n with
#: (1 - Pd)^n <= RETRO_STOP_PROBABILITY (3)
MAX_MISSES = int(np.ceil(np.log(RETRO_STOP_PROBABILITY) / np.log(1.0 - RETRO_DETECTION_PROBABILITY)))
#: a ratio under the threshold + the cap must stay decided with any one of the track's contacts left out
#: (:meth:`SideTracker._rests_on_more_than_one`). bench_side_errors.py, 60 worlds a setting, Pd 0.4, confirmed after
#: the turn, clutter 2 / 6 per ping: wrong 2.1 % / 5.5 % of decisions without it, 0 % / 2.8 % with it; the study's
#: trials 0 2 4 7 8 14 15 18 (bench_active_sides.py): 16 -> 14 right of 20 (two right approachers at 30.4 and 12.7
#: rest on one contact); off: bench_active_rows.py CW seed 2 false rows 1 -> 3 with it (decisions held back, ghosts
#: and false tracks not removed)
LEAVE_ONE_OUT = False
#: a contact's chi-square in the CV fit is capped at its chi-square(2) quantile of 1 - this (27.6): a stray one
STRAY_PROBABILITY = 1e-6
#: two confirmed tracks are mirror twins when they took the two contacts of one detection on this many pings (the
#: pair with the most such pings wins): 1, not 2, so that a pair confirmed together is one target from its first
#: ping (the default scene as CW, seed 1: a pair confirmed on the last ping was listed as two rows)
MIN_TWIN_PINGS = 1
#: a confirmed track that took the mirror contacts of a track decided on its target's side on this many pings is
#: that target's ghost too, twin or not (study trial 7: a second ghost, twin of an undecided duplicate of the decided
#: track, 6 such pings, stayed on the mirror to the end); two targets' tracks share a detection's two contacts only
#: while one crosses the other's mirror, for a ping or two
MIN_MIRROR_PINGS = 3


@dataclass(frozen=True, slots=True)
class SideDecisions:
    """One row per confirmed track: ``track_id``; ``decision`` "track" (the track is on its target's side),
    "mirror" (the track is a ghost: its target is on the other side) or "undecided"; ``side`` the side of the
    array (port | starboard) the target is judged on (the track's side at its last update, the other one for a
    ghost, "" when undecided); ``log_lr`` ln LR at the track's last contact; ``resolved_s`` the ping time (s)
    from which |ln LR| stayed above the threshold with the final sign (NaN: never); ``contacts`` the number of
    contacts in the fit (with those carried from joined segments); ``twin`` the confirmed track on this one's
    mirror (the track that took the other contact of the same detections on at least ``MIN_TWIN_PINGS`` pings, the
    most such pings), -1 when none."""

    track_id: np.ndarray
    decision: np.ndarray
    side: np.ndarray
    log_lr: np.ndarray
    resolved_s: np.ndarray
    contacts: np.ndarray
    twin: np.ndarray

    def __len__(self) -> int:
        return len(self.track_id)

    def of(self, track_id: int) -> int | None:
        """The first row of the track ``track_id`` (None: not a confirmed track)."""
        hit = np.nonzero(self.track_id == track_id)[0]
        return int(hit[0]) if len(hit) else None


def _mate(contacts, row: int) -> int | None:
    """The other contact of ``row``'s detection (None: it has none)."""
    other = np.nonzero((contacts.detection == contacts.detection[row]) & (np.arange(len(contacts)) != row))[0]
    return int(other[0]) if len(other) else None


def _axis_point(contacts) -> np.ndarray | None:
    """A point of the array's axis: the midpoint of a mirror pair (its two contacts lie symmetric about the axis
    through the receiver); None when the ping has no pair."""
    for row in range(len(contacts)):
        other = _mate(contacts, row)
        if other is not None:
            return 0.5 * (contacts.xy[row] + contacts.xy[other])
    return None


def _reflection(heading_rad: float) -> np.ndarray:
    """2 x 2 reflection about an axis of heading ``heading_rad`` (clockwise from north, x east): 2 a a^T - I."""
    a = np.array([np.sin(heading_rad), np.cos(heading_rad)])
    return 2.0 * np.outer(a, a) - np.eye(2)


class SideTracker:
    """The running side decision of every confirmed track (module doc).

    Parameters
    ----------
    gate_probability : float
        A contact is a track's when inside its chi-square(2) gate with S = P_xy + R (the nearest one per ping).
    min_turn_rad : float
        Change of the array's heading a track must have lived through before its side is decided (rad).
    min_log_lr : float
        |ln LR| at which the side is decided.
    q : float
        Process-noise intensity of the retrodiction (m^2/s^3).
    lookback : int
        Pings looked back over when a track is first confirmed (0: none).
    """

    def __init__(self, gate_probability: float = 0.99, min_turn_rad: float = 0.0, min_log_lr: float = MIN_LOG_LR,
                 q: float = 0.05, lookback: int = 40):
        from collections import deque

        from sonartrack.association.gating import gate_threshold

        self.gamma = gate_threshold(gate_probability, 2)
        self.cap = gate_threshold(1.0 - STRAY_PROBABILITY, 2)
        self.min_turn, self.min_log_lr, self.q = float(min_turn_rad), float(min_log_lr), float(q)
        self._past = deque(maxlen=max(int(lookback), 1))
        self._lookback = int(lookback)
        self._sums: dict[int, tuple[_CvFit, _CvFit]] = {}
        self._t0: dict[int, float] = {}
        self._h0: dict[int, float] = {}
        self._turned: dict[int, bool] = {}
        self._history: dict[int, list[tuple[float, float]]] = {}
        self._last_side: dict[int, int] = {}
        self._shared: dict[tuple[int, int], int] = {}  # (track, track) -> pings they took one detection's mirrors
        self._twins: dict[int, int] = {}
        self._pieces: dict[int, list[tuple[_CvFit, _CvFit]]] = {}  # track -> the joined segments' contacts
        self._search: dict[int, float] = {}  # track -> ln of the retrodiction's choices (:meth:`threshold`)
        self._loo: dict[int, tuple[int, float]] = {}  # track -> (contacts, ln LR with its weakest contact left out)
        self._now = np.nan  # the last ping's time (s)

    def update(self, t_s: float, heading_rad: float, contacts, track_ids, x, P, sides_of) -> None:
        """Add this ping's contacts of the confirmed tracks.

        Parameters
        ----------
        t_s : float
            Ping time (s).
        heading_rad : float
            The array's heading at the ping (rad, unwrapped).
        contacts : Contacts
            The ping's mirror-pair contacts (all of them, both sides).
        track_ids, x, P : arrays (n,), (n, 4), (n, 4, 4)
            The confirmed tracks after the ping's update.
        sides_of : callable
            ``sides_of(t_s, xy (n, 2)) -> (n,)`` +1 starboard / -1 port of the array.
        """
        self._now = float(t_s)
        if len(track_ids):
            self._update(t_s, heading_rad, contacts, track_ids, x, P, sides_of(t_s, np.asarray(x)[:, :2]))
        if self._lookback:
            self._past.append((float(t_s), float(heading_rad), contacts))

    def _retrodict(self, tid: int, t_s: float, heading_rad: float, contacts, x, P) -> None:
        """Seed a newly confirmed track's contact sequences with the detections of the last pings (module doc): a
        backward CV filter for each hypothesis, the track's state and its mirror's, takes per ping its nearest
        contact, and that detection's two contacts go to the sequences of both."""
        seqs = self._sums.setdefault(tid, (_CvFit(self.cap), _CvFit(self.cap)))
        self._t0[tid] = t_s
        origin = _axis_point(contacts)
        if not self._lookback or origin is None:
            return
        M = _reflection(heading_rad)
        Mx = np.kron(np.eye(2), M)
        hyps = [(np.array(x, float), np.array(P, float)),
                (np.concatenate([origin + M @ (x[:2] - origin), M @ x[2:]]), Mx @ P @ Mx.T)]
        t_prev, misses = t_s, 0
        for tp, hp, cp in reversed(self._past):
            hyps = [_predict(xh, Ph, tp - t_prev, self.q) for xh, Ph in hyps]
            t_prev = tp
            picks = [self._nearest(cp, *hyps[h]) for h in (0, 1)]
            if any(k is not None for k in picks):
                self._search[tid] = self._search.get(tid, 0.0) + np.log(self._choices(cp, hyps))
            misses = 0 if any(k is not None for k in picks) else misses + 1
            if misses >= MAX_MISSES:
                break
            taken = set()
            for h, row in enumerate(picks):
                mate = None if row is None else _mate(cp, row)
                if mate is None:
                    continue
                hyps[h] = _kalman_update(*hyps[h], cp.xy[row], cp.R[row])
                if int(cp.detection[row]) in taken:
                    continue
                taken.add(int(cp.detection[row]))
                own, mirror = (row, mate) if h == 0 else (mate, row)
                self._h0[tid] = hp
                seqs[0].add(tp - t_s, cp.xy[own], cp.R[own], False, tp, hp)
                seqs[1].add(tp - t_s, cp.xy[mirror], cp.R[mirror], False, tp, hp)

    def _choices(self, contacts, hyps) -> int:
        """The number of detections with a contact inside either hypothesis's gate: the retrodiction chose its
        pair among them (at least 1)."""
        inside = np.zeros(len(contacts), bool)
        for xh, Ph in hyps:
            nu = contacts.xy - xh[:2]
            inside |= np.einsum("mi,mi->m", nu, np.linalg.solve(Ph[:2, :2][None] + contacts.R, nu[..., None])[..., 0]) \
                < self.gamma
        return max(len(np.unique(np.asarray(contacts.detection)[inside])), 1)

    def threshold(self, track_id: int) -> float:
        """|ln LR| at which the track ``track_id`` is decided: ``min_log_lr`` plus ln M, M the number of contact
        sequences its retrodiction (and its carried segments') chose among (the product over the pings looked back
        of the detections inside either hypothesis's gate). The ratio of the chosen sequences is the largest of M
        ratios; under the wrong hypothesis each is >= 100 M with probability <= 1 / (100 M) (E[LR] = 1, Markov;
        Wald, Sequential Analysis, 1947, eq. 3:31), so by the union bound the largest with probability <= 1 / 100.
        With no clutter in the gates (M = 1) it is ``min_log_lr``."""
        return self.min_log_lr + self._search.get(int(track_id), 0.0)

    def _nearest(self, contacts, xh, Ph) -> int | None:
        """The contact of the smallest chi-square distance to a state (x_h, P_h + R), inside the gate (None:
        none)."""
        if not len(contacts):
            return None
        nu = contacts.xy - xh[:2]
        d2 = np.einsum("mi,mi->m", nu, np.linalg.solve(Ph[:2, :2][None] + contacts.R, nu[..., None])[..., 0])
        k = int(np.argmin(d2))
        return k if d2[k] < self.gamma else None

    def _update(self, t_s, heading_rad, contacts, track_ids, x, P, side) -> None:
        took: dict[int, list[tuple[int, int]]] = {}  # detection -> [(track, side of the contact it took)]
        for k, tid in enumerate(np.asarray(track_ids).tolist()):
            if tid not in self._sums:
                self._retrodict(tid, t_s, heading_rad, contacts, np.asarray(x[k], float), np.asarray(P[k], float))
            self._h0.setdefault(tid, heading_rad)
            self._turned[tid] = self._turned.get(tid, False) or abs(heading_rad - self._h0[tid]) >= self.min_turn
            self._last_side[tid] = int(side[k])
            pair = self._pair(contacts, x[k], P[k])
            if pair is None:
                continue
            own, mirror = pair
            self._count_twins(took.setdefault(int(contacts.detection[own]), []), tid, int(contacts.side[own]))
            t0 = self._t0.setdefault(tid, t_s)
            sums = self._sums.setdefault(tid, (_CvFit(self.cap), _CvFit(self.cap)))
            sums[0].add(t_s - t0, contacts.xy[own], contacts.R[own], True, t_s, heading_rad)
            sums[1].add(t_s - t0, contacts.xy[mirror], contacts.R[mirror], True, t_s, heading_rad)
            if sums[0].n >= MIN_CONTACTS or tid in self._pieces:
                self._history.setdefault(tid, []).append((t_s, self._log_lr(tid)))
        self._twins = self.twins()

    def _count_twins(self, took: list[tuple[int, int]], tid: int, side: int) -> None:
        """Count one ping on which ``tid`` and each track in ``took`` took the two mirror contacts of a detection."""
        for other, other_side in took:
            if other != tid and other_side != side:
                key = (min(other, tid), max(other, tid))
                self._shared[key] = self._shared.get(key, 0) + 1
        took.append((tid, side))

    def _pair(self, contacts, x, P) -> tuple[int, int] | None:
        """(own, mirror) rows: the contact nearest the track inside its gate, and the other of its detection."""
        if not len(contacts):
            return None
        nu = contacts.xy - x[:2]
        S = P[:2, :2][None] + contacts.R
        d2 = np.einsum("mi,mi->m", nu, np.linalg.solve(S, nu[..., None])[..., 0])
        best = int(np.argmin(d2))
        if d2[best] >= self.gamma:
            return None
        other = _mate(contacts, best)
        return None if other is None else (best, other)

    def decision(self, track_id: int) -> int:
        """+1 the track ``track_id`` is on its target's side, -1 a ghost, 0 undecided so far: the sign of the
        track's latest ln LR when its magnitude is at least ``min_log_lr``, else 0 (also for a track with no
        history). When the track and its mirror twin are BOTH decided on their side (one target cannot be on both:
        deciding both made GhostDeleter delete both, benchmarks/bench_active_turns.py, CW seed 2: 6 of 9 turn scenes
        lost their target's track at its side decision, ln LR 9.9 and 12.1 for the pair), the pair's two views are
        averaged, (ln LR_track - ln LR_twin) / 2 (each one's ratio is the other's with the sign turned when their
        evidence agrees): the track is decided by that one's sign when it reaches ``min_log_lr``, else neither
        (9.9 and 12.1: neither; a track re-joined onto a false track's evidence, bench_active_sides.py trial 15, 31.2
        against its twin's 280.6: the twin on its side, the track its mirror). Twins BOTH decided ghosts contradict
        alike (of a detection's two contacts one is the echo's) and are judged by the same average (study trial 7,
        the maneuvering target's track -29.8 from 11 contacts and its twin -34.6 from 15: neither)."""
        h = self._history.get(int(track_id))
        thr = self.threshold(track_id)
        if not h or abs(h[-1][1]) < thr:
            return 0
        lr = h[-1][1]
        if LEAVE_ONE_OUT and abs(lr) < thr + self.cap and not self._rests_on_more_than_one(int(track_id), lr, thr):
            return 0
        twin = self._twins.get(int(track_id))
        t = self._history.get(twin) if twin is not None else None
        if t and abs(t[-1][1]) >= self.threshold(twin) and np.sign(t[-1][1]) == np.sign(lr):  # they contradict
            pair = 0.5 * (lr - t[-1][1])
            return int(np.sign(pair)) if abs(pair) >= max(thr, self.threshold(twin)) else 0
        return 1 if lr > 0 else -1

    def _rests_on_more_than_one(self, tid: int, lr: float, thr: float) -> bool:
        """Whether ``lr`` stays decided (|ln LR| >= ``thr``, its sign) with any one of the track's own contacts left
        out. One stray contact can move a capped ln LR by up to the cap c (27.6; module doc), so a ratio under
        ``thr`` + c may rest on one contact (a hand-built world, bench_side_errors.py: a track decided the mirror at
        -9.2 on 8 contacts found by retrodiction through clutter). Checked on the track's own sequences (a track with
        joined pieces, or no sequences: True; MIN_CONTACTS or fewer: False)."""
        own = self._sums.get(tid)
        if tid in self._pieces or own is None:
            return True
        if own[0].n <= MIN_CONTACTS:
            return False
        n = own[0].n
        if self._loo.get(tid, (-1, 0.0))[0] != n:
            worst = np.inf
            for k in range(n):
                keep = [j for j in range(n) if j != k]
                v = own[0].subset(keep).log_likelihood() - own[1].subset(keep).log_likelihood()
                worst = min(worst, np.sign(lr) * v)
            self._loo[tid] = (n, float(worst))
        return self._loo[tid][1] >= thr

    def carry(self, into: int, source: int) -> None:
        """The track ``source`` is an earlier segment of ``into``'s target on the same side (joined after its loss,
        or deleted as ``into``'s duplicate: ActiveTracks.joins): its contacts, at the pings ``into`` holds none,
        become a piece of ``into``'s evidence, with its own CV motion (module doc), and ``into``'s ln LR is from now
        its own plus its pieces'. ``source``'s own pieces come with it (a chain of joins). A piece that cannot be
        ``into``'s object under either hypothesis (side_fit.py ``reachable``: its contacts, or their mirrors, out of
        reach of ``into``'s at ``MAX_SPEED_MPS``) is not carried: a false track merged into a ghost (study trial 15)
        gave the ghost the false track's +77.7, and the target on the other side was judged wrong."""
        into, source = int(into), int(source)
        if into == source or source not in self._sums:
            return
        own = self._sums.get(into)
        taken = set(own[0].at) if own is not None else set()
        for p in self._pieces.get(into, ()):
            taken.update(p[0].at)
        pieces = self._pieces.setdefault(into, [])
        n_before = len(pieces)
        refs = ([own] if own is not None else []) + list(pieces)
        for a, b in [self._sums[source], *self._pieces.get(source, ())]:
            keep = [k for k, t in enumerate(a.at) if t not in taken]
            piece = (a.subset(keep), b.subset(keep)) if keep else None
            # one object under either hypothesis: a ghost's own contacts jump while the array turns, its mirrors not
            if piece is not None and any(_reachable(piece[h], [r[h] for r in refs]) for h in (0, 1)):
                pieces.append(piece)
                refs.append(piece)
                taken.update(a.at[k] for k in keep)
        if len(pieces) > n_before:  # the carried segments' retrodiction choices come with their contacts
            self._search[into] = self._search.get(into, 0.0) + self._search.get(source, 0.0)
        if np.isfinite(self._now):
            self._history.setdefault(into, []).append((self._now, self._log_lr(into)))

    def _fits(self, tid: int) -> list[tuple[_CvFit, _CvFit]]:
        """The track's own contact sequences and its pieces', each ping once (a piece's contacts at the pings its
        own hold, e.g. found again by its retrodiction after a carry at its first confirmed scan, left out)."""
        own = self._sums.get(tid)
        out = [own] if own is not None and own[0].n else []
        taken = set(own[0].at) if own is not None else set()
        for a, b in self._pieces.get(tid, ()):
            keep = [k for k, t in enumerate(a.at) if t not in taken]
            if keep:
                out.append((a, b) if len(keep) == a.n else (a.subset(keep), b.subset(keep)))
        return out

    def _log_lr(self, tid: int) -> float:
        """ln LR of the track ``tid`` now: of its own contacts (0 before ``MIN_CONTACTS`` or the turn); with joined
        segments' pieces (:meth:`carry`), each hypothesis's log-likelihood is the larger of two models', each less
        Schwarz's (1978) penalty (k / 2) ln n (k = 4 parameters per CV motion, n = 2 per contact): one CV motion
        through every piece, or one per piece (a maneuver in a gap); a piece (or the whole) over which the array
        turned less than ``min_turn`` fits both hypotheses alike (the larger of its two log-likelihoods for both)."""
        if tid not in self._pieces:
            own = self._sums[tid]
            ok = own[0].n >= MIN_CONTACTS and self._turned.get(tid, False)
            return own[0].log_likelihood() - own[1].log_likelihood() if ok else 0.0
        fits = self._fits(tid)
        if not fits:
            return 0.0
        whole = tuple(_CvFit.joined([f[h] for f in fits]) for h in (0, 1))
        if whole[0].turn_rad() < self.min_turn:
            return 0.0
        ln_n = np.log(2.0 * whole[0].n)
        per = [(f[0].log_likelihood(), f[1].log_likelihood()) for f in fits]
        per = [(max(p),) * 2 if f[0].turn_rad() < self.min_turn else p for f, p in zip(fits, per, strict=True)]
        best = [max(whole[h].log_likelihood() - 2.0 * ln_n, sum(p[h] for p in per) - 2.0 * len(fits) * ln_n)
                for h in (0, 1)]
        return best[0] - best[1]

    def twins(self) -> dict[int, int]:
        """Mirror twins: track -> the confirmed track that took the other contact of the same detection on the most
        pings (at least ``MIN_TWIN_PINGS``), each track in one pair at most (pairs taken by decreasing count).

        Returns
        -------
        dict
            Both directions of each pair (a -> b and b -> a).
        """
        out: dict[int, int] = {}
        for (a, b), n in sorted(self._shared.items(), key=lambda kv: (-kv[1], kv[0])):
            if n >= MIN_TWIN_PINGS and a not in out and b not in out:
                out[a], out[b] = b, a
        return out

    def twin_of(self, track_id: int) -> int | None:
        """The mirror twin of ``track_id`` (:meth:`twins`), None when it has none."""
        return self._twins.get(int(track_id))

    def flip(self, track_id: int) -> None:
        """The track ``track_id`` has been reflected onto the other side (:class:`GhostDeleter`): its two contact
        sequences swap, its ln LR history changes sign and it is no one's twin any more (it now lies on its former
        twin's side), so it is no longer a rejected track."""
        tid = int(track_id)
        self._shared = {k: n for k, n in self._shared.items() if tid not in k}
        self._twins = self.twins()
        if tid in self._sums:
            self._sums[tid] = self._sums[tid][::-1]
        if tid in self._pieces:
            self._pieces[tid] = [p[::-1] for p in self._pieces[tid]]
        self._history[tid] = [(t, -lr) for t, lr in self._history.get(tid, [])]
        if tid in self._last_side:
            self._last_side[tid] = -self._last_side[tid]

    def rejected(self, track_id: int) -> bool:
        """True when ``track_id`` is the rejected hypothesis of a decided target: decided a ghost itself, the mirror
        twin (:meth:`twins`) of a track decided on its target's side, or a track that took such a track's mirror
        contacts on ``MIN_MIRROR_PINGS`` pings.

        Parameters
        ----------
        track_id : int
            The track's id.

        Returns
        -------
        bool
            Whether the track is a decided target's mirror.
        """
        tid = int(track_id)
        twin = self._twins.get(tid)
        if self.decision(tid) < 0 or (twin is not None and self.decision(twin) > 0):
            return True
        return any(n >= MIN_MIRROR_PINGS and tid in pair and self.decision(pair[pair[0] == tid]) > 0
                   for pair, n in self._shared.items())

    def result(self) -> SideDecisions:
        """Every confirmed track's decision (:class:`SideDecisions`).

        Returns
        -------
        SideDecisions
            One row per track seen confirmed, by increasing id; ``resolved_s`` in s.
        """
        ids = sorted(self._h0)
        twins = self.twins()
        dec, side, lr, when, n = [], [], [], [], []
        for tid in ids:
            h = np.array(self._history.get(tid, []), float).reshape(-1, 2)
            d = self.decision(tid)
            dec.append({1: "track", -1: "mirror", 0: "undecided"}[d])
            s = self._last_side[tid] * d
            side.append("" if d == 0 else ("starboard" if s > 0 else "port"))
            lr.append(float(h[-1, 1]) if len(h) else 0.0)
            n.append(sum(f[0].n for f in self._fits(tid)))
            ok = d * h[:, 1] >= self.threshold(tid) if d else np.zeros(len(h), bool)
            bad = np.nonzero(~ok)[0]
            start = bad[-1] + 1 if len(bad) else 0
            when.append(float(h[start, 0]) if d and start < len(h) else float("nan"))
        return SideDecisions(np.array(ids, np.int64), np.array(dec, dtype=object), np.array(side, dtype=object),
                             np.array(lr), np.array(when), np.array(n, np.int64),
                             np.array([twins.get(i, -1) for i in ids], np.int64))


class GhostDeleter:
    """A deleter part that runs ``inner`` and then acts on every track ``sides`` has rejected, so that a decided
    target is held by one track on its side (issue 34 item 4):

    * the rejected mirror of a target whose track on its side is alive (the track is decided a ghost, or is the twin
      of a live track decided on its target's side) is deleted at the scan after the decision instead of starving;
    * a rejected track with no live twin (decided a ghost itself, or the twin of a dead track decided on its
      target's side; its target was only confirmed on the wrong side, e.g. a track first
      confirmed after the array's turn, whose retrodiction (module doc) decides it the mirror at once) is reflected
      onto its target's side: its state x -> (p_a + M (p - p_a), M v) and covariances P -> M4 P M4^T (M the
      reflection about the array's axis through the receiver p_a at this scan, M4 = diag(M, M)), and its side
      evidence swapped (:meth:`SideTracker.flip`), so it goes on as the target's track with its identity and its
      confirmation. Deleting it instead (as before) left the target unheld until a new track on its side was
      confirmed 2-10 pings later and listed it twice (the default scene, seed 1, LFM: crossing-b as 3 rows, two of
      them a ghost that lived one ping).

    Parameters
    ----------
    inner : deleter part
        The tracker's own deleter (tracking/deleters.py, or a wrapper of it).
    sides : SideTracker
        The running side decisions.
    """

    def __init__(self, inner, sides: SideTracker):
        self.inner, self.sides = inner, sides
        self.axis: tuple[np.ndarray, float] | None = None  # (receiver xy m, array heading rad) of the scan

    def new_track_attrs(self, k: int) -> dict:
        """The inner deleter's per-track counters (``inner.new_track_attrs(k)``)."""
        return self.inner.new_track_attrs(k)

    def _merged(self) -> dict:
        """The duplicate merger's record (tracking/duplicates.py ``DuplicateMerger.merged``: deleted confirmed track
        -> the track kept) found down the ``inner`` chain; an empty dict when there is no merger."""
        d = self.inner
        while d is not None and not isinstance(getattr(d, "merged", None), dict):
            d = getattr(d, "inner", None)
        return d.merged if d is not None else {}

    def manage(self, T, hit):
        """The inner deleter's confirmation and deletion, then the rejected tracks deleted or reflected (TrackArrays
        in and out)."""
        from dataclasses import replace

        merged = self._merged()
        before = dict(merged)
        T = self.inner.manage(T, hit)
        for gone in merged.keys() - before.keys():  # a duplicate deleted: its side evidence goes to the kept track
            self.sides.carry(merged[gone], gone)
        if not len(T):
            return T
        live = set(T.track_id.tolist())
        drop, flip = np.zeros(len(T), bool), np.zeros(len(T), bool)
        for k, tid in enumerate(T.track_id.tolist()):
            if self.sides.rejected(tid):
                twin = self.sides.twin_of(tid)
                drop[k] = (twin is not None and twin in live) or self.axis is None  # no axis: deleted, as before
                flip[k] = not drop[k]
        if flip.any():
            rx, heading = self.axis
            M = _reflection(heading)
            M4 = np.kron(np.eye(2), M)
            x, P = T.x.copy(), T.P.copy()
            x[flip, :, :2] = rx + (x[flip, :, :2] - rx) @ M.T
            x[flip, :, 2:] = x[flip, :, 2:] @ M.T
            P[flip] = M4 @ P[flip] @ M4.T
            T = replace(T, x=x, P=P)
            for tid in T.track_id[flip].tolist():
                self.sides.flip(int(tid))
        return T.select(~drop) if drop.any() else T
