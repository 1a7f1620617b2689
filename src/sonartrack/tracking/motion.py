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
    rate of ``rates_deg_s`` (deg/s, > 0), each with white-noise intensity ``q`` (m^2/s^3)."""

    rates_deg_s: tuple[float, ...] = ()
    q: float = 1e-3

    def __post_init__(self):
        rates = tuple(float(v) for v in self.rates_deg_s)
        if any(not 0.0 < v <= 30.0 for v in rates) or not self.q >= 0.0:
            raise ValueError(f"turn rates must be in (0, 30] deg/s and q >= 0 m^2/s^3, got {rates} and {self.q}")
        object.__setattr__(self, "rates_deg_s", rates)

    def signed_rates_rad_s(self) -> tuple[float, ...]:
        """The modes' turn rates (rad/s, counter-clockwise positive): +w, -w for each rate w."""
        return tuple(s * float(np.deg2rad(w)) for w in self.rates_deg_s for s in (1.0, -1.0))


@dataclass(frozen=True)
class ImmConstantVelocity:
    """r motion modes (intensity ``q[r]``, position unit^2/s^3) on ``dims`` axes; mode chain ``transition``
    (r x r). ``turn_rate_rad_s[r]`` (2-D only; rad/s, counter-clockwise positive): mode r turns at that known
    rate (0: constant velocity); None: every mode constant velocity (P4's IMM)."""

    q: tuple[float, ...]
    dims: int = 2
    transition: np.ndarray | None = None  # (r, r); None: the identity (one mode, or modes that never switch)
    turn_rate_rad_s: tuple[float, ...] | None = None

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
        object.__setattr__(self, "_FQ", {})  # dt -> (F, Q): scans usually come at one period

    @property
    def n_modes(self) -> int:
        """Number of modes r."""
        return len(self.q)

    @property
    def state_dim(self) -> int:
        """State dimension d = 2 dims (positions, then velocities)."""
        return 2 * self.dims

    def interact(self, mu, x, P):
        """IMM interaction: predicted mode probabilities and mixed initial conditions (filters/imm.py).

        Parameters
        ----------
        mu, x, P : ndarray, shapes (n, r), (n, r, d), (n, r, d, d)
            Mode probabilities of n tracks and r modes, the mode-conditioned states and their covariances.

        Returns
        -------
        c, x0, P0 : ndarray, shapes as ``mu``, ``x``, ``P``
            Predicted mode probabilities, mixed states and mixed covariances.
        """
        if self.n_modes == 1:  # mixing one mode with itself: x0 = x, P0 = P (symmetrized, as imm_mix does)
            return mu, x, symmetrize(P)
        from sonartrack.filters.imm_kernel import mix  # numba: loaded on first use

        c, w = imm_mixing(mu, self.transition)
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
