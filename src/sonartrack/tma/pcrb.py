"""The posterior Cramer-Rao bound of a bearings-only track whose target wanders: Tichavsky's information recursion.

The batch CRB (tma/batch_ml.py :func:`~sonartrack.tma.batch_ml.crb`) bounds a target that keeps its velocity exactly.
A real target's velocity drifts; with the constant-velocity model driven by white acceleration noise of spectral
density q (models/motion.py: x_k = F_k x_k-1 + w_k, w_k ~ N(0, Q_k)) and bearings z_k = h(x_k) + v_k, v_k ~ N(0,
sigma_k^2), the mean-square error of ANY estimator of x_k from z_1..z_k and a prior N(x_0, P_0) is bounded by J_k^-1,
with the Fisher information carried by the recursion (Tichavsky, Muravchik & Nehorai, IEEE Trans. SP 46(5), 1998,
eq. 21, for linear dynamics and additive Gaussian noise; Ristic, Arulampalam & Gordon, Beyond the Kalman Filter,
2004, sec. 4.3 and ch. 6):

    J_0 = P_0^-1
    J_k = (Q_k + F_k J_k-1^-1 F_k^T)^-1 + E[H_k^T H_k] / sigma_k^2,     H_k = [dy_k, -dx_k, 0, 0] / r_k^2

(dx_k, dy_k the target's offset from the ownship, r_k its range; the expectation is over the true trajectories,
which :func:`pcrb_bearings_only` takes as one or as a sample of several). J_0 is the information at the first
bearing's time *including* that bearing, as Ristic et al. (2004, sec. 6.2) initialise from it (:func:`polar_prior`);
the recursion adds the bearings from the second on. With q = 0 the recursion is the batch CRB with the prior
added, carried along the track: J_k^-1 = F(t_k) (P_0^-1 + sum_i=1..k G_i^T G_i / sigma_i^2)^-1 F(t_k)^T, G_i the
batch Jacobian of eq. 16 (what tests/tma/test_published_scenarios.py checks).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require
from sonartrack.models.motion import cv_process_noise, cv_transition


def polar_prior(range_m: float, bearing_rad: float, speed_mps: float, course_rad: float, range_sd_m: float,
                bearing_sd_rad: float, speed_sd_mps: float, course_sd_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """A prior on [x, y, vx, vy] relative to the ownship from independent range, bearing, speed and course
    uncertainties, linearised: mean (r sin b, r cos b, s sin c, s cos c) and covariance A diag(sd^2) A^T with A the
    Jacobian of that map (the initialisation of Ristic et al. 2004, sec. 6.2: range from a prior range sd, bearing from
    the first measurement, course pointing at the observer with a uniform sd pi / sqrt(12)).

    Parameters
    ----------
    range_m, bearing_rad, speed_mps, course_rad : float
        The prior's centre: range (m), bearing and course (rad, clockwise from north), speed (m/s).
    range_sd_m, bearing_sd_rad, speed_sd_mps, course_sd_rad : float
        Their standard deviations (> 0).

    Returns
    -------
    mean : ndarray, shape (4,)
        [x, y, vx, vy] relative to the ownship (m, m/s).
    covariance : ndarray, shape (4, 4)
        Its covariance.
    """
    sds = np.array([range_sd_m, bearing_sd_rad, speed_sd_mps, course_sd_rad], float)
    require(bool(np.all(np.isfinite(sds)) and np.all(sds > 0)), "the prior's standard deviations must be positive")
    sb, cb, sc, cc = np.sin(bearing_rad), np.cos(bearing_rad), np.sin(course_rad), np.cos(course_rad)
    mean = np.array([range_m * sb, range_m * cb, speed_mps * sc, speed_mps * cc])
    A = np.zeros((4, 4))
    A[:2, :2] = [[sb, range_m * cb], [cb, -range_m * sb]]
    A[2:, 2:] = [[sc, speed_mps * cc], [cc, -speed_mps * sc]]
    return mean, A @ np.diag(sds**2) @ A.T


def bearing_information(states, own_xy, sigma_rad) -> np.ndarray:
    """E[H_k^T H_k] / sigma_k^2 at each time (module docstring): the information one bearing carries about the state
    at its own time, averaged over the trajectories given.

    Parameters
    ----------
    states : array_like, shape (n, 4) or (m, n, 4)
        True target states [x, y, vx, vy] (m, m/s) at the n bearing times: one trajectory or m of them.
    own_xy : array_like, shape (n, 2)
        Ownship positions (m) at those times.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise standard deviations (rad).

    Returns
    -------
    ndarray, shape (n, 4, 4)
        The information of each bearing (only the position block is non-zero).
    """
    X = np.asarray(states, float)
    X = X[None] if X.ndim == 2 else X
    d = X[..., :2] - np.asarray(own_xy, float)
    r2 = np.sum(d * d, axis=-1)
    g = np.stack([d[..., 1], -d[..., 0]], axis=-1) / r2[..., None]  # dh/d(x, y) = [dy, -dx] / r^2
    info = np.zeros(X.shape[1:2] + (4, 4))
    info[:, :2, :2] = np.mean(g[..., :, None] * g[..., None, :], axis=0)
    sig = np.broadcast_to(np.asarray(sigma_rad, float), (X.shape[1],))
    return info / (sig * sig)[:, None, None]


def pcrb_bearings_only(states, own_xy, time_s, sigma_rad, q_m2_s3: float, prior_covariance) -> np.ndarray:
    """The posterior CRB on the target's state at every bearing time (module docstring's recursion).

    Parameters
    ----------
    states : array_like, shape (n, 4) or (m, n, 4)
        True target states (m, m/s) at the bearing times; m trajectories average the bearings' information over
        the target's wandering (Tichavsky et al.'s expectation), one is the usual nominal-track bound.
    own_xy : array_like, shape (n, 2)
        Ownship positions (m).
    time_s : array_like, shape (n,)
        Bearing times (s), strictly increasing.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise standard deviations (rad).
    q_m2_s3 : float
        Acceleration noise spectral density per axis (m^2/s^3, >= 0; 0: a constant-velocity target).
    prior_covariance : array_like, shape (4, 4)
        P_0 at the first bearing's time, that bearing included (:func:`polar_prior`); positive definite.

    Returns
    -------
    ndarray, shape (n, 4, 4)
        J_k^-1: the bound on the covariance of any estimate of [x, y, vx, vy] at each time (m^2, m^2/s, m^2/s^2).
    """
    t = np.asarray(time_s, float)
    own = np.asarray(own_xy, float)
    require(t.ndim == 1 and len(t) >= 1 and own.shape == (len(t), 2), "times (n,) and ownship positions (n, 2)")
    require(bool(np.all(np.diff(t) > 0)), "bearing times must increase strictly")
    require(bool(np.isfinite(q_m2_s3) and q_m2_s3 >= 0), f"q must be >= 0 (m^2/s^3), got {q_m2_s3}")
    P0 = np.asarray(prior_covariance, float)
    require(P0.shape == (4, 4) and bool(np.all(np.linalg.eigvalsh(0.5 * (P0 + P0.T)) > 0)),
            "the prior covariance must be 4 x 4 and positive definite")
    info = bearing_information(states, own, sigma_rad)
    bounds = np.empty((len(t), 4, 4))
    bounds[0] = P0
    for k in range(1, len(t)):
        F = cv_transition(t[k] - t[k - 1])
        predicted = F @ bounds[k - 1] @ F.T + cv_process_noise(t[k] - t[k - 1], q_m2_s3)
        bounds[k] = np.linalg.inv(np.linalg.inv(predicted) + info[k])
    return bounds


def position_sd_m(bounds) -> np.ndarray:
    """sqrt(P_xx + P_yy) of each bound: the RMS position error no estimator beats (m).

    Parameters
    ----------
    bounds : array_like, shape (..., 4, 4)
        Covariance bounds.

    Returns
    -------
    ndarray, shape (...)
        The position sds (m).
    """
    B = np.asarray(bounds, float)
    return np.sqrt(B[..., 0, 0] + B[..., 1, 1])
