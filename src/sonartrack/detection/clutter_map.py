"""A clutter map over pings: contacts whose world position recurs, still, ping after ping are stationary clutter.

A strong fixed scatterer (a wreck, a rock, a seamount's flank) echoes on every ping at the same place on the sea
floor. The navigation puts each contact in the world frame (systems/active/contacts.py), so such a point gives a
contact at the same world position whatever the ownship does, where a target's contacts drift by its speed times the
time between pings. Two tests, on each contact z_0 (covariance R_0, time t_0) of a new ping:

1. recurrence: each of the last ``span`` pings is a hit when one of its contacts z_j passes the gate
   (z_0 - z_j)^T (R_0 + R_j)^(-1) (z_0 - z_j) <= gamma, gamma the chi2_2 quantile at ``gate_probability`` (the
   difference of two independent measurements of one still point has covariance R_0 + R_j); the nearest in the gate
   is the ping's hit. Fewer than ``min_hits`` hits: not clutter.
2. stillness: the hits and z_0 are fitted by weighted least squares with a point moving at a constant velocity,
   z_j = a + v (t_j - t_0) + e_j, e_j ~ N(0, R_j) (information J = sum_j H_j^T R_j^-1 H_j, H_j = [I, (t_j - t_0) I]);
   the contact is clutter only when the fit shows the point slower than ``slow_mps``: the confidence ellipse of v
   at ``still_probability`` lies inside that speed, |v| + sqrt(gamma_s lambda_max(C_vv)) <= slow_mps (C_vv =
   [J^-1]_vv, gamma_s the chi2_2 quantile). The fit's points are taken in a wider gate than the hits', one that lets
   a point move at up to 2 ``slow_mps`` (R_0 + R_j + (2 slow_mps (t_j - t_0))^2 I).

The first test alone (the map of before) also marks a slow target's contacts: it matches a ping j back while its
drift v j T stays inside the gate (~3 sqrt(2) sigma; sigma 70 m, T 30 s, 3 hits: below ~3 m/s; at T 10 s it ate the
study's quick-scene 5 kn target). The second test spares it: a contact is clutter only once the fit has shown it
slower than ``slow_mps``, which takes time, not pings: the velocity of a straight line through n hits T apart is
known to sigma_v ~ sigma sqrt(12 / (n (n^2 - 1))) / T (sigma 70 m across the beam, T 30 s: 0.57 m/s at n = 5, so a
still point is clutter from its 5th-8th ping; at T 10 s it takes about the same time), and a target faster than
``slow_mps`` is never shown slower (but for the test's error). A still point not yet shown still goes to the
tracker, and a track may start on it; the chain holds back the confirmation of a track slower than ``slow_mps``
sitting on a recurring contact (tracking/deleters.py :class:`StillHold`: ``recurring`` is the mask it reads) until
its own speed shows it moving or the map withholds the point. A target slower than ``slow_mps`` from the moment it
enters the window is taken for clutter (a still target is a still echo: nothing in the positions tells them apart);
one that slows or stops after its track is confirmed keeps its contacts: the chain withholds clutter contacts only
from tracks that are not confirmed (systems/active/run.py), so a confirmed track still gets the contacts in its
gate, whether its target stops or passes over a clutter point.

A still point's echo gives more contacts than its own: its mirror twin (the same detection on the other side of the
array) and the images of its echo in the other beams (a line array's grating lobe: at a spacing of half a wavelength
a beam steered to one endfire hears the other endfire at nearly full gain, and sidelobes elsewhere). All of them have
the echo's travel time, so the point's bistatic range r_B = |z - Tx| + |z - Rx|, and none is still in the world
(the twin and the images move as the array turns and moves). Measured on the independent generator's K 1 world with 6
points of 35 dB (2 h): 14 of 36 false confirmed tracks sat at endfire ahead on a point's delay while the point was at
cone 160-175 deg, 9 on a point's mirror. :func:`same_range` marks the contacts of a ping whose r_B lies within
``image_range_m`` of a stronger recurring contact (recurring, not only still: near endfire a point's position is
known to a few hundred metres across the beam, and the stillness test does not pass in the map's 8 pings); the chain
withholds them, and the mirror twins of the clutter contacts, as it withholds the point. The price: a target's echo
within ``image_range_m`` in r_B of a stronger recurring echo is withheld at that ping from the tracks not confirmed.
Where the elements are more than half a wavelength apart a grating image can lie anywhere in cone, and its delay is
known only to the image's own band (the grating lobe passes a band ~ f_0 / N of the pulse): the chain withholds the
grating images of the contacts this map shows still in a wider r_B window (systems/active/contact_tracker.py
``EndfireAlias.clutter_range_m``; measured: study active-chain trial 18, 48 x 0.75 wavelength, 2 false pairs -> 0).

A CW still point is hidden from the map by the front end itself: it echoes at the stationary sea's Doppler in its own
direction, on its own beam's reverberation ridge, which the CW front end notches (detection/cw_cells.py). The chain's
contacts then hold only its delay-Doppler skirt past the notch and its sidelobe images in other beams, 0.4-2 km off
it, at varying places, on a fraction of the pings, with the CW's wide errors: none of them recurs still, and study
active-chain trial 15 (CW, 16 x 0.5 m, 2.4 kHz, K +5 dB) confirmed 9 false tracks in its reverberation-only hour, 8 of
them in mirror pairs on two points of TS 25-30 dB. So the chain also finds the echoes under the notch (cw_cells.py
``ridge_echoes``: the peaks of the statistic before the notch, at the single-ping threshold), which go to no track,
and gives them to a second map of this class, the ridge map (systems/active/contact_tracker.py ``ridge_map_of``,
4 hits of 8: the sea's own ridge peaks above the threshold, 10-20 a ping, recur by chance): a still point gives one
at its own place on every ping it stands above the ridge, and the recurrence and stillness tests show it still as any
other point. The notch itself is no stillness test: a target crossing the line of sight holds the sea's Doppler too
(zero world range rate), and is told from a still point only by its world position, which does not recur still. A
contact in the gate of a point the ridge map knows, or within a CW's ambiguity of an echo it shows still at the ping
(c tau in bistatic range and 2.5 Doppler cells in range rate, :func:`echo_images`: its skirt or its images), is
withheld as this map's clutter is. Measured (benchmarks/bench_active_family.py, 1 h reverberation-only twins): trial
15 9 -> 0 false confirmed tracks (5 -> 0 rows); trial 1 (8 elements, 1 kHz) 6 -> 4 (a TS 30 dB point near endfire,
cone 5-15 deg, whose hidden echoes, 300-540 m wide across the beam and on half the pings, the ridge map shows still
only from ping 58); benchmarks/bench_cw_ridge_map.py (default scene as CW, seeds 1, 2, the same contacts): rows and
held % of every target unchanged. The price: a contact within that window of a known still point's echo, wherever
its cone, is withheld from unconfirmed tracks on that ping; and the ridge map needs ~10 pings of the hidden echo (its
fit's time base) before it withholds anything, so a track confirmed on the images before then keeps them. (Until
then the places where the hidden echo recurs hold a slow track's confirmation and raise the clutter density of the
contacts in their skirt: systems/active/ridge_skirt.py; trial 11's twin 4 -> 0 false confirmed tracks.)

Memory. The recurrence test looks back ``span`` pings, the stillness fit ``fit_span`` (longer: the velocity's error
falls as T n^1.5), and a position once shown still is a known point for ``keep_pings`` pings after its last contact: a
contact in a known point's gate is clutter without a new fit, so a point whose contacts grow wide across the beam as
the geometry changes (a short array, a point drifting towards endfire) stays clutter (class doc: measured). The price:
a target passing within the gate of a known point is withheld from unconfirmed tracks while it is there.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from sonartrack.association.gating import gate_threshold


class ClutterMap:
    """Recurring still world positions over the last ``span`` pings (module doc).

    Parameters
    ----------
    span : int
        Pings remembered.
    min_hits : int
        A contact is clutter only when this many of the remembered pings hold a contact in its gate.
    gate_probability : float
        Probability of the chi-square(2) gate on the difference of two positions.
    still_probability : float or None
        Probability of the velocity's confidence ellipse in the stillness test (None: no stillness test, recurrence
        alone).
    slow_mps : float
        A contact is clutter only when its fit shows it slower than this (m/s).
    image_range_m : float or None
        A weaker contact of the same ping whose bistatic range is within this of a recurring contact's is a lobe image
        (module doc; :func:`same_range`), m; None: the clutter contacts alone (not their twins either).
    fit_span : int or None
        Pings the stillness fit reaches back (>= ``span``; None: ``span``): the velocity's error falls as the
        time base grows (sigma_v ~ sigma sqrt(12 / (n (n^2 - 1))) / T), and with 8 pings a still point whose contacts
        are 150 m across the beam is never shown slower than 1 m/s (measured below).
    keep_pings : int or None
        A position once shown still is remembered as clutter (a known point) until this many pings pass without a
        contact in its gate; a contact in the gate of a known point is clutter without a new fit (None: no memory).

    Measured (study active-chain trial 4, seed 2017, LFM 16 x 0.25 m, 14 points, 1 h reverberation-only, the map's
    verdicts replayed on the chain's own contacts): a TS 27 dB point recurred on every ping but was shown still on
    pings 1-33 only; from ping 34 its contacts' sd across the beam grew 110 -> 290 m and the 8-ping fit's bound passed
    1 m/s; a track confirmed on it at ping 44 held 77 pings (4 such false tracks in the hour).
    """

    def __init__(self, span: int = 8, min_hits: int = 3, gate_probability: float = 0.99,
                 still_probability: float | None = 0.9, slow_mps: float = 1.5, image_range_m: float | None = 15.0,
                 fit_span: int | None = 24, keep_pings: int | None = 24):
        self.span, self.min_hits, self.slow_mps = int(span), int(min_hits), float(slow_mps)
        self.fit_span = max(self.span, int(fit_span)) if fit_span is not None else self.span
        self.keep_pings = None if keep_pings is None else int(keep_pings)
        self.known = np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0)  # known still points: xy, R, last seen (s)
        self._ping_s = None
        self.image_range_m = None if image_range_m is None else float(image_range_m)
        self.gamma = float(gate_threshold(gate_probability, 2))
        self.still_gamma = None if still_probability is None else float(gate_threshold(still_probability, 2))
        self._pings: deque = deque(maxlen=self.fit_span)
        self.recurring = np.zeros(0, bool)  # the last update's contacts with >= min_hits hits (still or not)

    def update(self, xy: np.ndarray, R: np.ndarray, t_s: float = 0.0) -> np.ndarray:
        """Mark a ping's contacts, then remember them.

        Parameters
        ----------
        xy : ndarray (m, 2)
            Contact positions in the world frame (m).
        R : ndarray (m, 2, 2)
            Their covariances (m^2).
        t_s : float
            The ping's time (s): the stillness test's time base.

        Returns
        -------
        numpy.ndarray
            (m,) bool, True: clutter (hits on >= ``min_hits`` of the remembered pings, and still).
        """
        xy, R = np.asarray(xy, float).reshape(-1, 2), np.asarray(R, float).reshape(-1, 2, 2)
        info = np.zeros((len(xy), 4, 4))  # the fit's information J and vector b = sum H^T W (z - z_0)
        vec = np.zeros((len(xy), 4))
        hits = np.zeros(len(xy), np.int64)
        _add_point(info, vec, np.ones(len(xy), bool), np.zeros_like(xy), _inv2(R), 0.0)
        for age, (t_j, xy_j, R_j) in enumerate(reversed(self._pings)):
            if not (len(xy) and len(xy_j)):
                continue
            if age < self.span:  # recurrence: the last span pings; the fit reaches back fit_span
                hits += (mahalanobis2(xy, R, xy_j, R_j) <= self.gamma).any(axis=1)
            d2 = mahalanobis2(xy, R, xy_j, R_j, (2.0 * self.slow_mps * (t_j - t_s)) ** 2)
            near = np.argmin(d2, axis=1)
            on = d2[np.arange(len(xy)), near] <= self.gamma
            _add_point(info, vec, on, xy_j[near] - xy, _inv2(R_j[near]), t_j - t_s)
        self._step_s = float(t_s) - self._ping_s if self._ping_s is not None else None
        self._ping_s = float(t_s)
        self._pings.append((float(t_s), xy, R))
        clutter = hits >= self.min_hits
        self.recurring = clutter.copy()
        if self.still_gamma is not None and clutter.any():
            clutter[clutter] = speed_bound(info[clutter], vec[clutter], self.still_gamma) <= self.slow_mps
        return self._with_known(xy, R, float(t_s), clutter)

    def _with_known(self, xy: np.ndarray, R: np.ndarray, t_s: float, clutter: np.ndarray) -> np.ndarray:
        """``clutter`` or in the gate of a known still point; the points refreshed (keep_pings, class doc)."""
        if self.keep_pings is None:
            return clutter
        kxy, kR, seen = self.known
        if len(kxy) and len(xy):
            gate = mahalanobis2(xy, R, kxy, kR) <= self.gamma
            clutter = clutter | gate.any(axis=1)
            seen = np.where(gate.any(axis=0), t_s, seen)
        new = clutter & ~(mahalanobis2(xy, R, kxy, kR) <= self.gamma).any(axis=1) if len(kxy) else clutter
        kxy, kR, seen = np.concatenate([kxy, xy[new]]), np.concatenate([kR, R[new]]), np.concatenate(
            [seen, np.full(int(new.sum()), t_s)])
        step = self._step_s if self._step_s else 0.0
        alive = t_s - seen <= self.keep_pings * step
        self.known = kxy[alive], kR[alive], seen[alive]
        return clutter


def same_range(xy: np.ndarray, tx_xy, rx_xy, anchor: np.ndarray, statistic: np.ndarray, tol_m: float) -> np.ndarray:
    """The contacts of one ping weaker than an ``anchor`` contact whose bistatic range r_B = |z - Tx| + |z - Rx| lies
    within ``tol_m`` of the anchor's (module doc: a strong echo's lobe images share its travel time t = r_B / c and
    are weaker than it).

    Parameters
    ----------
    xy : ndarray (m, 2)
        The ping's contact positions (m).
    tx_xy, rx_xy : array (2,)
        Source and receiver at the ping (m).
    anchor : ndarray (m,) bool
        The contacts whose images are sought (the clutter map's recurring ones).
    statistic : ndarray (m,)
        Each contact's detection statistic: an image is strictly weaker than its anchor (so a mirror twin, of equal
        statistic, is not one).
    tol_m : float
        Half-width of the r_B window (m).

    Returns
    -------
    numpy.ndarray
        (m,) bool: within ``tol_m`` in r_B of a stronger anchor.
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    anchor, stat = np.asarray(anchor, bool), np.asarray(statistic, float)
    if not anchor.any():
        return np.zeros(len(xy), bool)
    r_b = np.linalg.norm(xy - np.asarray(tx_xy, float), axis=1) + np.linalg.norm(xy - np.asarray(rx_xy, float), axis=1)
    near = np.abs(r_b[:, None] - r_b[None, anchor]) <= tol_m
    return (near & (stat[:, None] < stat[None, anchor])).any(axis=1)


