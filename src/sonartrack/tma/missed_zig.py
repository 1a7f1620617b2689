"""The current leg's covariance widened for a zig the detector may have missed.

Why. A leg fit (tma/legs.py :func:`~sonartrack.tma.legs.fit_legs`) states the covariance of its own model: legs of
constant velocity joined at the detected zigs. A zig the test did not find (too small, too far, too recent for
the bearings to show it yet) leaves the model short of two parameters, and the fewer parameters the smaller the
covariance: on the manoeuvring-target study (trial version 5) every one of the 12 determined current legs more than
5 of their own sds from the truth (up to 44) had a missed zig, while their errors were within the Cramer-Rao bound
of the true legs (Mahalanobis 0.6-2.9). Their residuals passed every whiteness and chi-square test: the bearings do
not show the zig, so no test can flag it; only the covariance can own it.

How. A velocity change dv at time tau that the fit leaves out biases it. With the whitened Jacobian G of the fitted
model (n x P), B(tau) = [(t_i - tau)+ g_i] (n x 2; g_i the whitened bearing gradient with respect to the target's
position, tma/zig.py's change Jacobian) and L the map from the fit's parameters to the state at the last bearing t_n
(tma/legs.py ``_state_map``), the fit's parameters move by F dv, F = (G^T G)^-1 G^T B, while the true state at t_n
moves by A dv, A = [(t_n - tau) I_2; I_2]; the error of the state is

    e = K dv,      K = L F - A        (the omitted-variable bias; Seber & Lee, Linear Regression Analysis, 2003,
                                       sec. 9.2, linearised about the fit)

The test missed the zig, so its noncentrality lambda = dv^T M dv with M = B^T (I - G (G^T G)^-1 G^T) B (tma/zig.py's
score form) was at most about its threshold h; and a ship changes its velocity by a few m/s, s per axis. dv is taken
within both, as the covariance S = (M / h + I / s^2)^-1 (the ellipse dv^T (M / h + I / s^2) dv <= 1 holds the dv
below both bounds, to within a factor 2), and the state's covariance becomes

    P(tau) = P + K S K^T

(P the fit's). P(tau) >= P, and -> P where the bearings would have seen any zig (M large) or s -> 0. The zig's time is
unknown: the current leg takes the smallest covariance at least every P(tau) along each direction (core/linalg.py
:func:`~sonartrack.core.linalg.covariance_max`, taken in turn), over ``n_tau`` times evenly over the record (a zig
in an earlier leg has more bearings after it, so M there is large: the bearings decide how much each tau adds). A
missed zig's error lies across the bearing as often as along it (the fit bends away from the last bearings), so no
one tau's largest variance serves. This widens the covariance by the zig the record cannot exclude, not the largest
one conceivable.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.core.linalg import covariance_max
from sonartrack.tma.legs import LegFit, _course_speed, _state_map, leg_bearing_model

#: prior sd (m/s, per axis) of a velocity change the detector may have missed: a 60 deg turn at 6 kn changes the
#: velocity by 3.1 m/s, a 30 deg one at 10 kn by 2.7 m/s (the manoeuvring-target family: 20-120 deg, 4-15 kn)
MISSED_ZIG_DV_SD_MPS = 2.0
#: times tau tried for the missed zig, evenly over the record
MISSED_ZIG_TIMES = 48


def missed_zig_covariance(fit: LegFit, time_s, own_xy_m, sigma_rad, threshold: float, *,
                          dv_sd_mps: float = MISSED_ZIG_DV_SD_MPS, n_tau: int = MISSED_ZIG_TIMES,
                          min_after: int = 2) -> np.ndarray:
    """The covariance (4, 4) of [x, y, vx, vy] at the last bearing with a zig the test may have missed at any of
    ``n_tau`` times (module doc).

    Parameters
    ----------
    fit : LegFit
        The leg fit of these bearings.
    time_s : ndarray (n,)
        Bearing times (s).
    own_xy_m : ndarray (n, 2)
        Ownship positions (m).
    sigma_rad : float or ndarray (n,)
        The bearing sd the fit used (rad).
    threshold : float
        The zig test's threshold h (tma/zig.py :func:`~sonartrack.tma.zig.glr_threshold`).
    dv_sd_mps : float
        s, the size of a ship's velocity change (m/s per axis).
    n_tau : int
        Times tried for the zig.
    min_after : int
        Fewest bearings after a tried time.

    Returns
    -------
    ndarray (4, 4)
        The widened covariance; the fit's own where it cannot be computed.
    """
    t, own = np.asarray(time_s, float), np.asarray(own_xy_m, float)
    sig = np.broadcast_to(np.asarray(sigma_rad, float), t.shape)
    L, G = _end_map_and_jacobian(fit, t, own, sig)
    with np.errstate(invalid="ignore", over="ignore"):
        base = L @ fit.covariance @ L.T
    if len(t) <= min_after + 2 or not np.all(np.isfinite(base)):
        return base
    out = base
    for tau in np.linspace(t[min_after], t[-1 - min_after], n_tau):
        try:
            K, M = omitted_zig_bias(L, G, t, tau)
            S = np.linalg.inv(M / threshold + np.eye(2) / dv_sd_mps**2)
            P = base + K @ S @ K.T
            out = covariance_max(out, P) if np.all(np.isfinite(P)) else out
        except np.linalg.LinAlgError:
            continue
    return out


def _end_map_and_jacobian(fit: LegFit, t, own, sig):
    """(L, the map from the fit's parameters to the state at the last bearing (4, P); G, the whitened Jacobian of the
    bearings (n, P))."""
    c, theta = np.asarray(fit.change_times_s, float), np.asarray(fit.params, float)
    L = _state_map(theta, c, t[0], t[-1], fit.refined)
    _, jac, _ = leg_bearing_model(theta, c, t, own, t[0], with_change_times=fit.refined)
    return L, jac / sig[:, None]


def omitted_zig_bias(L, G, time_s, tau_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(K (4, 2), M (2, 2)) of a velocity change at ``tau_s`` that the fit leaves out (module doc): the state's error
    at the last bearing is K dv, and the zig test's noncentrality dv^T M dv. L (4, P) and G (n, P) as
    :func:`_end_map_and_jacobian` gives them (the position columns of G first). Raises LinAlgError when G^T G is
    singular."""
    t = np.asarray(time_s, float)
    B = np.clip(t - tau_s, 0.0, None)[:, None] * G[:, :2]
    F = np.linalg.solve(G.T @ G, G.T @ B)
    K = L @ F - np.vstack([(t[-1] - tau_s) * np.eye(2), np.eye(2)])
    PB = B - G @ F
    return K, PB.T @ PB


