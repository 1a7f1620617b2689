"""The array's own turn predicted in a cone-angle tracker, with each track's side (port/starboard) as a hypothesis.

A line array measures the cone angle theta between its axis (heading h) and the target's true bearing b. The
tracker's state is the unfolded cone angle phi (tracking/measurements.py ``fold_cone_deg``), tied to the bearing
by the side s the track started on (s = +1 starboard, b = h + phi; s = -1 port, b = h - phi):

    phi = s (b - h)   =>   phi_k = phi_{k-1} + T phi_dot - s dh,   dh = h_k - h_{k-1}   (exact, no small angle)

so a heading change dh between two scans moves a starboard target's cone angle by -dh and a port target's by +dh,
while the state's rate phi_dot = s b_dot stays the target's own bearing rate (the turn is no longer absorbed as
process noise). The side is unknown, so each track carries P(s = +1) = p and the prediction is the two-component
Gaussian mixture {phi - dh w.p. p, phi + dh w.p. 1 - p} collapsed to its first two moments (a multiple-model
estimator whose two models - the sides - never switch, merged every scan by moment matching as the first-order
generalised pseudo-Bayesian estimator GPB1 does; Bar-Shalom, Li & Kirubarajan, Estimation with Applications to
Tracking and Navigation, 2001, sec. 11.6):

    mean shift  -(2 p - 1) dh,     added variance  4 p (1 - p) dh^2   (on phi only)

and after the scan p is updated by Bayes' rule with each hypothesis' PDA likelihood of the scan (the mode
likelihood ratio of association/pda.py, Bar-Shalom, Daum & Huang 2009, eq. 36, times the clutter density lambda,
which is common to both sides):

    Lambda_s = (1 - P_D P_G) lambda + P_D sum_j N(z_j; fold(phi_s), S)     over the track's gated peaks,
    p <- p Lambda_+ / (p Lambda_+ + (1 - p) Lambda_-)

with S = P-[0, 0] + sigma_p^2 of the prediction without the turn. A track in an unresolved pair
(tracking/resolution.py) keeps its p through that scan: the one peak is the pair's, not its own.

While the array holds its heading both hypotheses predict the same and p does not move; in a turn the side that
explains the peaks wins within a few scans, and the prediction becomes exact. This is the left/right ambiguity of
a towed array resolved by the ownship's manoeuvre, in the tracker rather than only in the TMA (tma/sides.py).

Limit: the window gate (width V) is centred on the collapsed mean, so while the side is still unknown a heading
change of V/2 or more in one scan puts the true peak at or beyond its edge (measured: 2 deg/s turns held with 1 s
scans and V = 6 deg, 3 deg/s lost a scan or two at the start of the turn).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.tracking.measurements import fold_cone_deg

#: p is kept within [P_FLOOR, 1 - P_FLOOR] so that one bad scan cannot make a side impossible
P_FLOOR = 1e-6


@dataclass(frozen=True)
class ArrayTurnPrediction:
    """Predicts each track's cone angle through the array's heading change (module docstring); per-track
    ``p_starboard`` in the tracks' ``attrs``. ``p_detect``, ``clutter_density_per_deg`` and ``gate_deg`` (the window
    V) as the tracker's."""

    p_detect: float
    clutter_density_per_deg: float
    gate_deg: float

    attr = "p_starboard"

    def new_track_attrs(self, k: int) -> dict:
        """Side probabilities of ``k`` new tracks, ``{"p_starboard": (k,) array of 0.5}`` (either side)."""
        return {self.attr: np.full(k, 0.5)}

    def predict(self, x_pred, P_pred, attrs: dict, turn_deg: float):
        """The predicted states moved by the heading change, the two sides' mixture collapsed (module docstring).

        Parameters
        ----------
        x_pred : ndarray, shape (n, r, 2)
            Predicted [phi (deg), phi rate (deg/s)] without the turn.
        P_pred : ndarray, shape (n, r, 2, 2)
            Their covariances (deg^2, ...).
        attrs : dict
            Per-track ``p_starboard`` (n,).
        turn_deg : float
            The array's heading change dh since the last scan (deg, clockwise positive).

        Returns
        -------
        x : ndarray, shape (n, r, 2)
            phi shifted by -(2 p - 1) dh.
        P : ndarray, shape (n, r, 2, 2)
            P[0, 0] increased by 4 p (1 - p) dh^2.
        """
        p = attrs[self.attr][:, None]
        x, P = x_pred.copy(), P_pred.copy()
        x[..., 0] -= (2.0 * p - 1.0) * turn_deg
        P[..., 0, 0] += 4.0 * p * (1.0 - p) * turn_deg**2
        return x, P

    def update(self, attrs: dict, x_pred, P_pred, sigma_p, z, gated, turn_deg: float) -> dict:
        """Side probabilities after the scan: Bayes' rule with each side's PDA likelihood (module docstring).

        Parameters
        ----------
        attrs : dict
            Per-track ``p_starboard`` (n,).
        x_pred, P_pred : ndarray, shapes (n, 1, 2) and (n, 1, 2, 2)
            The predictions WITHOUT the turn (phi, deg).
        sigma_p : ndarray, shape (n,)
            Per-track peak spread (deg).
        z : ndarray, shape (m,)
            The scan's cone angles (deg).
        gated : ndarray of bool, shape (n, m)
            The tracks' gates (of the collapsed prediction).
        turn_deg : float
            The heading change dh (deg).

        Returns
        -------
        dict
            ``attrs`` with ``p_starboard`` updated.
        """
        p = attrs[self.attr]
        if turn_deg == 0.0 or len(p) == 0:
            return attrs
        from scipy.special import erf

        S = P_pred[:, 0, 0, 0] + np.asarray(sigma_p, float) ** 2
        gate_probability = erf(self.gate_deg / (2.0 * np.sqrt(2.0 * S)))
        lam = []
        for s in (1.0, -1.0):
            theta = fold_cone_deg(x_pred[:, 0, 0] - s * turn_deg)[0]
            nu = np.asarray(z, float)[None, :] - theta[:, None]
            dens = np.where(gated, np.exp(-0.5 * nu**2 / S[:, None]) / np.sqrt(2 * np.pi * S[:, None]), 0.0)
            lam.append((1.0 - self.p_detect * gate_probability) * self.clutter_density_per_deg
                       + self.p_detect * dens.sum(axis=1))
        num = p * lam[0]
        den = num + (1.0 - p) * lam[1]
        new = np.where(den > 0, num / np.where(den > 0, den, 1.0), p)
        return {**attrs, self.attr: np.clip(new, P_FLOOR, 1.0 - P_FLOOR)}
