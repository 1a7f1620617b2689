"""The live tracks of a multi-target tracker as stacked arrays, and what a scan hands back.

All tracks are held together (axis n), each with its mode-conditioned states (axis r, the IMM modes;
r = 1 for a single model), so every part of the tracker works on whole arrays. Parts that need
per-track quantities of their own (a bearing track's sigma_p and amplitude strength, the M-of-N
counters) keep them in ``attrs``, a dict of (n, ...) arrays that is selected and appended with the rest.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from sonartrack.core.linalg import symmetrize


@dataclass(frozen=True, slots=True)
class Scan:
    """One scan of measurements: ``z (m, k)`` with the state's first k entries measured.

    ``R (m, k, k)`` per-measurement covariances (position contacts) or None when the measurement model
    takes them from the tracks (bearing peaks); ``amplitude (m,)`` peak amplitudes or None."""

    time_s: float
    z: np.ndarray
    R: np.ndarray | None = None
    amplitude: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.z)


@dataclass(frozen=True, slots=True)
class TrackArrays:
    """n tracks, r modes, state dimension d."""

    x: np.ndarray  # (n, r, d) mode-conditioned states
    P: np.ndarray  # (n, r, d, d)
    mu: np.ndarray  # (n, r) mode probabilities
    existence: np.ndarray  # (n,) existence probability (NaN without an existence model)
    confirmed: np.ndarray  # (n,) bool
    track_id: np.ndarray  # (n,) int
    born_s: np.ndarray  # (n,) time of initiation
    P_init: np.ndarray  # (n, d, d) covariance at initiation (CTT test, P4 eq. 23)
    attrs: dict = field(default_factory=dict)  # name -> (n, ...) per-track quantities of the parts

    @classmethod
    def empty(cls, r: int, d: int) -> TrackArrays:
        """No tracks, with r modes and state dimension d.

        Parameters
        ----------
        r : int
            Modes.
        d : int
            State dimension.

        Returns
        -------
        TrackArrays
            Zero-length arrays of the right trailing shapes.
        """
        return cls(np.zeros((0, r, d)), np.zeros((0, r, d, d)), np.zeros((0, r)), np.zeros(0), np.zeros(0, bool),
                   np.zeros(0, np.int64), np.zeros(0), np.zeros((0, d, d)))

    def __len__(self) -> int:
        return len(self.track_id)

    def select(self, keep: np.ndarray) -> TrackArrays:
        """The tracks where ``keep``.

        Parameters
        ----------
        keep : ndarray of bool, shape (n,), or of int
            Mask or indices.

        Returns
        -------
        TrackArrays
            Those tracks, ``attrs`` included.
        """
        return TrackArrays(self.x[keep], self.P[keep], self.mu[keep], self.existence[keep], self.confirmed[keep],
                           self.track_id[keep], self.born_s[keep], self.P_init[keep],
                           {k: v[keep] for k, v in self.attrs.items()})

    def append(self, new: TrackArrays) -> TrackArrays:
        """The concatenation, a new :class:`TrackArrays`: these tracks followed by the tracks ``new`` (both must carry
        the same ``attrs`` names)."""
        if not len(new):
            return self
        if not len(self):
            return new
        cat = np.concatenate
        return TrackArrays(cat([self.x, new.x]), cat([self.P, new.P]), cat([self.mu, new.mu]),
                           cat([self.existence, new.existence]), cat([self.confirmed, new.confirmed]),
                           cat([self.track_id, new.track_id]), cat([self.born_s, new.born_s]),
                           cat([self.P_init, new.P_init]), {k: cat([v, new.attrs[k]]) for k, v in self.attrs.items()})

    def with_attrs(self, **updates) -> TrackArrays:
        """The same tracks with some ``attrs`` entries replaced.

        Parameters
        ----------
        **updates : ndarray, shape (n, ...)
            New per-track quantities by name.

        Returns
        -------
        TrackArrays
            A copy with the updated ``attrs``.
        """
        return replace(self, attrs={**self.attrs, **updates})


@dataclass(frozen=True, slots=True)
class TrackSnapshot:
    """The live tracks after a scan (n tracks, r modes): combined estimates and track management state."""

    time_s: float
    track_id: np.ndarray  # (n,)
    confirmed: np.ndarray  # (n,) bool
    existence: np.ndarray  # (n,) (NaN without an existence model)
    x: np.ndarray  # (n, d) combined estimate (the IMM output, not fed back)
    P: np.ndarray  # (n, d, d)
    mu: np.ndarray  # (n, r)
    P_init: np.ndarray  # (n, d, d) covariance at initiation (CTT test, P4 eq. 23)
    born_s: np.ndarray  # (n,)
    attrs: dict  # name -> (n, ...) per-track quantities of the parts (e.g. "strength")

    @classmethod
    def of(cls, time_s: float, T: TrackArrays) -> TrackSnapshot:
        """Snapshot of ``T`` with combined estimates (filters/imm.py).

        ``x = sum_r mu_r x_r``, ``P = sum_r mu_r (P_r + (x_r - x)(x_r - x)^T)``.

        Parameters
        ----------
        time_s : float
            Scan time (s).
        T : TrackArrays
            Live tracks.

        Returns
        -------
        TrackSnapshot
            Copies of the track management arrays and the combined estimates.
        """
        if T.mu.shape[1] == 1:  # one mode: the combination is the mode's estimate (symmetrized, as imm_combine)
            xc, Pc = T.x[:, 0].copy(), symmetrize(T.P[:, 0])
        elif len(T):
            from sonartrack.filters.imm_kernel import combine  # numba: loaded on first use

            xc, Pc = combine(T.mu, T.x, T.P)  # filters/imm.py's imm_combine, compiled (identical results)
        else:
            xc, Pc = np.zeros(T.x.shape[:1] + T.x.shape[2:]), np.zeros(T.P.shape[:1] + T.P.shape[2:])
        return cls(float(time_s), T.track_id.copy(), T.confirmed.copy(), T.existence.copy(), xc, Pc, T.mu.copy(),
                   T.P_init.copy(), T.born_s.copy(), {k: v.copy() for k, v in T.attrs.items()})
