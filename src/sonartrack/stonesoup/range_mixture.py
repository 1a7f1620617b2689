"""A range-parameterised Gaussian mixture for a target seen only in angle: a bank of EKFs, one per range interval.

Peach, "Bearings-only tracking using a set of range-parameterised extended Kalman filters", IEE Proc. Control
Theory Appl. 142(1), 1995; Ristic, Arulampalam & Gordon, *Beyond the Kalman Filter*, 2004, ch. 6 (the RPEKF).
The range interval [r_min, r_max] is cut into N_F subintervals in geometric progression, so that every filter
starts with the same coefficient of variation C_R = sigma_r / r (an EKF's bearings-only behaviour depends on
C_R, not on r, and stays stable when C_R is small)::

    rho    = (r_max / r_min)^(1 / N_F)
    r_i    = r_min (rho^i + rho^(i-1)) / 2                    the subinterval's midpoint, i = 1..N_F
    sd_i   = r_min (rho^i - rho^(i-1)) / sqrt(12)             the sd of a range uniform over the subinterval
    C_R    = sd_i / r_i = 2 (rho - 1) / (sqrt(12) (rho + 1))  the same for every i
    w_i    = 1 / N_F  (range uniform in log r)   or   (rho^i - rho^(i-1)) / (rho^N_F - 1)  (uniform in r)

Each filter is an EKF; after each measurement z_k its weight is multiplied by its measurement likelihood::

    w_i <- w_i N(z_k; h(x_i-), S_i) / sum_j w_j N(z_k; h(x_j-), S_j)

and the mixture collapses to one Gaussian by moment matching::

    x = sum_i w_i x_i,     P = sum_i w_i (P_i + (x_i - x)(x_i - x)^T)

The measurement is Stone Soup's angle geometry (models/measurement/nonlinear.py): the line of sight in the
sensor frame is u = R (p - o), with p the target position, o the sensor's ``translation_offset`` and R its
``rotation_matrix``; ``Cartesian2DToBearing`` measures phi = atan2(u_y, u_x) (counter-clockwise from the
x axis: not sonartrack's clockwise-from-north bearing) and ``CartesianToElevationBearing`` measures
[theta, phi] with theta = asin(u_z / |u|). Functions here take and return arrays; the Stone Soup initiator
around them is stonesoup/bearings_initiator.py.
"""

from __future__ import annotations

import math

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.gaussian import logsumexp
from sonartrack.filters.ekf import ekf_update, gaussian_loglik

#: the range priors a mixture can start from (the initial weights, module doc)
RANGE_PRIORS = ("log-uniform", "uniform")


def filters_for_cv(r_min_m: float, r_max_m: float, range_cv: float) -> int:
    """The fewest subintervals N_F whose coefficient of variation C_R is at most ``range_cv``.

    From C_R = 2 (rho - 1) / (sqrt(12) (rho + 1)): rho = (1 + sqrt(3) C_R) / (1 - sqrt(3) C_R), and
    N_F = ceil(ln(r_max / r_min) / ln rho).

    Parameters
    ----------
    r_min_m, r_max_m : float
        The range interval (m), 0 < r_min < r_max.
    range_cv : float
        The largest C_R allowed, 0 < C_R < 1 / sqrt(3).

    Returns
    -------
    int
        N_F >= 1.
    """
    require(0.0 < range_cv < 1.0 / math.sqrt(3.0), f"range_cv {range_cv} must be in (0, 0.577): it is sd/range "
                                                   f"of a range uniform over one subinterval")
    ratio = (1.0 + math.sqrt(3.0) * range_cv) / (1.0 - math.sqrt(3.0) * range_cv)
    return max(1, math.ceil(math.log(r_max_m / r_min_m) / math.log(ratio) - 1e-12))


def range_subintervals(r_min_m: float, r_max_m: float, n_filters: int, prior: str = "log-uniform"):
    """Peach's range subintervals (module doc): tma/range_bank.py's
    :func:`~sonartrack.tma.range_bank.range_subintervals` (the interval ``r_min_m`` < ``r_max_m`` in m, ``n_filters``
    N_F >= 1; each filter's midpoint range r_i and range sd_i, m) with each filter's initial weight w_i (summing to
    1) from the range ``prior``: equal weights for "log-uniform" (as the RPEKF of Ristic et al. starts), weights
    proportional to the subintervals' widths for "uniform" (uniform in range). Returns (range_m, range_sd_m,
    weight), each of shape (N_F,).
    """
    from sonartrack.tma.range_bank import range_subintervals as peach_subintervals

    range_m, range_sd_m = peach_subintervals(r_min_m, r_max_m, n_filters)  # checks the interval and N_F
    require(prior in RANGE_PRIORS, f"range prior {prior!r}: choose one of {', '.join(RANGE_PRIORS)}")
    # a subinterval's width is sqrt(12) times its range sd: uniform weights in range are proportional to the sds
    weight = np.full(n_filters, 1.0 / n_filters) if prior == "log-uniform" else range_sd_m / range_sd_m.sum()
    return range_m, range_sd_m, weight


