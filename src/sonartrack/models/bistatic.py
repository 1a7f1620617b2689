"""Bistatic active sonar: from (travel time, bearing, array heading, sound speed, Tx, Rx) to a point.

Geometry (Park, Song, Lee 2017, Fig. 1 and eqs. 2-6; DIGEST P4). The transmitter Tx and the
receiver Rx are at different places. The sonar measures the total travel time t (Tx -> target ->
Rx), the bearing theta of the echo *relative to the receiving array's axis*, whose heading phi is
known, and assumes a mean sound speed c. With

    r_B = c t                      total (bistatic) path length
    L   = Tx - Rx                  baseline vector, from Rx to Tx
    beta = phi + theta             absolute bearing at Rx, clockwise from north
    u   = [sin beta, cos beta]     unit vector from Rx towards the target

the Rx-to-target range follows from |r_R u - L| = r_B - r_R:

    r_R = (r_B^2 - |L|^2) / (2 (r_B - u . L)),      target = Rx + r_R u             (eq. 2)

Input vector order used for Jacobians and covariances (8 inputs):
``p = [t, theta, phi, c, Tx_x, Tx_y, Rx_x, Rx_y]``. The covariance of the point is
``J Sigma J^T`` (eqs. 3-6), J = d(target)/dp evaluated at the *measured* inputs, Sigma diagonal
(independent errors). Derivatives, with D = 2 (r_B - u . L) and u' = du/dbeta = [cos beta, -sin beta]:

    d r_R / d r_B  = 2 (r_B - r_R) / D          (r_B = c t:  d/dt = c d/dr_B,  d/dc = t d/dr_B)
    d r_R / d beta = 2 r_R (u' . L) / D
    d r_R / d L    = 2 (r_R u - L) / D           (L = Tx - Rx)
    d target / d beta = (d r_R / d beta) u + r_R u'
    d target / d Tx   = u (d r_R / d L)^T,       d target / d Rx = I - u (d r_R / d L)^T

The map is nonlinear, so the point computed from noisy inputs is biased; the P4 study measures the
bias by Monte Carlo (it is small against the spread at the paper's geometry).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle


@dataclass(frozen=True, slots=True)
class BistaticErrors:
    """Standard deviations of the bistatic inputs (independent, zero-mean Gaussian)."""

    sigma_time_s: float = 0.01
    sigma_bearing_rad: float = np.deg2rad(0.5)
    sigma_heading_rad: float = 0.0
    sigma_sound_speed_mps: float = 7.5
    sigma_position_m: float = 30.0

    def variances(self, sigma_bearing_rad=None) -> np.ndarray:
        """Diagonal of Sigma in input order ``[t, theta, phi, c, Tx_x, Tx_y, Rx_x, Rx_y]``.

        Units: s^2, rad^2, rad^2, m^2/s^2, then m^2 for the four coordinates.

        Parameters
        ----------
        sigma_bearing_rad : float or array_like, optional
            Bearing standard deviation (rad) to use instead of the field, e.g. one per measurement.

        Returns
        -------
        ndarray, shape (..., 8)
            Variances; leading shape that of ``sigma_bearing_rad``.
        """
        sb = self.sigma_bearing_rad if sigma_bearing_rad is None else np.asarray(sigma_bearing_rad, float)
        sb2 = np.asarray(sb, float) ** 2
        base = np.array([self.sigma_time_s**2, 0.0, self.sigma_heading_rad**2, self.sigma_sound_speed_mps**2]
                        + [self.sigma_position_m**2] * 4)
        out = np.broadcast_to(base, np.shape(sb2) + (8,)).copy()
        out[..., 1] = sb2
        return out


def bistatic_position(t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy):
    """Target position from bistatic inputs, Park, Song, Lee 2017, eq. 2.

    ``r_R = (r_B^2 - |L|^2) / (2 (r_B - u . L))``, target = Rx + r_R u (module docstring).

    Parameters
    ----------
    t_s : float or array_like, shape (...)
        Total travel time Tx -> target -> Rx (s).
    theta_rad : float or array_like
        Echo bearing relative to the receiving array's heading (rad, clockwise).
    phi_rad : float or array_like
        Array heading (rad, clockwise from north).
    c_mps : float or array_like
        Mean sound speed (m/s).
    tx_xy, rx_xy : array_like, shape (..., 2)
        Transmitter and receiver positions [x east, y north] (m).

    Returns
    -------
    position : ndarray, shape (..., 2)
        Target position [x, y] (m).
    r_R : ndarray, shape (...)
        Receiver-to-target range (m).
    """
    rb = np.asarray(c_mps, float) * np.asarray(t_s, float)
    beta = np.asarray(phi_rad, float) + np.asarray(theta_rad, float)
    u = np.stack([np.sin(beta), np.cos(beta)], axis=-1)
    L = np.asarray(tx_xy, float) - np.asarray(rx_xy, float)
    uL = np.einsum("...i,...i->...", u, L)
    rr = (rb**2 - np.einsum("...i,...i->...", L, L)) / (2.0 * (rb - uL))
    return np.asarray(rx_xy, float) + rr[..., None] * u, rr


def bistatic_jacobian(t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy):
    """Jacobian J of the target position with respect to the 8 inputs (eqs. 3-6; derivatives in the module docstring).

    Parameters
    ----------
    t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy
        As :func:`bistatic_position` (s, rad, rad, m/s, m, m).

    Returns
    -------
    ndarray, shape (..., 2, 8)
        d[x, y] / d[t, theta, phi, c, Tx_x, Tx_y, Rx_x, Rx_y] (m/s, m/rad, m/rad, s, 1, 1, 1, 1).
    """
    t = np.asarray(t_s, float)
    c = np.asarray(c_mps, float)
    rb = c * t
    beta = np.asarray(phi_rad, float) + np.asarray(theta_rad, float)
    u = np.stack([np.sin(beta), np.cos(beta)], axis=-1)
    du = np.stack([np.cos(beta), -np.sin(beta)], axis=-1)
    L = np.asarray(tx_xy, float) - np.asarray(rx_xy, float)
    uL = np.einsum("...i,...i->...", u, L)
    D = 2.0 * (rb - uL)
    rr = (rb**2 - np.einsum("...i,...i->...", L, L)) / D
    drr_drb = 2.0 * (rb - rr) / D
    drr_dbeta = 2.0 * rr * np.einsum("...i,...i->...", du, L) / D
    drr_dL = 2.0 * (rr[..., None] * u - L) / D[..., None]
    shape = np.broadcast_shapes(rb.shape, beta.shape, L.shape[:-1])
    J = np.zeros(shape + (2, 8))
    J[..., :, 0] = (drr_drb * c)[..., None] * u
    dpos_dbeta = drr_dbeta[..., None] * u + rr[..., None] * du
    J[..., :, 1] = dpos_dbeta
    J[..., :, 2] = dpos_dbeta
    J[..., :, 3] = (drr_drb * t)[..., None] * u
    dtx = u[..., :, None] * drr_dL[..., None, :]
    J[..., :, 4:6] = dtx
    J[..., :, 6:8] = np.eye(2) - dtx
    return J


def bistatic_covariance(t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy, variances):
    """Covariance ``J Sigma J^T`` of the bistatic point, Sigma = diag(variances) (eqs. 3-6).

    Parameters
    ----------
    t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy
        As :func:`bistatic_position`, at the measured values.
    variances : array_like, shape (..., 8)
        Input variances in the order of :meth:`BistaticErrors.variances`.

    Returns
    -------
    ndarray, shape (..., 2, 2)
        Position covariance (m^2).
    """
    J = bistatic_jacobian(t_s, theta_rad, phi_rad, c_mps, tx_xy, rx_xy)
    return np.einsum("...ik,...k,...jk->...ij", J, np.asarray(variances, float), J)


def bistatic_inputs(target_xy, tx_xy, rx_xy, phi_rad, c_mps):
    """Noise-free travel time and relative bearing of a target: the inverse of eq. 2.

    Parameters
    ----------
    target_xy : array_like, shape (..., 2)
        Target position [x east, y north] (m).
    tx_xy, rx_xy : array_like, shape (..., 2)
        Transmitter and receiver positions (m).
    phi_rad : float or array_like
        Receiving array heading (rad, clockwise from north).
    c_mps : float or array_like
        Mean sound speed (m/s).

    Returns
    -------
    t : ndarray
        Travel time Tx -> target -> Rx (s).
    theta : ndarray
        Bearing at Rx relative to the array heading (rad, clockwise, in (-pi, pi]).
    """
    target = np.asarray(target_xy, float)
    d_tx = np.linalg.norm(target - np.asarray(tx_xy, float), axis=-1)
    rel = target - np.asarray(rx_xy, float)
    d_rx = np.linalg.norm(rel, axis=-1)
    t = (d_tx + d_rx) / np.asarray(c_mps, float)
    theta = wrap_angle(np.arctan2(rel[..., 0], rel[..., 1]) - np.asarray(phi_rad, float))
    return t, theta
