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
The sums are kept per track and updated each ping, so the ratio is known at every ping at no growing cost.
A track confirmed after the turn has no turn in its own life, so when a track is first confirmed its contacts
are also looked for backwards over the last ``lookback`` pings (retrodiction: its state run back with the CV
model, x_k = F(t_k - t) x, P_k = F P F^T + Q(|t_k - t|), the nearest contact inside the chi-square(2) gate of
P_k + R per ping): a track on its target's side finds the target's contacts from before the turn, whose
mirrors no CV motion explains; a ghost finds little there (its past lies on the mirror of another axis).
The side is decided when |ln LR| >= ``min_log_lr`` (ln 100 by default, the passive chain's 100:1) once the
track has lived through ``min_turn_rad`` of change of the array's heading: ln LR > 0 says the track is on
its target's side; < 0 that the track is the mirror of a target on the other side (a ghost).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the side is decided at a likelihood ratio of 100:1 (the passive chain's threshold, tma/sides.py)
MIN_LOG_LR = float(np.log(100.0))
#: fewest contacts of a track before its ratio is computed (the CV fit has 4 parameters; 2 per contact)
MIN_CONTACTS = 3


@dataclass(frozen=True, slots=True)
class SideDecisions:
    """One row per confirmed track: ``track_id``; ``decision`` "track" (the track is on its target's side),
    "mirror" (the track is a ghost: its target is on the other side) or "undecided"; ``side`` the side of the
    array (port | starboard) the target is judged on (the track's side at its last update, the other one for a
    ghost, "" when undecided); ``log_lr`` ln LR at the track's last contact; ``resolved_s`` the ping time (s)
    from which |ln LR| stayed above the threshold with the final sign (NaN: never); ``contacts`` the number of
    contacts in the fit."""

    track_id: np.ndarray
    decision: np.ndarray
    side: np.ndarray
    log_lr: np.ndarray
    resolved_s: np.ndarray
    contacts: np.ndarray

    def __len__(self) -> int:
        return len(self.track_id)

    def of(self, track_id: int) -> int | None:
        """Row of ``track_id`` (None: not a confirmed track).

        Parameters
        ----------
        track_id : int
            The track's id.

        Returns
        -------
        int or None
            The first row with that id, or None.
        """
        hit = np.nonzero(self.track_id == track_id)[0]
        return int(hit[0]) if len(hit) else None