def line_of_sight(position_m, offset_m, rotation):
    """The line of sight u = R (p - o) in the sensor frame, as a 3-vector (z = 0 for a 2-D position).

    Parameters
    ----------
    position_m : ndarray, shape (N, d)
        Target positions, d = 2 or 3 (m).
    offset_m : ndarray, shape (d,)
        The sensor position o (m).
    rotation : ndarray, shape (3, 3)
        The sensor's rotation matrix R.

    Returns
    -------
    ndarray, shape (N, 3)
        u (m).
    """
    d = position_m.shape[-1]
    return (position_m - offset_m) @ rotation[:, :d].T


def angles_and_jacobian(position_m, offset_m, rotation):
    """Stone Soup's measured angles at positions, and their Jacobian with respect to the position.

    2-D (d = 2): h = [phi], phi = atan2(u_y, u_x), dphi/du = [-u_y, u_x, 0] / (u_x^2 + u_y^2).
    3-D (d = 3): h = [theta, phi], theta = asin(u_z / |u|),
    dtheta/du = [-u_x u_z, -u_y u_z, u_x^2 + u_y^2] / (sqrt(u_x^2 + u_y^2) |u|^2); then dh/dp = dh/du R.

    Parameters
    ----------
    position_m : ndarray, shape (N, d)
        Positions (m).
    offset_m : ndarray, shape (d,)
        Sensor position (m).
    rotation : ndarray, shape (3, 3)
        Sensor rotation matrix.

    Returns
    -------
    h_rad : ndarray, shape (N, m)
        Angles (rad), m = d - 1.
    jacobian : ndarray, shape (N, m, d)
        dh/dp (rad/m).
    """
    d = position_m.shape[-1]
    u = line_of_sight(position_m, offset_m, rotation)
    horizontal_sq = u[:, 0] ** 2 + u[:, 1] ** 2
    phi = np.arctan2(u[:, 1], u[:, 0])
    dphi = np.stack([-u[:, 1], u[:, 0], np.zeros(len(u))], axis=1) / horizontal_sq[:, None]
    if d == 2:
        return phi[:, None], (dphi @ rotation[:, :2])[:, None, :]
    range_sq = horizontal_sq + u[:, 2] ** 2
    theta = np.arcsin(u[:, 2] / np.sqrt(range_sq))
    dtheta = np.stack([-u[:, 0] * u[:, 2], -u[:, 1] * u[:, 2], horizontal_sq], axis=1)
    dtheta /= (np.sqrt(horizontal_sq) * range_sq)[:, None]
    return np.stack([theta, phi], axis=1), np.stack([dtheta, dphi], axis=1) @ rotation


def component_positions(angles_rad, angle_var_rad2, range_m, range_sd_m, offset_m, rotation):
    """Position means and covariances of the components at ranges r_i along a measured line of sight.

    In the sensor frame, with l = [cos theta cos phi, cos theta sin phi, sin theta] the line of sight,
    e = dl/dtheta and n = [-sin phi, cos phi, 0]: u_i = r_i l, and
    P_u,i = sd_i^2 l l^T + r_i^2 var_theta e e^T + (r_i cos theta)^2 var_phi n n^T (the linearised polar
    covariance); then p_i = o + R^T u_i and P_i = R^T P_u,i R (rows of the position dimension d).

    Parameters
    ----------
    angles_rad : ndarray, shape (m,)
        The measurement: [phi] (2-D) or [theta, phi] (3-D), rad.
    angle_var_rad2 : ndarray, shape (m,)
        Their noise variances (rad^2).
    range_m, range_sd_m : ndarray, shape (N,)
        The components' ranges and range sd (m).
    offset_m : ndarray, shape (d,)
        Sensor position (m), d = m + 1.
    rotation : ndarray, shape (3, 3)
        Sensor rotation matrix.

    Returns
    -------
    mean_m : ndarray, shape (N, d)
        Positions (m).
    covar_m2 : ndarray, shape (N, d, d)
        Their covariances (m^2).
    """
    theta, var_theta = (angles_rad[0], angle_var_rad2[0]) if len(angles_rad) == 2 else (0.0, 0.0)
    phi, var_phi = angles_rad[-1], angle_var_rad2[-1]
    los = np.array([math.cos(theta) * math.cos(phi), math.cos(theta) * math.sin(phi), math.sin(theta)])
    up = np.array([-math.sin(theta) * math.cos(phi), -math.sin(theta) * math.sin(phi), math.cos(theta)])
    across = np.array([-math.sin(phi), math.cos(phi), 0.0])
    covar_u = (range_sd_m[:, None, None] ** 2 * np.outer(los, los)
               + (range_m ** 2 * var_theta)[:, None, None] * np.outer(up, up)
               + ((range_m * math.cos(theta)) ** 2 * var_phi)[:, None, None] * np.outer(across, across))
    d = len(offset_m)
    back = rotation.T[:d]  # R^T, position rows
    return offset_m + range_m[:, None] * (back @ los), back @ covar_u @ back.T


