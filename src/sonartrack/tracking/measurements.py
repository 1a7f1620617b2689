"""Measurement parts of a tracker: from predicted tracks and a scan to the likelihoods an associator weighs.

* :class:`PositionMeasurements` -- Cartesian points with their own covariances R_m (bistatic contacts,
  paper P4), chi-square gate of any mode, P_G fixed by the gate, clutter density per m^2.
* :class:`BearingMeasurements` -- cross-correlation peaks (paper P0): a bearing with the track's own
  peak spread sigma_p (R = sigma_p^2 per track), the window gate of width V, and the amplitude
  threshold tau that lowers P_D to P_D0 Phi((z_hat - tau) / sigma_a) (association/amplitude.py). With
  ``amplitude_aided`` (JPDA_A) each pair weight is multiplied by the amplitude likelihood ratio r_tj,
  and with ``adaptive_strength`` the track strength follows eq. 9 after every update.

Equations: association/likelihood.py. Per-track quantities (sigma_p, strength, sigma_a) are the
tracks' ``attrs``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.association.amplitude import amplitude_log_ratio, detection_probability_above, update_strength
from sonartrack.association.gating import gate_threshold
from sonartrack.association.likelihood import Likelihoods, position_likelihoods, window_likelihoods
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

    def after_update(self, attrs: dict, lik: Likelihoods, scan: Scan) -> dict:
        """Per-track quantities after the update: unchanged for position contacts.

        Parameters
        ----------
        attrs : dict
            Per-track quantities.
        lik : Likelihoods
            This scan's likelihoods.
        scan : Scan
            The scan.

        Returns
        -------
        dict
            ``attrs`` itself.
        """
        return attrs


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
        if not self.endfire_fold:
            return window_likelihoods(x_pred, P_pred, scan.z[:, 0], attrs["sigma_p"], gate_width=self.gate_deg,
                                      pd_hit=pd_hit, pd_miss=pd_eff, clutter_density=self.clutter_density_per_deg,
                                      log_ratio_extra=extra)
        folded, sign = fold_cone_state(x_pred)
        lik = window_likelihoods(folded, P_pred, scan.z[:, 0], attrs["sigma_p"], gate_width=self.gate_deg,
                                 pd_hit=pd_hit, pd_miss=pd_eff, clutter_density=self.clutter_density_per_deg,
                                 log_ratio_extra=extra)
        # the innovation of the unfolded state: z - fold(phi) read back through the fold's slope (+1 or -1)
        return replace(lik, nu=lik.nu * sign[lik.pair_track][:, :, None])

    def after_update(self, attrs: dict, lik: Likelihoods, scan: Scan) -> dict:
        """Track strength update, paper P0 eq. 9: ``z_hat = 0.7 z_hat + 0.3`` (largest amplitude in the gate).

        Only with ``amplitude_aided`` and ``adaptive_strength``; tracks with an empty gate keep theirs.

        Parameters
        ----------
        attrs : dict
            Per-track quantities, ``strength`` among them.
        lik : Likelihoods
            This scan's likelihoods (their gates).
        scan : Scan
            The scan (amplitudes).

        Returns
        -------
        dict
            ``attrs`` with ``strength`` updated (or unchanged).
        """
        if not (self.amplitude_aided and self.adaptive_strength):
            return attrs
        amax = np.where(lik.gated, scan.amplitude[None, :], -np.inf).max(axis=1, initial=-np.inf)
        return {**attrs, "strength": update_strength(attrs["strength"], np.where(np.isfinite(amax), amax, np.nan))}