class _CvSums:
    """Running normal equations of the weighted CV fit of one contact sequence (module doc)."""

    __slots__ = ("info", "b", "zwz", "logdet", "n")

    def __init__(self):
        self.info, self.b, self.zwz, self.logdet, self.n = np.zeros((4, 4)), np.zeros(4), 0.0, 0.0, 0

    def add(self, dt_s: float, z, R) -> None:
        W = np.linalg.inv(R)
        A = np.hstack([np.eye(2), dt_s * np.eye(2)])
        self.info += A.T @ W @ A
        self.b += A.T @ W @ z
        self.zwz += float(z @ W @ z)
        self.logdet += float(np.log(np.linalg.det(2.0 * np.pi * R)))
        self.n += 1

    def log_likelihood(self) -> float:
        chi2 = self.zwz - float(self.b @ np.linalg.lstsq(self.info, self.b, rcond=None)[0])
        return -0.5 * (max(chi2, 0.0) + self.logdet)


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
        self.min_turn, self.min_log_lr, self.q = float(min_turn_rad), float(min_log_lr), float(q)
        self._past = deque(maxlen=max(int(lookback), 1))
        self._lookback = int(lookback)
        self._sums: dict[int, tuple[_CvSums, _CvSums]] = {}
        self._t0: dict[int, float] = {}
        self._h0: dict[int, float] = {}
        self._turned: dict[int, bool] = {}
        self._history: dict[int, list[tuple[float, float]]] = {}
        self._last_side: dict[int, int] = {}

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
        if len(track_ids):
            self._update(t_s, heading_rad, contacts, track_ids, x, P, sides_of(t_s, np.asarray(x)[:, :2]))
        if self._lookback:
            self._past.append((float(t_s), float(heading_rad), contacts))

    def _retrodict(self, tid: int, t_s: float, x, P) -> None:
        """Seed a newly confirmed track's sums with its contacts of the last pings (module doc)."""
        sums = self._sums.setdefault(tid, (_CvSums(), _CvSums()))
        self._t0[tid] = t_s
        for tp, hp, cp in self._past if self._lookback else ():
            dt = tp - t_s
            F = np.eye(4)
            F[0, 2] = F[1, 3] = dt
            Pk = F @ P @ F.T + self.q * np.kron(np.array([[abs(dt)**3 / 3, dt**2 / 2], [dt**2 / 2, abs(dt)]]),
                                                np.eye(2))
            pair = self._pair(cp, F @ x, Pk)
            if pair is not None:
                self._h0.setdefault(tid, hp)
                sums[0].add(dt, cp.xy[pair[0]], cp.R[pair[0]])
                sums[1].add(dt, cp.xy[pair[1]], cp.R[pair[1]])

    def _update(self, t_s, heading_rad, contacts, track_ids, x, P, side) -> None:
        for k, tid in enumerate(np.asarray(track_ids).tolist()):
            if tid not in self._sums:
                self._retrodict(tid, t_s, np.asarray(x[k], float), np.asarray(P[k], float))
            self._h0.setdefault(tid, heading_rad)
            self._turned[tid] = self._turned.get(tid, False) or abs(heading_rad - self._h0[tid]) >= self.min_turn
            self._last_side[tid] = int(side[k])
            pair = self._pair(contacts, x[k], P[k])
            if pair is None:
                continue
            own, mirror = pair
            t0 = self._t0.setdefault(tid, t_s)
            sums = self._sums.setdefault(tid, (_CvSums(), _CvSums()))
            sums[0].add(t_s - t0, contacts.xy[own], contacts.R[own])
            sums[1].add(t_s - t0, contacts.xy[mirror], contacts.R[mirror])
            if sums[0].n >= MIN_CONTACTS:
                lr = sums[0].log_likelihood() - sums[1].log_likelihood()
                self._history.setdefault(tid, []).append((t_s, lr if self._turned[tid] else 0.0))

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
        other = np.nonzero((contacts.detection == contacts.detection[best]) & (np.arange(len(contacts)) != best))[0]
        return (best, int(other[0])) if len(other) else None

    def decision(self, track_id: int) -> int:
        """+1 the track is on its target's side, -1 a ghost, 0 undecided (so far).

        Parameters
        ----------
        track_id : int
            The track's id.

        Returns
        -------
        int
            The sign of the track's latest ln LR when its magnitude is at least ``min_log_lr``, else 0 (also 0 for
            a track with no history).
        """
        h = self._history.get(int(track_id))
        if not h or abs(h[-1][1]) < self.min_log_lr:
            return 0
        return 1 if h[-1][1] > 0 else -1

    def result(self) -> SideDecisions:
        """Every confirmed track's decision (:class:`SideDecisions`).

        Returns
        -------
        SideDecisions
            One row per track seen confirmed, by increasing id; ``resolved_s`` in s.
        """
        ids = sorted(self._h0)
        dec, side, lr, when, n = [], [], [], [], []
        for tid in ids:
            h = np.array(self._history.get(tid, []), float).reshape(-1, 2)
            d = self.decision(tid)
            dec.append({1: "track", -1: "mirror", 0: "undecided"}[d])
            s = self._last_side[tid] * d
            side.append("" if d == 0 else ("starboard" if s > 0 else "port"))
            lr.append(float(h[-1, 1]) if len(h) else 0.0)
            n.append(self._sums[tid][0].n if tid in self._sums else 0)
            ok = d * h[:, 1] >= self.min_log_lr if d else np.zeros(len(h), bool)
            bad = np.nonzero(~ok)[0]
            start = bad[-1] + 1 if len(bad) else 0
            when.append(float(h[start, 0]) if d and start < len(h) else float("nan"))
        return SideDecisions(np.array(ids, np.int64), np.array(dec, dtype=object), np.array(side, dtype=object),
                             np.array(lr), np.array(when), np.array(n, np.int64))
