"""Motion part of a tracker: constant-velocity modes joined by a Markov mode chain (IMM).

Each mode r is a constant-velocity model with its own white-noise intensity q_r (models/motion.py);
the mode chain with transition matrix Pi[i, j] = P(mode j at k | mode i at k-1) mixes them before the
prediction and re-weighs them after the update, with the IMM steps of filters/imm.py (Blom &
Bar-Shalom 1988; Park, Song, Lee 2017, eqs. 7-11 and 19):

    interaction   c_j = sum_i Pi[i, j] mu_i,  x0_j, P0_j mixed with mu_{i|j} = Pi[i, j] mu_i / c_j
    prediction    x-_j = F x0_j,  P-_j = F P0_j F^T + Q_j
    mode update   mu_j = c_j Lambda_j / sum_l c_l Lambda_l   (Lambda_j from the associator)

One mode is a plain (single-model) filter: the interaction and mode update are then identities. The
mixing runs compiled (filters/imm_kernel.py, the same numbers as filters/imm.py's ``imm_mix``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.linalg import symmetrize
from sonartrack.filters.imm import imm_mixing, imm_mode_update, validate_transition_matrix
from sonartrack.models.motion import cv_process_noise_stack, cv_transition


@dataclass(frozen=True)
class ImmConstantVelocity:
    """r constant-velocity modes (intensity ``q[r]``, position unit^2/s^3) on ``dims`` axes; mode chain
    ``transition`` (r x r)."""

    q: tuple[float, ...]
    dims: int = 2
    transition: np.ndarray | None = None  # (r, r); None: the identity (one mode, or modes that never switch)

    def __post_init__(self):
        object.__setattr__(self, "q", tuple(float(v) for v in self.q))
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
        mu : ndarray, shape (n, r)
            Mode probabilities.
        x : ndarray, shape (n, r, d)
            Mode-conditioned states.
        P : ndarray, shape (n, r, d, d)
            Their covariances.

        Returns
        -------
        c : ndarray, shape (n, r)
            Predicted mode probabilities.
        x0 : ndarray, shape (n, r, d)
            Mixed states.
        P0 : ndarray, shape (n, r, d, d)
            Mixed covariances.
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
            FQ = self._FQ[dt_s] = (cv_transition(dt_s, self.dims), cv_process_noise_stack(dt_s, self.q, self.dims))
        F, Q = FQ
        return x0 @ F.T, F @ P0 @ F.T + Q

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