def mixture_update(x, P, log_w, z_rad, h_rad, H, R):
    """One measurement through every EKF of the bank, and the weights' Bayes update (module doc).

    Parameters
    ----------
    x : ndarray, shape (N, n)
        Predicted component means.
    P : ndarray, shape (N, n, n)
        Their covariances.
    log_w : ndarray, shape (N,)
        Log weights (normalised).
    z_rad : ndarray, shape (m,)
        The measurement (rad; every component an angle, wrapped in the innovation).
    h_rad : ndarray, shape (N, m)
        Predicted measurements h(x_i-).
    H : ndarray, shape (N, m, n)
        Jacobians dh/dx at x_i-.
    R : ndarray, shape (m, m)
        Measurement noise covariance (rad^2).

    Returns
    -------
    x, P : ndarray
        Updated means and covariances.
    log_w : ndarray, shape (N,)
        Updated, normalised log weights.
    log_likelihood : float
        log p(z_k | z_1..k-1) = log sum_i w_i N(z_k; h(x_i-), S_i), the mixture's predictive density.
    d2 : ndarray, shape (N,)
        Each component's squared Mahalanobis distance nu_i^T S_i^-1 nu_i (for a gate).
    """
    x_new, P_new, nu, S, S_inv = ekf_update(x, P, z_rad, h_rad, H, R, angle_rows=tuple(range(len(z_rad))))
    joint = log_w + gaussian_loglik(nu, S, S_inv)
    log_likelihood = float(logsumexp(joint))
    d2 = np.einsum("...i,...ij,...j->...", nu, S_inv, nu)
    return x_new, P_new, joint - log_likelihood, log_likelihood, d2


def collapse(x, P, log_w):
    """The mixture's moment-matched Gaussian: x = sum w_i x_i, P = sum w_i (P_i + (x_i - x)(x_i - x)^T).

    Parameters
    ----------
    x : ndarray, shape (N, n)
        Component means.
    P : ndarray, shape (N, n, n)
        Component covariances.
    log_w : ndarray, shape (N,)
        Normalised log weights.

    Returns
    -------
    mean : ndarray, shape (n,)
    covar : ndarray, shape (n, n)
    """
    w = np.exp(log_w - logsumexp(log_w))
    mean = w @ x
    spread = x - mean
    covar = np.einsum("i,ijk->jk", w, P) + np.einsum("i,ij,ik->jk", w, spread, spread)
    return mean, (covar + covar.T) / 2.0


def range_cv(mean_m, covar_m2, offset_m) -> tuple[float, float]:
    """The range from the sensor of a Gaussian position, its sd and their ratio.

    r = |p - o|, sd_r^2 = l^T P l with l = (p - o) / r (the variance along the line of sight).

    Parameters
    ----------
    mean_m : ndarray, shape (d,)
        Position mean (m).
    covar_m2 : ndarray, shape (d, d)
        Position covariance (m^2).
    offset_m : ndarray, shape (d,)
        Sensor position (m).

    Returns
    -------
    range_m : float
    cv : float
        sd_r / r (inf at r = 0).
    """
    delta = np.asarray(mean_m, float) - offset_m
    range_m = float(np.linalg.norm(delta))
    if range_m == 0.0:
        return 0.0, math.inf
    los = delta / range_m
    return range_m, math.sqrt(max(float(los @ covar_m2 @ los), 0.0)) / range_m