def _inv2(R: np.ndarray) -> np.ndarray:
    """Inverses of (n, 2, 2) covariances (closed form; a singular one gets zero weight)."""
    det = R[:, 0, 0] * R[:, 1, 1] - R[:, 0, 1] * R[:, 1, 0]
    inv = np.stack([np.stack([R[:, 1, 1], -R[:, 0, 1]], -1), np.stack([-R[:, 1, 0], R[:, 0, 0]], -1)], -2)
    return inv / np.where(det > 0, det, np.inf)[:, None, None]


def _add_point(info: np.ndarray, vec: np.ndarray, on: np.ndarray, dz: np.ndarray, W: np.ndarray, tau: float) -> None:
    """Add measurements dz (n, 2) at time offset tau with weights W (n, 2, 2) where ``on``: H = [I, tau I]."""
    w = W * on[:, None, None]
    info[:, :2, :2] += w
    info[:, :2, 2:] += tau * w
    info[:, 2:, :2] += tau * w
    info[:, 2:, 2:] += tau * tau * w
    wz = np.einsum("nij,nj->ni", w, dz)
    vec[:, :2] += wz
    vec[:, 2:] += tau * wz


def velocity_fit(info: np.ndarray, vec: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The weighted least-squares velocity of the fit z_j = a + v tau_j (module doc, test 2).

    Parameters
    ----------
    info : ndarray (n, 4, 4)
        J = sum_j H_j^T R_j^-1 H_j (H_j = [I, tau_j I]).
    vec : ndarray (n, 4)
        sum_j H_j^T R_j^-1 z_j.

    Returns
    -------
    tuple
        (ok (n,) bool: the fit has velocity information, v (n, 2) m/s, C_vv (n, 2, 2) (m/s)^2; NaN where not ok).
    """
    det = np.linalg.det(info)
    ok = np.isfinite(det) & (det > 0)
    v, C = np.full((len(info), 2), np.nan), np.full((len(info), 2, 2), np.nan)
    if ok.any():
        Ci = np.linalg.inv(info[ok])
        v[ok], C[ok] = np.einsum("nij,nj->ni", Ci, vec[ok])[:, 2:], Ci[:, 2:, 2:]
    return ok, v, C


def speed_bound(info: np.ndarray, vec: np.ndarray, gamma: float) -> np.ndarray:
    """|v| + sqrt(gamma lambda_max(C_vv)): the largest speed in the fitted velocity's confidence ellipse (m/s; inf
    where the fit has no velocity information).

    Parameters
    ----------
    info, vec : ndarray (n, 4, 4), (n, 4)
        As :func:`velocity_fit`.
    gamma : float
        The ellipse's chi-square(2) level.

    Returns
    -------
    numpy.ndarray
        (n,) speed (m/s).
    """
    ok, v, C = velocity_fit(info, vec)
    out = np.full(len(info), np.inf)
    if ok.any():
        lam = np.linalg.eigvalsh(C[ok])[:, -1]
        out[ok] = np.hypot(v[ok, 0], v[ok, 1]) + np.sqrt(gamma * np.maximum(lam, 0.0))
    return out


def mahalanobis2(xy_a: np.ndarray, R_a: np.ndarray, xy_b: np.ndarray, R_b: np.ndarray,
                 extra_m2: float = 0.0) -> np.ndarray:
    """(a, b): d^2 = (z_a - z_b)^T (R_a + R_b + extra I)^(-1) (z_a - z_b) (closed-form 2 x 2 inverse; inf if
    singular).

    Parameters
    ----------
    xy_a, xy_b : ndarray (a, 2), (b, 2)
        Positions (m).
    R_a, R_b : ndarray (a, 2, 2), (b, 2, 2)
        Covariances (m^2).
    extra_m2 : float
        Variance added on both axes (m^2).

    Returns
    -------
    numpy.ndarray
        (a, b) squared Mahalanobis distances.
    """
    d = xy_a[:, None, :] - xy_b[None, :, :]
    S = R_a[:, None] + R_b[None, :] + extra_m2 * np.eye(2)
    det = S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] * S[..., 1, 0]
    return (S[..., 1, 1] * d[..., 0] ** 2 - (S[..., 0, 1] + S[..., 1, 0]) * d[..., 0] * d[..., 1]
            + S[..., 0, 0] * d[..., 1] ** 2) / np.where(det > 0, det, np.inf)


def in_gate(xy_a: np.ndarray, R_a: np.ndarray, xy_b: np.ndarray, R_b: np.ndarray, gamma: float) -> np.ndarray:
    """(a, b) bool: d^2 = (z_a - z_b)^T (R_a + R_b)^(-1) (z_a - z_b) <= gamma, the positions (m) and covariances
    (m^2) as :func:`mahalanobis2`'s, ``gamma`` the gate threshold on d^2.

    Returns
    -------
    numpy.ndarray
        (a, b) bool.
    """
    return mahalanobis2(xy_a, R_a, xy_b, R_b) <= gamma


def echo_images(xy: np.ndarray, range_rate_mps: np.ndarray, tx_xy, rx_xy, echo_xy: np.ndarray,
                echo_rate_mps: np.ndarray, range_m: float, rate_mps: float) -> np.ndarray:
    """The contacts of one ping within ``range_m`` in bistatic range r_B = |z - Tx| + |z - Rx| AND ``rate_mps`` in
    bistatic range rate of an echo (a CW still point's, found under the ridge notch: detection/cw_cells.py
    ``ridge_echoes``): that echo's delay-Doppler skirt past the notch (a CW's ambiguity reaches one pulse length tau
    off in delay, its Doppler main lobe widening to 2 / tau half a pulse off: Levanon & Mozeson, Radar Signals,
    2004, ch. 2) and its sidelobe images in other beams (its own delay and Doppler), wherever in cone they fall.

    Parameters
    ----------
    xy : ndarray (m, 2)
        The ping's contact positions (m).
    range_rate_mps : ndarray (m,)
        Their measured bistatic range rates (m/s; NaN: none measured, never an image).
    tx_xy, rx_xy : array (2,)
        Source and receiver at the ping (m).
    echo_xy : ndarray (k, 2)
        The echoes' positions (m; either mirror: r_B is the same).
    echo_rate_mps : ndarray (k,)
        Their measured range rates (m/s).
    range_m, rate_mps : float
        Half-widths of the r_B (m) and range-rate (m/s) windows.

    Returns
    -------
    numpy.ndarray
        (m,) bool.
    """
    xy, e = np.asarray(xy, float).reshape(-1, 2), np.asarray(echo_xy, float).reshape(-1, 2)
    if not len(xy) or not len(e):
        return np.zeros(len(xy), bool)
    tx, rx = np.asarray(tx_xy, float), np.asarray(rx_xy, float)
    r_b = np.linalg.norm(xy - tx, axis=1) + np.linalg.norm(xy - rx, axis=1)
    r_e = np.linalg.norm(e - tx, axis=1) + np.linalg.norm(e - rx, axis=1)
    with np.errstate(invalid="ignore"):
        near = (np.abs(r_b[:, None] - r_e[None, :]) <= range_m) & (
            np.abs(np.asarray(range_rate_mps, float)[:, None] - np.asarray(echo_rate_mps, float)[None, :]) <= rate_mps)
    return near.any(axis=1)
