"""Multi-target IPDA / IMM-IPDA tracker with track management (false track discrimination).

One tracker class serves both: single-model IPDA is IMM-IPDA with one mode. Every track carries
its mode-conditioned states ``x (r, 4)``, covariances ``P (r, 4, 4)``, mode probabilities ``mu (r,)``
and existence probability; all tracks are held in stacked arrays and updated together, so the cost
per scan is a handful of NumPy calls, not a Python loop over tracks.

One scan (Park, Song, Lee 2017, Fig. 3 and eqs. 7-21; Musicki, Suvorova, Challa 2004):

1. interaction: predicted mode probabilities and mixed initial conditions (filters/imm.py)
2. prediction: constant-velocity Kalman prediction per mode with that mode's q (models/motion.py);
   existence by the Markov chain (association/ipda.py)
3. gating: union of the modes' chi-square gates
4. update: PDA per mode with per-measurement covariances, mode probabilities
   mu_r ∝ c_r Lambda_r, existence from 1 - delta = sum_r c_r Lambda_r (association/pda.py)
5. combination: the output estimate (not fed back)

Track management:

* initiation (one-point, with a velocity prior): every measurement validated by no existing track
  starts a tentative track at ``[z, 0, 0]`` with covariance ``diag(R_z, s_v^2 I)``; ``s_v`` is the
  velocity prior's standard deviation. One-point initiation is chosen over two-point because it needs
  no pairing of measurements across scans in 40-point clutter and lets the existence probability do
  the discrimination (Musicki & Evans 2004, "Joint integrated probabilistic data association: JIPDA",
  sec. VI uses the same). The covariance at initiation is kept as ``P_init`` for the CTT test (eq. 23).
* confirmation: a track becomes confirmed when its existence exceeds ``confirm_threshold`` and stays
  confirmed until it is terminated;
* termination: a track is deleted when its existence falls below ``terminate_threshold``.

The tracker keeps no history of its own (memory is bounded by the live tracks); the caller gets a
:class:`TrackSnapshot` after every scan and keeps what it needs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sonartrack.association.gating import gate_threshold
from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.association.pda import pda_update_batch
from sonartrack.core.errors import InputError, require
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, validate_transition_matrix
from sonartrack.models.motion import cv_process_noise_stack, cv_transition

TENTATIVE, CONFIRMED = 0, 1


@dataclass(frozen=True, slots=True)
class TrackerConfig:
    """Parameters of the IPDA / IMM-IPDA tracker. One q per mode; one q means single-model IPDA."""

    q: tuple[float, ...] = (0.001,)
    transition_diagonal: float = 0.95
    pd: float = 0.8
    gate_probability: float = 0.99
    clutter_density_per_m2: float = 1e-6
    p_survive: float = 0.98
    p_birth: float = 0.0
    initial_existence: float = 0.05
    confirm_threshold: float = 0.9
    terminate_threshold: float = 0.01
    init_velocity_std_mps: float = 5.0
    max_tracks: int = 2000

    def __post_init__(self):
        require(len(self.q) >= 1 and all(q >= 0 for q in self.q), "q must be one or more non-negative values (m^2/s^3)")
        require(0 < self.pd <= 1, f"pd must be in (0, 1] (got {self.pd})")
        require(0 < self.gate_probability < 1, "gate_probability must be in (0, 1)")
        require(self.clutter_density_per_m2 > 0, "clutter density must be positive (per m^2)")
        require(0 <= self.terminate_threshold < self.initial_existence < self.confirm_threshold <= 1,
                "need terminate_threshold < initial_existence < confirm_threshold <= 1")
        require(1.0 / len(self.q) <= self.transition_diagonal <= 1.0 or len(self.q) == 1,
                "transition_diagonal must be in [1/modes, 1]")

    @property
    def transition_matrix(self) -> np.ndarray:
        """Pi with ``transition_diagonal`` on the diagonal and the rest spread evenly."""
        r = len(self.q)
        if r == 1:
            return np.ones((1, 1))
        off = (1.0 - self.transition_diagonal) / (r - 1)
        Pi = np.full((r, r), off)
        np.fill_diagonal(Pi, self.transition_diagonal)
        return Pi


@dataclass(frozen=True, slots=True)
class TrackSnapshot:
    """The live tracks after a scan (n tracks, r modes)."""

    time_s: float
    track_id: np.ndarray  # (n,)
    status: np.ndarray  # (n,) TENTATIVE or CONFIRMED
    existence: np.ndarray  # (n,)
    x: np.ndarray  # (n, 4) combined estimate
    P: np.ndarray  # (n, 4, 4)
    mu: np.ndarray  # (n, r)
    P_init: np.ndarray  # (n, 4, 4) covariance at initiation (CTT test, eq. 23)
    born_s: np.ndarray  # (n,)

    @property
    def confirmed(self) -> np.ndarray:
        return self.status == CONFIRMED


@dataclass
class _Tracks:
    x: np.ndarray
    P: np.ndarray
    mu: np.ndarray
    exist: np.ndarray
    status: np.ndarray
    track_id: np.ndarray
    P_init: np.ndarray
    born_s: np.ndarray

    @classmethod
    def empty(cls, r: int) -> _Tracks:
        return cls(np.zeros((0, r, 4)), np.zeros((0, r, 4, 4)), np.zeros((0, r)), np.zeros(0), np.zeros(0, np.int8),
                   np.zeros(0, np.int64), np.zeros((0, 4, 4)), np.zeros(0))

    def select(self, keep: np.ndarray) -> _Tracks:
        return _Tracks(*(getattr(self, f)[keep] for f in _FIELDS))

    def append(self, other: _Tracks) -> _Tracks:
        return _Tracks(*(np.concatenate([getattr(self, f), getattr(other, f)]) for f in _FIELDS))


_FIELDS = ("x", "P", "mu", "exist", "status", "track_id", "P_init", "born_s")


@dataclass
class Tracker:
    """IPDA / IMM-IPDA multi-target tracker; call :meth:`step` once per scan, in time order."""

    config: TrackerConfig = field(default_factory=TrackerConfig)

    def __post_init__(self):
        c = self.config
        self._r = len(c.q)
        self._Pi = validate_transition_matrix(c.transition_matrix)
        self._gamma = gate_threshold(c.gate_probability, 2)
        self._tracks = _Tracks.empty(self._r)
        self._time: float | None = None
        self._next_id = 1

    def step(self, time_s: float, z, R) -> TrackSnapshot:
        """Process one scan of position measurements ``z (m, 2)`` with covariances ``R (m, 2, 2)``."""
        c = self.config
        z = np.asarray(z, float).reshape(-1, 2)
        R = np.broadcast_to(np.asarray(R, float), (len(z), 2, 2))
        if not np.all(np.isfinite(z)) or not np.all(np.isfinite(R)):
            raise InputError(f"scan at t = {time_s} s has NaN or infinite measurements: remove or fix those rows")
        if self._time is not None and not time_s > self._time:
            raise InputError(f"scan times must increase (got {time_s} s after {self._time} s)")
        T = self._tracks
        gated_any = np.zeros(len(z), bool)
        if len(T.exist):
            dt = time_s - self._time
            cpred, w = imm_mixing(T.mu, self._Pi)
            x0, P0 = imm_mix(T.x, T.P, w)
            F = cv_transition(dt)
            Q = cv_process_noise_stack(dt, c.q)
            x_pred = x0 @ F.T
            P_pred = F @ P0 @ F.T + Q
            e_pred = existence_predict(T.exist, c.p_survive, c.p_birth)
            res = pda_update_batch(x_pred, P_pred, z, R, pd=c.pd, pg=c.gate_probability, gamma=self._gamma,
                                   clutter_density=c.clutter_density_per_m2)
            # mode probabilities and existence (log space for the mode weights)
            a = np.log(np.maximum(cpred, 1e-300)) + res.log_lambda
            amax = a.max(axis=1, keepdims=True)
            wts = np.exp(a - amax)
            lam_total = wts.sum(axis=1) * np.exp(amax[:, 0])  # sum_r c_r Lambda_r
            mu = wts / wts.sum(axis=1, keepdims=True)
            exist = existence_update(e_pred, lam_total)
            status = np.where(exist > c.confirm_threshold, CONFIRMED, T.status).astype(np.int8)
            T = _Tracks(res.x, res.P, mu, exist, status, T.track_id, T.P_init, T.born_s)
            gated_any = res.gated.any(axis=0)
            T = T.select(T.exist >= c.terminate_threshold)
        # one-point initiation from measurements no existing track validated
        new = np.nonzero(~gated_any)[0]
        room = max(0, c.max_tracks - len(T.exist))
        new = new[:room]
        if len(new):
            T = T.append(self._initiate(time_s, z[new], R[new]))
        self._tracks = T
        self._time = time_s
        return self.snapshot()

    def _initiate(self, time_s: float, z, R) -> _Tracks:
        c, r, k = self.config, self._r, len(z)
        P = np.zeros((k, 4, 4))
        P[:, :2, :2] = R
        P[:, 2, 2] = P[:, 3, 3] = c.init_velocity_std_mps**2
        x = np.zeros((k, 4))
        x[:, :2] = z
        ids = np.arange(self._next_id, self._next_id + k)
        self._next_id += k
        return _Tracks(np.repeat(x[:, None], r, axis=1), np.repeat(P[:, None], r, axis=1), np.full((k, r), 1.0 / r),
                       np.full(k, c.initial_existence), np.zeros(k, np.int8), ids, P, np.full(k, float(time_s)))

    def snapshot(self) -> TrackSnapshot:
        T = self._tracks
        if len(T.exist):
            xc, Pc = imm_combine(T.mu, T.x, T.P)
        else:
            xc, Pc = np.zeros((0, 4)), np.zeros((0, 4, 4))
        return TrackSnapshot(float(self._time if self._time is not None else np.nan), T.track_id.copy(),
                             T.status.copy(), T.exist.copy(), xc, Pc, T.mu.copy(), T.P_init.copy(), T.born_s.copy())
