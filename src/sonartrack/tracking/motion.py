"""Motion part of a tracker: constant-velocity and coordinated-turn modes joined by a Markov mode chain (IMM).

Each mode r is a constant-velocity model with its own white-noise intensity q_r (models/motion.py), or, in 2-D,
a coordinated turn at a known rate w_r with that intensity (filters/coordinated_turn.py: linear for a known
rate, so every mode stays a Kalman filter on the same state [x, y, vx, vy]);
the mode chain with transition matrix Pi[i, j] = P(mode j at k | mode i at k-1) mixes them before the
prediction and re-weighs them after the update, with the IMM steps of filters/imm.py (Blom &
Bar-Shalom 1988; Park, Song, Lee 2017, eqs. 7-11 and 19):

    interaction   c_j = sum_i Pi[i, j] mu_i,  x0_j, P0_j mixed with mu_{i|j} = Pi[i, j] mu_i / c_j
    prediction    x-_j = F_j x0_j,  P-_j = F_j P0_j F_j^T + Q_j
    mode update   mu_j = c_j Lambda_j / sum_l c_l Lambda_l   (Lambda_j from the associator)

One mode is a plain (single-model) filter: the interaction and mode update are then identities. The
mixing runs compiled (filters/imm_kernel.py, the same numbers as filters/imm.py's ``imm_mix``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.linalg import symmetrize
from sonartrack.filters.coordinated_turn import ct_process_noise, ct_transition
from sonartrack.filters.imm import imm_mixing, imm_mode_update, validate_transition_matrix
from sonartrack.models.motion import cv_process_noise_stack, cv_transition


@dataclass(frozen=True)
class TurnModes:
    """Coordinated-turn modes to add to a position tracker's IMM: a pair (clockwise and counter-clockwise) at each
    rate of ``rates_deg_s`` (deg/s, > 0), each with white-noise intensity ``q`` (m^2/s^3).

    ``turn_deg`` (deg, > 0): the mean course change of one turn, so a mode at rate w lasts turn_deg / w seconds on
    average (its expected sojourn time, :meth:`sojourn_s`; Bar-Shalom, Li, Kirubarajan 2001, sec. 11.6.6: p_jj =
    1 - T / tau_j for a sojourn tau_j); e.g. 120 deg, the middle of the 60-180 deg turns of issue 34 item 5. None
    (default): the turn modes keep the tracker's per-scan diagonal. Not the default: measured on the independent
    turning-target generator of tests/systems/active/test_turns_tracker.py (seeds 0-7) and the active chain
    (benchmarks/bench_active_turns.py, bench_active_rows.py) it did not hold turns better (module doc of the
    benchmark has the numbers)."""

    rates_deg_s: tuple[float, ...] = ()
    q: float = 1e-3
    turn_deg: float | None = None

    def __post_init__(self):
        rates = tuple(float(v) for v in self.rates_deg_s)
        if any(not 0.0 < v <= 30.0 for v in rates) or not self.q >= 0.0:
            raise ValueError(f"turn rates must be in (0, 30] deg/s and q >= 0 m^2/s^3, got {rates} and {self.q}")
        if self.turn_deg is not None and not 0.0 < self.turn_deg <= 360.0:
            raise ValueError(f"a turn's mean course change must be in (0, 360] deg, got {self.turn_deg}")
        object.__setattr__(self, "rates_deg_s", rates)

    def sojourn_s(self) -> tuple[float, ...] | None:
        """Mean time (s) in each turn mode, in :meth:`signed_rates_rad_s`'s order: turn_deg / rate (None: not set)."""
        if self.turn_deg is None:
            return None
        return tuple(float(self.turn_deg) / w for w in self.rates_deg_s for _ in (1.0, -1.0))

    def signed_rates_rad_s(self) -> tuple[float, ...]:
        """The modes' turn rates (rad/s, counter-clockwise positive): +w, -w for each rate w."""
        return tuple(s * float(np.deg2rad(w)) for w in self.rates_deg_s for s in (1.0, -1.0))