def with_missed_zig(fit: LegFit, time_s, own_xy_m, sigma_rad, threshold: float, *,
                    dv_sd_mps: float = MISSED_ZIG_DV_SD_MPS, max_range_sd_fraction: float = 1.0) -> LegFit:
    """``fit`` with its current leg's state covariance, course and speed sds, range sd and ``position_end_cov``
    widened by :func:`missed_zig_covariance`; the leg not determined when its range sd then exceeds
    ``max_range_sd_fraction`` of its range (its reason says so)."""
    P = missed_zig_covariance(fit, time_s, own_xy_m, sigma_rad, threshold, dv_sd_mps=dv_sd_mps)
    leg = fit.legs[-1]
    course, course_sd, speed, speed_sd = _course_speed(leg.state[2:], P[2:, 2:])
    d = leg.state[:2] - np.asarray(own_xy_m, float)[-1]
    u = d / max(float(np.hypot(*d)), 1e-9)
    with np.errstate(invalid="ignore"):
        rng_sd = float(np.sqrt(u @ P[:2, :2] @ u))
    determined = leg.determined and bool(rng_sd <= max_range_sd_fraction * leg.range_m)
    reason = leg.reason if leg.determined == determined else (
        f"range not determined on leg {len(fit.legs)}: its sd, with a zig the bearings cannot exclude, exceeds "
        f"{max_range_sd_fraction:g} of the range")
    last = replace(leg, state_cov=P, course_sd_deg=course_sd, speed_sd_kn=speed_sd, range_sd_m=rng_sd,
                   determined=determined, reason=reason)
    return replace(fit, legs=fit.legs[:-1] + (last,), position_end_cov=P[:2, :2])
