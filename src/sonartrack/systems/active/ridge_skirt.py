"""A CW still point's skirt before the ridge map knows the point: the places where its hidden echo recurs, widened by
its delay-Doppler skirt, hold a slow track's confirmation and raise the clutter density its contacts are scored against.

Why (issue 34 item 2; study active-chain trial 11, CW 32 x 0.25 m at 2.4 kHz, spiky K, its reverberation-only hour:
2 false rows, 4 tracks; benchmarks/bench_cw_ridge_learn.py). A still point echoes on its own beam's reverberation
ridge, which the CW front end notches; the chain finds that hidden echo (detection/cw_cells.py ``ridge_echoes``) and
its own clutter map, the ridge map (contact_tracker.py ``ridge_map_of``), withholds the point's skirt and images once
it shows the echo still. But the hidden echo stands above the ridge's reverberation on only a third to a half of the
pings (a TS 27 dB point's within 300 m of it on 13 of the first 44 pings, with 150 x 220 m errors), so the map's
recurrence test (4 hits of 8) is met long before its stillness fit (speed bound 2.2-4.5 m/s at the first 4 hits;
shown still at ping 102; a TS 22 dB point never in the hour). Meanwhile the echo's skirt past the notch, 300-800 m
down the line of sight (r_B + 500-1400 m, 1-2 Doppler cells off), gives a contact on a few pings, and two of them 30-60
s apart confirm a track: the CW tracker's clutter density is its contacts' mean over the listening disc (~5e-10
/m^2, cw_tracking.py), so each contact in a young track's gate multiplies its odds by 300-2000 (note 12, CWCONF),
where a still point's skirt recurs ~1000 times denser. The track then coasts confirmed 10-20 pings.

What is known at that time is that the hidden echo RECURS at one place (a place, not a ping: the skirt contact of
the confirming ping often has no hidden echo of its own ping beside it). Recurrence alone is no stillness: a target
crossing the ridge recurs too, so nothing is withheld on it. Instead:

1. :class:`RidgePlaces` keeps the ridge map's recurring hidden echoes for the map's ``span`` pings after each was
   last seen, with the covariance widened along grad r_B by the skirt's reach (:func:`skirt_covariance`);
2. a contact in one's gate is scored against that skirt's own clutter density, :func:`skirt_density` (a spatial
   clutter density: Musicki & Evans, "Clutter map information for data association and track initialization",
   IEEE Trans. AES 40(2), 2004, where each measurement's likelihood ratio is p_j / rho_j with rho_j the clutter
   measurement density where it lies; IPDA's Lambda = 1 - P_D P_G + P_D P_G sum_j p_j / rho_j, Musicki, Evans,
   Stankovic 1994 eq. 29, unchanged). A young track's wide gate then gains odds ~1-4 a skirt contact, not
   300-2000; a confirmed track's narrow one still gains;
3. a slow track newly confirmed in such a gate waits until its velocity's confidence ellipse shows it moving
   (tracking/deleters.py ``StillHold`` with ``moving_gamma`` at :data:`RIDGE_HOLD_PROBABILITY`).

Measured (benchmarks/bench_cw_ridge_learn.py, the tracker stage replayed on the chain's recorded contacts, 1 h
reverberation-only twins, false confirmed tracks / listed rows): see that benchmark's docstring.
"""

from __future__ import annotations

import numpy as np

#: the confidence of the velocity ellipse by which a slow track newly confirmed in a recurring hidden ridge echo's
#: skirt must show it moving before its confirmation stands (tracking/deleters.py StillHold ``moving_gamma``): two
#: skirt contacts 30-60 s apart leave a young track's speed at 1.3-1.4 m/s on study active-chain trial 11's still
#: points (0.2-0.3 m/s once confirmed), over the 1 m/s the speed estimate alone would test
RIDGE_HOLD_PROBABILITY = 0.9

#: contacts in a recurring hidden ridge echo's skirt gate are scored against the skirt's own clutter density
#: (:func:`skirt_density`), not the scan's mean (False: the hold alone)
RIDGE_SKIRT_DENSITY = True


