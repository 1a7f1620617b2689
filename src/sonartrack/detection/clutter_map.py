"""A clutter map over pings: contacts whose world position recurs ping after ping are stationary clutter.

A strong fixed scatterer (a wreck, a rock, a seamount's flank) echoes on every ping at the same place on the sea
floor. The navigation puts each contact in the world frame (systems/active/contacts.py), so such a point gives a
contact at the same world position whatever the ownship does, where a target's contacts drift by its speed times the
time between pings. For each contact z_i (covariance R_i) of a new ping and each of the last ``span`` pings, the
ping is a hit when one of its contacts z_j passes the gate

    (z_i - z_j)^T (R_i + R_j)^(-1) (z_i - z_j) <= gamma,     gamma = chi2_2 quantile at ``gate_probability``

(the difference of two independent position measurements of one still point has covariance R_i + R_j); a contact
with hits on at least ``min_hits`` of the last ``span`` pings is marked clutter. Mirror contacts are kept like any
other (a still point's mirror is still while the array holds its heading).

A slow target is the price: its contacts match a ping j pings back while its drift v j T stays inside the gate
(about 3 sqrt(2) sigma, sigma the contact's position error), so one moving slower than about
3 sqrt(2) sigma / (min_hits T) looks still (sigma 70 m, T 30 s, min_hits 3: ~3 m/s; the map must learn a point
before IPDA confirms a track on it, ~4 pings, so min_hits cannot be much larger). So the chain does not delete
clutter contacts: it keeps them from tracks that are not confirmed (systems/active/run.py), so they start and confirm
no track, while a confirmed track (a target already held that slows, or passes over a clutter point) still gets the
contacts in its gate. A target that is slower than that from the moment it enters the window is not confirmed while
it stays slow: that is the measured trade (benchmarks/bench_active_clutter.py).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from sonartrack.association.gating import gate_threshold


class ClutterMap:
    """Recurring world positions over the last ``span`` pings (module doc).

    Parameters
    ----------
    span : int
        Pings remembered.
    min_hits : int
        A contact is clutter when this many of the remembered pings hold a contact in its gate.
    gate_probability : float
        Probability of the chi-square(2) gate on the difference of two positions.
    """

    def __init__(self, span: int = 8, min_hits: int = 3, gate_probability: float = 0.99):
        self.span, self.min_hits = int(span), int(min_hits)
        self.gamma = float(gate_threshold(gate_probability, 2))
        self._pings: deque = deque(maxlen=self.span)

    def update(self, xy: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Mark a ping's contacts, then remember them.

        Parameters
        ----------
        xy : ndarray (m, 2)
            Contact positions in the world frame (m).
        R : ndarray (m, 2, 2)
            Their covariances (m^2).

        Returns
        -------
        numpy.ndarray
            (m,) bool, True: clutter (hits on >= ``min_hits`` of the remembered pings).
        """
        xy, R = np.asarray(xy, float).reshape(-1, 2), np.asarray(R, float).reshape(-1, 2, 2)
        hits = np.zeros(len(xy), np.int64)
        for xy_j, R_j in self._pings:
            if len(xy) and len(xy_j):
                hits += in_gate(xy, R, xy_j, R_j, self.gamma).any(axis=1)
        self._pings.append((xy, R))
        return hits >= self.min_hits


def in_gate(xy_a: np.ndarray, R_a: np.ndarray, xy_b: np.ndarray, R_b: np.ndarray, gamma: float) -> np.ndarray:
    """(a, b) bool: d^2 = (z_a - z_b)^T (R_a + R_b)^(-1) (z_a - z_b) <= gamma (2 x 2 inverse in closed form).

    Parameters
    ----------
    xy_a, xy_b : ndarray (a, 2), (b, 2)
        Positions (m).
    R_a, R_b : ndarray (a, 2, 2), (b, 2, 2)
        Covariances (m^2).
    gamma : float
        Gate threshold on d^2.

    Returns
    -------
    numpy.ndarray
        (a, b) bool.
    """
    d = xy_a[:, None, :] - xy_b[None, :, :]
    S = R_a[:, None] + R_b[None, :]
    det = S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] * S[..., 1, 0]
    d2 = (S[..., 1, 1] * d[..., 0] ** 2 - (S[..., 0, 1] + S[..., 1, 0]) * d[..., 0] * d[..., 1]
          + S[..., 0, 0] * d[..., 1] ** 2) / np.where(det > 0, det, np.inf)
    return d2 <= gamma
