"""Measurement parts of a tracker: from predicted tracks and a scan to the likelihoods an associator weighs.

* :class:`PositionMeasurements` -- Cartesian points with their own covariances R_m (bistatic contacts,
  paper P4), chi-square gate of any mode, P_G fixed by the gate, clutter density per m^2.
* :class:`RangeRatePositionMeasurements` -- the same contacts with a measured bistatic range rate (a CW's
  Doppler): each pair's likelihood ratio times the range rate's (:func:`range_rate_log_factor`).
* :class:`BearingMeasurements` -- cross-correlation peaks (paper P0): a bearing with the track's own
  peak spread sigma_p (R = sigma_p^2 per track), the window gate of width V, and the amplitude
  threshold tau that lowers P_D to P_D0 Phi((z_hat - tau) / sigma_a) (association/amplitude.py). With
  ``amplitude_aided`` (JPDA_A) each pair weight is multiplied by the amplitude likelihood ratio r_tj,
  and with ``adaptive_strength`` the track strength follows eq. 9 after every update.

Equations: association/likelihood.py. Per-track quantities (sigma_p, strength, sigma_a) are the
tracks' ``attrs``.

Where several ships' peaks share one gate (the crossing configuration of the bearing tracker, with the
merged-measurement groups of tracking/resolution.py), two DEVIATIONS from P0 keep a quiet ship's track on its ship:
``own_peak_strength`` (eq. 9 on the track's own peak, :func:`own_peak_amplitude`) and ``gate_sds`` (a track's
window widened to its prediction's uncertainty, :func:`widened_gates`, only P0's window counting for its life,
:meth:`BearingMeasurements.counted_pairs`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.association.amplitude import amplitude_log_ratio, detection_probability_above, update_strength
from sonartrack.association.gating import gate_threshold
from sonartrack.association.likelihood import Likelihoods, position_likelihoods, window_likelihoods
from sonartrack.core.errors import require
from sonartrack.tracking.tracks import Scan


@dataclass(frozen=True)
class PositionMeasurements:
    """Position contacts z (m, 2) with covariances R (m, 2, 2) (P4)."""

    pd: float
    gate_probability: float
    clutter_density_per_m2: float

    measurement_dim = 2
    scan_needs = ("R",)

    def __post_init__(self):
        object.__setattr__(self, "_gamma", gate_threshold(self.gate_probability, 2))

    def likelihoods(self, x_pred, P_pred, scan: Scan, attrs: dict) -> Likelihoods:
        """Likelihoods of position contacts against the predicted tracks (chi-square gate; association/likelihood.py).

        Parameters
        ----------
        x_pred : ndarray, shape (n, r, d)
            Predicted mode-conditioned states ([x, y, vx, vy] in m and m/s).
        P_pred : ndarray, shape (n, r, d, d)
            Their covariances.
        scan : Scan
            Contacts z (m, 2) in m with covariances R (m, 2, 2) in m^2.
        attrs : dict
            Per-track quantities (unused).

        Returns
        -------
        Likelihoods
            Gated pairs and log likelihood ratios against clutter (per m^2).
        """
        return position_likelihoods(x_pred, P_pred, scan.z, scan.R, pd=self.pd, pg=self.gate_probability,
                                    gamma=self._gamma, clutter_density=self.clutter_density_per_m2)

    def after_update(self, attrs: dict, lik: Likelihoods, scan: Scan, beta_pair=None) -> dict:
        """Per-track quantities after the update: unchanged for position contacts.

        Parameters
        ----------
        attrs : dict
            Per-track quantities.
        lik : Likelihoods
            This scan's likelihoods.
        scan : Scan
            The scan.
        beta_pair : ndarray, optional
            The association probabilities (unused).

        Returns
        -------
        dict
            ``attrs`` itself.
        """
        return attrs


def range_rate_log_factor(x, P, rate_mps, tx, rx, rate_sd_mps: float, max_range_rate_mps: float) -> np.ndarray:
    """log of the range rate's factor on a contact's likelihood ratio in P4's IMM-IPDA (log p_r / rho_r).

    The measurement is z = (position, rdot); given the state x = [p, v] the two errors are independent, so its
    density is p(z | x) = N(z_p; H x, S) N(rdot; h(x), s^2), and a false contact's density is the clutter density
    in the plane times a uniform one in rate on [-v_max, v_max] (the Doppler bank's span): rho = lambda / (2 v_max).
    The likelihood ratio of the pair (track, contact) that enters the PDA weights and the IPDA existence update
    (Musicki, Evans, Stankovic, IEEE Trans. AC 39(6), 1994, eqs. 16-19: p_j / rho) is then

        L = [P_D P_G N(z_p; H x, S) / lambda] x [N(rdot; h(x), s^2) 2 v_max],

    the feature-aided PDA (a measured feature whose false-alarm law is known multiplies each ratio: Lerro and
    Bar-Shalom, IEEE Trans. AES 29(4), 1993, eq. 12, for the amplitude; Bar-Shalom, Willett, Tian, Tracking and
    Data Fusion, 2011, sec. 3.4.4). h(x) = u_T . (v - v_T) + u_R . (v - v_R) (systems/active/contacts.py), u_T, u_R
    the unit vectors from the source and the receiver to p, linearised at the predicted state:
    s^2 = sd^2 + g P g^T, g = [dh/dp, dh/dv], dh/dv = u_T + u_R, dh/dp = (I - u_T u_T^T)(v - v_T) / |p - T|
    + (I - u_R u_R^T)(v - v_R) / |p - R|. The position gate is left alone (the factor only weighs). The function
    returns log(2 v_max) - log(sqrt(2 pi) s) - (rdot - h)^2 / (2 s^2); 0 where the rate is NaN (not measured).

    Parameters
    ----------
    x : ndarray (G, r, 4)
        Predicted mode-conditioned states [x, y, vx, vy] (m, m/s) of the gated pairs' tracks.
    P : ndarray (G, r, 4, 4)
        Their covariances.
    rate_mps : ndarray (G,)
        The pairs' measured bistatic range rates (m/s; NaN: none).
    tx, rx : tuple of (position (2,), velocity (2,))
        Source and receiver at the scan (m, m/s).
    rate_sd_mps, max_range_rate_mps : float
        Standard deviation of a measured rate and the half-span of the rates searched (m/s).

    Returns
    -------
    numpy.ndarray
        (G, r) log factors.
    """
    p, v = x[..., :2], x[..., 2:4]
    g = np.zeros(x.shape)
    h = np.zeros(x.shape[:-1])
    for xy, vel in (tx, rx):
        d = p - np.asarray(xy, float)
        dist = np.linalg.norm(d, axis=-1, keepdims=True)
        u = d / np.maximum(dist, 1e-9)
        w = v - np.asarray(vel, float)
        uw = np.sum(u * w, axis=-1, keepdims=True)
        h += uw[..., 0]
        g[..., :2] += (w - u * uw) / np.maximum(dist, 1e-9)
        g[..., 2:4] += u
    s2 = rate_sd_mps**2 + np.einsum("...i,...ij,...j->...", g, P, g)
    r = np.asarray(rate_mps, float)[:, None]
    out = np.log(2.0 * max_range_rate_mps) - 0.5 * np.log(2.0 * np.pi * s2) - 0.5 * (r - h) ** 2 / s2
    return np.where(np.isfinite(r), out, 0.0)


@dataclass(frozen=True)
class RangeRatePositionMeasurements(PositionMeasurements):
    """Position contacts whose measured bistatic range rate weighs each pair (:func:`range_rate_log_factor`).

    ``rate_sd_mps`` and ``max_range_rate_mps`` (m/s) are the measurement's; the scan's platforms ``tx``, ``rx``
    ((position, velocity) each) and contact rates ``range_rate_mps`` (m,) are set per scan with :meth:`at_scan`
    (until then, and for NaN rates, the factor is 1)."""

    rate_sd_mps: float = 1.0
    max_range_rate_mps: float = 15.0
    tx: tuple | None = None
    rx: tuple | None = None
    range_rate_mps: np.ndarray | None = None

    def at_scan(self, tx, rx, range_rate_mps, clutter_density_per_m2: float | None = None
                ) -> RangeRatePositionMeasurements:
        """This measurement part for one scan (and its clutter density, when given).

        Parameters
        ----------
        tx, rx : tuple of (array (2,), array (2,))
            Source and receiver (position m, velocity m/s) at the scan.
        range_rate_mps : array (m,)
            The scan's contacts' measured range rates (m/s; NaN: none).
        clutter_density_per_m2 : float, optional
            lambda for this scan (1/m^2); None: unchanged.

        Returns
        -------
        RangeRatePositionMeasurements
            A copy holding them.
        """
        lam = self.clutter_density_per_m2 if clutter_density_per_m2 is None else float(clutter_density_per_m2)
        return replace(self, tx=tx, rx=rx, range_rate_mps=np.asarray(range_rate_mps, float),
                       clutter_density_per_m2=lam)

    def likelihoods(self, x_pred, P_pred, scan: Scan, attrs: dict) -> Likelihoods:
        """P4's position likelihoods (:class:`PositionMeasurements`) with each gated pair's ratio times its range
        rate's factor (:func:`range_rate_log_factor`).

        Parameters
        ----------
        x_pred : ndarray, shape (n, r, 4)
            Predicted mode-conditioned states (m, m/s).
        P_pred : ndarray, shape (n, r, 4, 4)
            Their covariances.
        scan : Scan
            Contacts z (m, 2) in m with covariances R (m, 2, 2); their rates are :meth:`at_scan`'s.
        attrs : dict
            Per-track quantities (unused).

        Returns
        -------
        Likelihoods
            Gated pairs and log likelihood ratios against clutter.
        """
        lik = super().likelihoods(x_pred, P_pred, scan, attrs)
        rate = self.range_rate_mps
        if rate is None or self.tx is None or not len(lik.pair_track):
            return lik
        require(len(rate) == len(scan), f"{len(rate)} range rates for {len(scan)} contacts: give one per contact")
        add = range_rate_log_factor(x_pred[lik.pair_track], P_pred[lik.pair_track], rate[lik.pair_meas], self.tx,
                                    self.rx, self.rate_sd_mps, self.max_range_rate_mps)
        dense = None
        if lik.dense_log_ratio is not None:
            dense = lik.dense_log_ratio.copy()
            dense[lik.pair_track, :, lik.pair_meas] += add
        return replace(lik, pair_log_ratio=lik.pair_log_ratio + add, dense_log_ratio=dense)


@dataclass(frozen=True)
class AmplitudeRangeRateMeasurements(RangeRatePositionMeasurements):
    """:class:`RangeRatePositionMeasurements` whose contacts' amplitudes (their detector's statistic) weigh each pair
    by the amplitude likelihood ratio p1(a | target) / p0(a | clutter) above the threshold (Lerro & Bar-Shalom 1993,
    eq. 12; association/amplitude_ipda.py), in the PDA weights and, through Lambda, in IPDA's existence update.

    ``model`` (:class:`~sonartrack.association.amplitude_ipda.AmplitudeModel`) holds the clutter law, fed each scan
    by the initiator (tracking/initiators.py :class:`AmplitudeOnePointInitiator`); each track carries ``amp_w`` (sum
    of its association weights, forgotten by ``target_memory`` a scan) and ``amp_sum`` (the same sum of w a) in its
    attrs, updated after each scan (:meth:`after_update`). DEVIATION: the weights are the pairs' PDA weights averaged
    over the modes with equal weight (the mode probabilities are not the measurement part's)."""

    model: object = None
    target_memory: float = 0.9

    scan_needs = ("R", "amplitude")

    def likelihoods(self, x_pred, P_pred, scan: Scan, attrs: dict) -> Likelihoods:
        """The range-rate position likelihoods with each gated pair's log ratio plus its amplitude's (class doc)."""
        lik = super().likelihoods(x_pred, P_pred, scan, attrs)
        if self.model is None or scan.amplitude is None or not len(lik.pair_track):
            return lik
        t, j = lik.pair_track, lik.pair_meas
        add = self.model.log_ratio(scan.amplitude[j], _attr(attrs, "amp_w", len(x_pred))[t],
                                   _attr(attrs, "amp_sum", len(x_pred))[t])[:, None]
        dense = None
        if lik.dense_log_ratio is not None:
            dense = lik.dense_log_ratio.copy()
            dense[t, :, j] += add
        return replace(lik, pair_log_ratio=lik.pair_log_ratio + add, dense_log_ratio=dense)

    def after_update(self, attrs: dict, lik: Likelihoods, scan: Scan, beta_pair=None) -> dict:
        """Each track's amplitude sums forgotten by ``target_memory`` and the scan's pairs added with their weights
        (mode-averaged ``beta_pair`` (G, r)); the other attrs unchanged."""
        n = lik.gated.shape[0]
        w, s = _attr(attrs, "amp_w", n) * self.target_memory, _attr(attrs, "amp_sum", n) * self.target_memory
        if beta_pair is not None and scan.amplitude is not None and len(lik.pair_track):
            b = np.asarray(beta_pair, float).reshape(len(lik.pair_track), -1).mean(axis=1)
            w = w + np.bincount(lik.pair_track, weights=b, minlength=n)
            s = s + np.bincount(lik.pair_track, weights=b * scan.amplitude[lik.pair_meas], minlength=n)
        return {**attrs, "amp_w": w, "amp_sum": s}


def _attr(attrs: dict, name: str, n: int) -> np.ndarray:
    """A per-track attr as floats, zeros when the tracks do not carry it."""
    v = attrs.get(name)
    return np.zeros(n) if v is None else np.asarray(v, float)


def fold_cone_deg(phi_deg) -> tuple[np.ndarray, np.ndarray]:
    """The cone angle theta in [0, 180] deg of an unfolded angle phi, and the fold's slope d theta / d phi (+1 or -1).

    A target that passes through endfire (the array's axis) has a cone angle that reflects at 0 or 180 deg while
    its true bearing h + phi (on the side it started) moves on smoothly; the tracker follows phi, which runs on
    through 180 (or below 0), and the array measures theta = fold(phi) = |((phi + 180) mod 360) - 180|. Each
    pass of phi through a multiple of 180 deg is one crossing of the array's axis: the target changes side.

    Parameters
    ----------
    phi_deg : array_like
        Unfolded cone angles (deg).

    Returns
    -------
    (ndarray, ndarray)
        theta (deg, 0..180) and the slope (+1 where theta = phi mod 360, -1 on the mirrored half).
    """
    r = np.mod(np.asarray(phi_deg, float), 360.0)
    mirrored = r > 180.0
    return np.where(mirrored, 360.0 - r, r), np.where(mirrored, -1.0, 1.0)


def fold_cone_state(x):
    """States [phi, phi rate] (..., 2) folded into [theta, theta rate], and the fold's slope (:func:`fold_cone_deg`;
    the covariance is unchanged: the Jacobian diag(s, s) with s = +-1 gives J P J = P).

    Parameters
    ----------
    x : array (..., 2)
        Unfolded cone angle phi (deg) and its rate, in the rate unit of the state.

    Returns
    -------
    state : numpy.ndarray
        (..., 2) [theta (deg, 0..180 from the array's forward axis), theta rate].
    sign : numpy.ndarray
        (...,) the slope s (+1 or -1).
    """
    theta, sign = fold_cone_deg(x[..., 0])
    out = np.array(x, float, copy=True)
    out[..., 0] = theta
    out[..., 1] = x[..., 1] * sign
    return out, sign


@dataclass(frozen=True)
class BearingMeasurements:
    """Bearing peaks (deg) with amplitudes (P0); tracks carry ``sigma_p``, ``strength`` and ``sigma_a``."""

    p_detect: float
    gate_deg: float
    clutter_density_per_deg: float
    amplitude_threshold: float
    false_amplitude_rate: float
    amplitude_aided: bool  # JPDA_A: weigh the peak amplitudes
    adaptive_strength: bool  # eq. 9 strength update (JPDA_A only, as in the paper)
    #: a line array's cone angle: the state is the unfolded angle phi (through endfire), measured as fold(phi)
    endfire_fold: bool = False
    #: eq. 9 on the track's own peak (its likeliest association, when more likely than not) instead of the largest
    #: amplitude in its gate (:meth:`after_update`): where two ships' peaks share a gate
    own_peak_strength: bool = False
    #: 0: P0's window of width V; else each track's half-window is at least this many sds of its prediction
    #: sqrt(S) (:func:`widened_gates`)
    gate_sds: float = 0.0

    measurement_dim = 1
    scan_needs = ("amplitude",)

    def likelihoods(self, x_pred, P_pred, scan: Scan, attrs: dict) -> Likelihoods:
        """Likelihoods of bearing peaks with a window gate and the amplitude threshold (paper P0; module docstring).

        Parameters
        ----------
        x_pred : ndarray, shape (n, r, 2)
            Predicted [bearing (deg), bearing rate (deg/s)]; for a line array the bearing is the cone angle
            from its axis.
        P_pred : ndarray, shape (n, r, 2, 2)
            Their covariances.
        scan : Scan
            Peaks z (m, 1) in deg with amplitudes (m,).
        attrs : dict
            Per-track ``sigma_p`` (deg), ``strength`` and ``sigma_a`` (amplitude units), each (n,).

        Returns
        -------
        Likelihoods
            Gated pairs and log ratios (clutter per deg; with ``amplitude_aided`` the amplitude ratio included).
        """
        strength, sigma_a = attrs["strength"], attrs["sigma_a"]
        pd_eff = np.clip(detection_probability_above(self.p_detect, strength, np.maximum(sigma_a, 1e-9),
                                                     self.amplitude_threshold), 1e-6, 1.0)
        extra, pd_hit = None, pd_eff
        if self.amplitude_aided:
            # P_D x (true amplitude density above tau) = P_D0 N(a; z_hat, sigma_a^2): the hit weight takes P_D0
            extra = amplitude_log_ratio(scan.amplitude, strength, sigma_a, self.false_amplitude_rate,
                                        self.amplitude_threshold)
            pd_hit = np.full(len(strength), self.p_detect)
        half = self.gate_deg / 2.0
        if self.gate_sds > 0.0:
            S = P_pred[:, :, 0, 0].max(axis=1, initial=0.0) + np.asarray(attrs["sigma_p"], float) ** 2
            half = np.maximum(half, self.gate_sds * np.sqrt(S))
        width = 2.0 * float(np.max(half, initial=self.gate_deg / 2.0))
        folded, sign = fold_cone_state(x_pred) if self.endfire_fold else (x_pred, None)
        lik = window_likelihoods(folded, P_pred, scan.z[:, 0], attrs["sigma_p"], gate_width=width,
                                 pd_hit=pd_hit, pd_miss=pd_eff, clutter_density=self.clutter_density_per_deg,
                                 log_ratio_extra=extra)
        if self.gate_sds > 0.0:
            lik = widened_gates(lik, half, P_pred, attrs["sigma_p"], pd_eff)
        if sign is None:
            return lik
        # the innovation of the unfolded state: z - fold(phi) read back through the fold's slope (+1 or -1)
        return replace(lik, nu=lik.nu * sign[lik.pair_track][:, :, None])

    def counted_pairs(self, lik: Likelihoods) -> np.ndarray:
        """Which gated pairs count as a hit (a track's life, tracking/deleters.py) and use their peak (no new track
        on it, tracking/initiators.py): those within P0's window V / 2. A gate widened by ``gate_sds``
        (:func:`widened_gates`) lets an uncertain track take its ship's peak where it reappears, but a peak only
        in the widened part neither keeps the track alive (else a track whose ship is hidden, its sd growing, is
        never dropped and wanders onto another ship: study trial 1, three ships within one beam at endfire) nor
        stops a new track from starting on it.

        Parameters
        ----------
        lik : Likelihoods
            The scan's likelihoods.

        Returns
        -------
        ndarray of bool, shape (G,)
            Per gated pair.
        """
        return np.abs(lik.nu[:, 0, 0]) <= self.gate_deg / 2.0

    def after_update(self, attrs: dict, lik: Likelihoods, scan: Scan, beta_pair=None) -> dict:
        """Track strength update, paper P0 eq. 9: ``z_hat = 0.7 z_hat + 0.3`` (largest amplitude in the gate).

        Only with ``amplitude_aided`` and ``adaptive_strength``; tracks with an empty gate keep theirs.

        With ``own_peak_strength`` (and the association weights ``beta_pair``) the amplitude is that of the track's
        own peak instead: the gated peak of its largest association probability beta_tj, when beta_tj > 1/2 (more
        likely than not the track's), else none (the strength kept, as for an empty gate). DEVIATION from P0's
        largest amplitude in the gate, which assumes one target per gate: where a loud ship comes within half a
        gate of a quiet ship's track, the largest amplitude is the loud ship's, the quiet track's strength rises to
        it within a few scans, and JPDA_A's amplitude ratio then gives the quiet track the loud ship's peak and
        calls its own peak clutter (measured: 24 x 1.5 m, a trawler's track at z 26 rose to 40, the merchant's z,
        while the merchant passed within 3 deg; after their crossing it took the merchant's peak).

        Parameters
        ----------
        attrs : dict
            Per-track quantities, ``strength`` among them.
        lik : Likelihoods
            This scan's likelihoods (their gates).
        scan : Scan
            The scan (amplitudes).

        beta_pair : ndarray, shape (G, r), optional
            The gated pairs' association probabilities (used with ``own_peak_strength``).

        Returns
        -------
        dict
            ``attrs`` with ``strength`` updated (or unchanged).
        """
        if not (self.amplitude_aided and self.adaptive_strength):
            return attrs
        if self.own_peak_strength and beta_pair is not None:
            return {**attrs, "strength": update_strength(attrs["strength"],
                                                         own_peak_amplitude(lik, beta_pair, scan.amplitude))}
        amax = np.where(lik.gated, scan.amplitude[None, :], -np.inf).max(axis=1, initial=-np.inf)
        return {**attrs, "strength": update_strength(attrs["strength"], np.where(np.isfinite(amax), amax, np.nan))}


def own_peak_amplitude(lik: Likelihoods, beta_pair, amplitude) -> np.ndarray:
    """Each track's own peak amplitude: that of its gated peak of largest association probability, where that
    probability exceeds 1/2; NaN elsewhere (:meth:`BearingMeasurements.after_update`).

    Parameters
    ----------
    lik : Likelihoods
        The scan's gated pairs (``pair_track``, ``pair_meas``).
    beta_pair : ndarray, shape (G, r)
        The pairs' association probabilities (the first mode's are used: the bearing tracker has one).
    amplitude : ndarray, shape (m,)
        The scan's peak amplitudes.

    Returns
    -------
    ndarray, shape (n,)
        The amplitude, or NaN.
    """
    out = np.full(lik.gated.shape[0], np.nan)
    beta = np.asarray(beta_pair, float)[:, 0]
    order = np.lexsort((beta, lik.pair_track))  # by track, then by probability: each track's largest is its last
    last = order[np.r_[lik.pair_track[order][1:] != lik.pair_track[order][:-1], True]] if len(order) else order
    mine = last[beta[last] > 0.5]
    out[lik.pair_track[mine]] = np.asarray(amplitude, float)[lik.pair_meas[mine]]
    return out


def widened_gates(lik: Likelihoods, half_deg, P_pred, sigma_p, pd_miss) -> Likelihoods:
    """The likelihoods of a window as wide as the widest track's, each track's gate cut back to its own half-width
    ``half_deg`` (deg, (n,)): pairs outside it dropped, and its miss weight 1 - P_D P_G with P_G = erf(h / sqrt(2 S))
    of its own width (association/likelihood.py ``window_likelihoods``).

    DEVIATION from P0's one window V for every track: a track's half-window is max(V / 2, g sqrt(S)) (S = P-[0, 0]
    + sigma_p^2, g = ``gate_sds``). P0's tracks are all about as certain, and V covers them; a member of an
    unresolved pair whose ship the merged peak hides (tracking/resolution.py: its update weight 1 - w is small) or a
    track of unknown side through the array's turn (tracking/own_motion.py) has a prediction several degrees
    uncertain, and a fixed window then loses its ship when it reappears: measured, a trawler's member at sd 2.5 deg
    3.9 deg from its reappearing peak, outside the 3 deg half-window, coasted as a ghost and a new track took the
    trawler (32 x 1.0 m); a track of unknown side at sd 5.8 deg in a 1 deg/s turn was dropped (study trial 1).
    Tracks with g sqrt(S) <= V / 2 keep P0's window exactly.

    Parameters
    ----------
    lik : Likelihoods
        From ``window_likelihoods`` with the widest window.
    half_deg : ndarray, shape (n,)
        Each track's half-window (deg).
    P_pred : ndarray, shape (n, r, 2, 2)
        The predicted covariances.
    sigma_p : ndarray, shape (n,)
        Per-track peak spread (deg).
    pd_miss : ndarray, shape (n,)
        P_D in the miss weight.

    Returns
    -------
    Likelihoods
        The same likelihoods on each track's own gate.
    """
    from scipy.special import erf

    half = np.broadcast_to(np.asarray(half_deg, float), (lik.gated.shape[0],))
    keep = np.abs(lik.nu[:, 0, 0]) <= half[lik.pair_track]
    gated = np.zeros_like(lik.gated)
    gated[lik.pair_track[keep], lik.pair_meas[keep]] = True
    S = P_pred[:, :, 0, 0] + np.asarray(sigma_p, float)[:, None] ** 2
    miss = 1.0 - np.asarray(pd_miss, float)[:, None] * erf(half[:, None] / np.sqrt(2.0 * S))
    dense = None if lik.dense_log_ratio is None else np.where(gated[:, None, :], lik.dense_log_ratio, -np.inf)
    return replace(lik, pair_log_ratio=lik.pair_log_ratio[keep], gated=gated, miss=miss, dense_log_ratio=dense,
                   pair_track=lik.pair_track[keep], pair_meas=lik.pair_meas[keep], nu=lik.nu[keep],
                   S_inv=lik.S_inv[keep])