class RidgePlaces:
    """The places where a CW's hidden ridge echoes recur (module doc, 1), kept ``span`` pings after the last.

    Parameters
    ----------
    skirt_range_m : float
        The skirt's reach in bistatic range (m; c tau, systems/active/cw_tracking.py ``cw_ridge_window``).
    """

    def __init__(self, skirt_range_m: float):
        self.skirt_range_m = float(skirt_range_m)
        self.xy, self.R, self.seen = np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0)

    def update(self, t_s: float, ridge, recurring: np.ndarray | None, tx_xy, rx_xy, span: int,
               step_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Add this ping's recurring hidden echoes, forget those not seen for ``span`` pings; return the places.

        Parameters
        ----------
        t_s : float
            The ping's time (s).
        ridge : Contacts or None
            The ping's hidden-echo contacts (the ridge map's input).
        recurring : ndarray (k,) bool or None
            The ridge map's verdict on them (``ClutterMap.recurring``: hits on >= its ``min_hits`` pings).
        tx_xy, rx_xy : array (2,)
            Source and receiver (m).
        span : int
            Pings a place is kept after it was last seen.
        step_s : float
            The ping interval (s).

        Returns
        -------
        tuple
            (k, 2) positions (m) and (k, 2, 2) skirt-widened covariances (m^2).
        """
        if ridge is not None and recurring is not None and recurring.any():
            r = np.asarray(recurring, bool)
            wide = skirt_covariance(ridge.xy[r], ridge.R[r], tx_xy, rx_xy, self.skirt_range_m)
            self.xy, self.R = np.concatenate([self.xy, ridge.xy[r]]), np.concatenate([self.R, wide])
            self.seen = np.concatenate([self.seen, np.full(int(r.sum()), float(t_s))])
        alive = float(t_s) - self.seen <= span * step_s
        self.xy, self.R, self.seen = self.xy[alive], self.R[alive], self.seen[alive]
        return self.xy, self.R


def skirt_density(xy: np.ndarray, R: np.ndarray, place_xy: np.ndarray, place_R: np.ndarray, lam: float,
                  gamma: float) -> np.ndarray | None:
    """Each contact's clutter density (1/m^2): ``lam`` (the scan's mean), or where the contact lies in the gate
    d^2 <= gamma of a place (covariance R_j + R_place) one contact a ping over that gate's area, pi gamma
    sqrt(det(R_j + R_place)), when larger (the densest such place); None when no contact's density is raised.

    Parameters
    ----------
    xy, R : ndarray (m, 2), (m, 2, 2)
        The contacts (m, m^2).
    place_xy, place_R : ndarray (k, 2), (k, 2, 2)
        The places whose skirt recurs (m, m^2; :func:`skirt_covariance`).
    lam : float
        The scan's clutter density (1/m^2).
    gamma : float
        The chi-square(2) gate.

    Returns
    -------
    numpy.ndarray or None
        (m,) densities (1/m^2).
    """
    from sonartrack.detection.clutter_map import mahalanobis2

    if not len(place_xy) or not len(xy):
        return None
    S = np.asarray(R, float)[:, None] + np.asarray(place_R, float)[None]
    det = S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] * S[..., 1, 0]
    dense = 1.0 / (np.pi * gamma * np.sqrt(np.maximum(det, 1e-12)))
    rho = np.where(mahalanobis2(xy, R, place_xy, place_R) <= gamma, dense, 0.0).max(axis=1)
    return np.maximum(rho, lam) if (rho > lam).any() else None


def skirt_covariance(xy: np.ndarray, R: np.ndarray, tx_xy, rx_xy, range_m: float) -> np.ndarray:
    """Covariances of hidden ridge echoes widened along their bistatic range by their delay-Doppler skirt: a CW
    echo's ambiguity reaches ``range_m`` (c tau) in r_B past its peak (Levanon & Mozeson, Radar Signals, 2004, ch. 2),
    so a skirt contact lies up to that far in r_B from the echo, i.e. up to range_m / |grad r_B| along grad r_B in the
    world (grad r_B = u_T + u_R, |grad r_B| = 2 monostatic). Taken as uniform over +-that: variance (range_m /
    |grad r_B|)^2 / 3 added along the unit vector of grad r_B.

    Parameters
    ----------
    xy : ndarray (k, 2)
        Echo positions (m).
    R : ndarray (k, 2, 2)
        Their covariances (m^2).
    tx_xy, rx_xy : array (2,)
        Source and receiver (m).
    range_m : float
        The skirt's half-width in r_B (m).

    Returns
    -------
    numpy.ndarray
        (k, 2, 2) widened covariances (m^2).
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    grad = np.zeros_like(xy)
    for p in (tx_xy, rx_xy):
        d = xy - np.asarray(p, float)
        grad += d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    norm = np.maximum(np.linalg.norm(grad, axis=1), 1e-9)
    u = grad / norm[:, None]
    return np.asarray(R, float) + ((range_m / norm) ** 2 / 3.0)[:, None, None] * np.einsum("ki,kj->kij", u, u)