@dataclass(frozen=True)
class ImmConstantVelocity:
    """r motion modes (intensity ``q[r]``, position unit^2/s^3) on ``dims`` axes; mode chain ``transition``
    (r x r). ``turn_rate_rad_s[r]`` (2-D only; rad/s, counter-clockwise positive): mode r turns at that known
    rate (0: constant velocity); None: every mode constant velocity (P4's IMM).

    ``sojourn_s[r]`` (s, or None per mode): mode r lasts that long on average, so over a scan interval T it is kept
    with probability exp(-T / sojourn) (the exponential sojourn of a continuous-time chain; 1 - T / sojourn for T
    much shorter, Bar-Shalom, Li, Kirubarajan 2001, sec. 11.6.6) and left in the proportions of ``transition``'s
    off-diagonal row; a None mode (or ``sojourn_s`` None) keeps ``transition``'s row whatever T. A turn lasts its
    course change over its rate, whatever the ping interval: a fixed per-scan diagonal (0.98 at 30 s: 25 min) keeps
    a track in a turn mode long after a 2-minute turn has ended."""

    q: tuple[float, ...]
    dims: int = 2
    transition: np.ndarray | None = None  # (r, r); None: the identity (one mode, or modes that never switch)
    turn_rate_rad_s: tuple[float, ...] | None = None
    sojourn_s: tuple[float | None, ...] | None = None

    def __post_init__(self):
        object.__setattr__(self, "q", tuple(float(v) for v in self.q))
        if self.turn_rate_rad_s is not None:
            w = tuple(float(v) for v in self.turn_rate_rad_s)
            if len(w) != len(self.q) or self.dims != 2:
                raise ValueError(f"turn rates need 2 axes and one rate per mode ({len(self.q)}), got {len(w)}")
            object.__setattr__(self, "turn_rate_rad_s", w if any(w) else None)
        Pi = np.eye(len(self.q)) if self.transition is None else self.transition
        object.__setattr__(self, "transition", validate_transition_matrix(Pi))
        if self.transition.shape[0] != len(self.q):
            raise ValueError(f"{len(self.q)} modes but a {self.transition.shape} transition matrix")
        if self.sojourn_s is not None:
            tau = tuple(None if v is None else float(v) for v in self.sojourn_s)
            if len(tau) != len(self.q) or any(v is not None and not v > 0.0 for v in tau):
                raise ValueError(f"need one sojourn time > 0 s (or None) per mode ({len(self.q)}), got {tau}")
            object.__setattr__(self, "sojourn_s", tau if any(v is not None for v in tau) else None)
        object.__setattr__(self, "_FQ", {})  # dt -> (F, Q): scans usually come at one period
        object.__setattr__(self, "_Pi", {})  # dt -> the transition matrix over dt (with sojourn times)

    @property
    def n_modes(self) -> int:
        """Number of modes r."""
        return len(self.q)

    @property
    def state_dim(self) -> int:
        """State dimension d = 2 dims (positions, then velocities)."""
        return 2 * self.dims

    def transition_at(self, dt_s: float | None = None) -> np.ndarray:
        """The mode chain over a scan interval: ``transition``, with each row of a mode with a sojourn time kept
        with probability exp(-dt / sojourn) and left in the proportions of that row's off-diagonal (class doc).

        Parameters
        ----------
        dt_s : float, optional
            Time since the last scan (s); None: ``transition`` as given.

        Returns
        -------
        ndarray, shape (r, r)
            Pi[i, j] = P(mode j at k | mode i at k-1), rows summing to 1.
        """
        if self.sojourn_s is None or dt_s is None:
            return self.transition
        Pi = self._Pi.get(dt_s)
        if Pi is None:
            if len(self._Pi) > 64:
                self._Pi.clear()
            Pi = self._Pi[dt_s] = sojourn_transition(self.transition, self.sojourn_s, dt_s)
        return Pi

    def interact(self, mu, x, P, dt_s: float | None = None):
        """IMM interaction: predicted mode probabilities and mixed initial conditions (filters/imm.py).

        Parameters
        ----------
        mu, x, P : ndarray, shapes (n, r), (n, r, d), (n, r, d, d)
            Mode probabilities of n tracks and r modes, the mode-conditioned states and their covariances.
        dt_s : float, optional
            Time since the last scan (s): the chain over it (:meth:`transition_at`); None: ``transition``.

        Returns
        -------
        c, x0, P0 : ndarray, shapes as ``mu``, ``x``, ``P``
            Predicted mode probabilities, mixed states and mixed covariances.
        """
        if self.n_modes == 1:  # mixing one mode with itself: x0 = x, P0 = P (symmetrized, as imm_mix does)
            return mu, x, symmetrize(P)
        from sonartrack.filters.imm_kernel import mix  # numba: loaded on first use

        c, w = imm_mixing(mu, self.transition_at(dt_s))
        x0, P0 = mix(x, P, w)  # filters/imm.py's imm_mix, compiled (identical results)
        return c, x0, P0

    def predict(self, x0, P0, dt_s: float):
        """Mode-matched prediction ``x- = F x0``, ``P- = F P0 F^T + Q_r``, every track and mode at once.

        Parameters
        ----------
        x0 : ndarray, shape (n, r, d)
            Mixed states (position unit and position unit/s).
        P0 : ndarray, shape (n, r, d, d)
            Mixed covariances.
        dt_s : float
            Time since the last scan (s).

        Returns
        -------
        x_pred : ndarray, shape (n, r, d)
            Predicted states.
        P_pred : ndarray, shape (n, r, d, d)
            Predicted covariances.
        """
        FQ = self._FQ.get(dt_s)
        if FQ is None:
            if len(self._FQ) > 64:
                self._FQ.clear()
            FQ = self._FQ[dt_s] = self._transition_and_noise(dt_s)
        F, Q = FQ
        if F.ndim == 2:  # constant-velocity modes share one F
            return x0 @ F.T, F @ P0 @ F.T + Q
        return np.einsum("rij,nrj->nri", F, x0), F @ P0 @ F.swapaxes(-1, -2) + Q

    def _transition_and_noise(self, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """F (d, d) shared by constant-velocity modes, or (r, d, d) one per mode with turns; Q (r, d, d)."""
        if self.turn_rate_rad_s is None:
            return cv_transition(dt_s, self.dims), cv_process_noise_stack(dt_s, self.q, self.dims)
        pairs = list(zip(self.q, self.turn_rate_rad_s, strict=True))
        return (np.stack([ct_transition(dt_s, w) for _, w in pairs]),
                np.stack([ct_process_noise(dt_s, q, w) for q, w in pairs]))

    def mode_update(self, c, log_lambda):
        """Posterior mode probabilities and the total likelihood ``log sum_r c_r Lambda_r`` (filters/imm.py).

        Parameters
        ----------
        c : ndarray, shape (n, r)
            Predicted mode probabilities.
        log_lambda : ndarray, shape (n, r) or None
            Mode log-likelihood ratios log Lambda_r; None when the associator gives none (JPDA).

        Returns
        -------
        mu : ndarray, shape (n, r)
            Posterior mode probabilities (``c`` unchanged with one mode).
        log_total : ndarray, shape (n,) or None
            ``log sum_r c_r Lambda_r``; None if ``log_lambda`` is None.
        """
        if self.n_modes == 1:
            return c, None if log_lambda is None else log_lambda[:, 0]
        return imm_mode_update(c, log_lambda)


def sojourn_transition(Pi, sojourn_s, dt_s: float) -> np.ndarray:
    """``Pi`` with each mode i of a sojourn time tau_i kept over ``dt_s`` with probability exp(-dt / tau_i) and left
    in the proportions of Pi's off-diagonal row i (a mode whose row has no off-diagonal mass stays); modes with tau
    None keep their row (:class:`ImmConstantVelocity` doc).

    Parameters
    ----------
    Pi : ndarray, shape (r, r)
        Markov transition matrix (rows sum to 1).
    sojourn_s : sequence of float or None, length r
        Mean time in each mode (s), None where the row stays as given.
    dt_s : float
        Scan interval (s), >= 0.

    Returns
    -------
    ndarray, shape (r, r)
        The transition matrix over dt_s.
    """
    out = np.array(Pi, float, copy=True)
    for i, tau in enumerate(sojourn_s):
        if tau is None:
            continue
        off = out[i].copy()
        off[i] = 0.0
        total = off.sum()
        if total <= 0.0:
            continue
        stay = float(np.exp(-max(float(dt_s), 0.0) / tau))
        out[i] = (1.0 - stay) * off / total
        out[i, i] = stay
    return out
