"""Batch bearings-only TMA: maximum likelihood by Gauss-Newton with Levenberg-Marquardt safeguards,
its covariance, the Cramer-Rao bound, and the observability check (paper P3, eqs. 1-18).

Target at constant velocity with state X0 = [x0, y0, vx, vy] at the reference time t0 (the first
bearing's); at time t_n (tau_n = t_n - t0) and ownship position o_n = (ox_n, oy_n):

    dx_n = x0 + vx tau_n - ox_n,   dy_n = y0 + vy tau_n - oy_n,   r_n^2 = dx_n^2 + dy_n^2
    h_n(X0) = atan2(dx_n, dy_n)                                            (eq. 6)
    H_n = dh_n/dX0 = [dy_n, -dx_n, tau_n dy_n, -tau_n dx_n] / r_n^2         (eq. 16)

ML minimises C(X0) = sum_n wrap(z_n - h_n)^2 / sigma_n^2 (eq. 15). Gauss-Newton (eqs. 17-18) with the
Levenberg-Marquardt damping of Marquardt (1963): solve (J^T J + lambda diag(J^T J)) delta = J^T e with
J = H / sigma, e = wrap(z - h) / sigma; accept if C falls (lambda / 10), else retry (lambda * 10).
Covariance: the inverse Fisher information (J^T J)^-1 at the solution; the CRB is the same matrix
at the true state (Nardone, Lindgren & Gong 1984). Starting point: the pseudo-linear estimate
(Lindgren & Gong 1978): each bearing line gives the linear equation

    [cos z, -sin z, tau cos z, -tau sin z] X0 = ox cos z - oy sin z.

Observability: with the ownship at constant velocity every target track scaled about the ownship's
line fits the bearings exactly, so range is unobservable (Nardone & Aidala 1981); we check the
ownship's deviation from its best constant-velocity fit over the record.

Arguments the functions here share (their docstrings refer to this list):

- ``x0`` (or ``x0_true``), array_like (4,): the target state [x0, y0, vx, vy] at t0 (m, m/s);
- ``tau_s``, array_like (n,): times since t0 (s);
- ``own_xy``, ndarray (n, 2): ownship positions (m; x east, y north) at those times;
- ``sigma_rad``, float or array_like (n,): bearing noise standard deviation (rad);
- ``rho``, float: lag-1 correlation of the normalised bearing errors in bearing order, 0 <= rho < 1 (0: white;
  :func:`fisher_information`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.models.motion import cv_transition

#: ownship must leave its best straight constant-velocity line by this much (m) for range to be observable
MIN_MANEUVER_M = 50.0


@dataclass(frozen=True, slots=True)
class LmFit:
    """A Levenberg-Marquardt fit (:func:`levenberg_marquardt`): X0 at ``t0_s`` (s) and its covariance, with how the
    solver ended (iterations, convergence, the cost C it reached); the fields the batch solutions share."""

    x0: np.ndarray
    covariance: np.ndarray
    t0_s: float
    iterations: int
    converged: bool
    objective: float


@dataclass(frozen=True, slots=True)
class BatchEstimate(LmFit):
    """A batch TMA solution: X0 = [x0, y0, vx, vy] (m, m/s) at ``t0_s`` and its covariance, with how the solver
    ended and the ``method`` that made it."""

    method: str

    def state_at(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """States (n, 4) and covariances (n, 4, 4) at times ``t_s`` (constant-velocity propagation).

        Parameters
        ----------
        t_s : float or array_like, shape (n,)
            Times (s, same clock as ``t0_s``).

        Returns
        -------
        x : ndarray, shape (n, 4)
            [x, y, vx, vy] (m, m/s) at each time.
        P : ndarray, shape (n, 4, 4)
            F P0 F^T at each time.
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float)) - self.t0_s
        F = np.broadcast_to(np.eye(4), (len(t), 4, 4)).copy()
        F[:, 0, 2] = F[:, 1, 3] = t
        # an unobservable fit's covariance holds inf (0 * inf = NaN in the product): its rows come out NaN, which
        # every caller reads as 'not determined', so the warning would only be noise on stderr
        with np.errstate(invalid="ignore"):
            return F @ self.x0, F @ self.covariance @ np.swapaxes(F, 1, 2)


def bearing_model(x0, tau_s, own_xy) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Predicted bearings h (n,), Jacobian H (n, 4) (eq. 16) and ranges (n,) of the CV track x0.

    Parameters
    ----------
    x0, tau_s, own_xy
        The track and the ownship's positions at the times (module docstring).

    Returns
    -------
    h : ndarray, shape (n,)
        Bearings (rad, clockwise from north), eq. 6.
    H : ndarray, shape (n, 4)
        dh/dX0 (eq. 16).
    r : ndarray, shape (n,)
        Ranges (m).
    """
    x0 = np.asarray(x0, dtype=float)
    tau = np.asarray(tau_s, dtype=float)
    dx = x0[0] + x0[2] * tau - own_xy[:, 0]
    dy = x0[1] + x0[3] * tau - own_xy[:, 1]
    r2 = dx * dx + dy * dy
    H = np.empty((len(r2), 4))  # [dy, -dx, tau dy, -tau dx] / r2, filled in place (no stacked temporary)
    H[:, 0], H[:, 1], H[:, 2], H[:, 3] = dy, -dx, tau * dy, -tau * dx
    H /= r2[:, None]
    return np.arctan2(dx, dy), H, np.sqrt(r2)


def fisher_information(x0, tau_s, own_xy, sigma_rad, rho: float = 0.0) -> np.ndarray:
    """J = sum_n H_n^T H_n / sigma_n^2: the bearings' Fisher information about X0; with ``rho`` > 0, that of
    errors e_n / sigma_n that are AR(1) in bearing order with lag-1 correlation rho, J = sum_n g_n^T g_n with the
    whitened rows g_1 = H_1 / sigma_1, g_n = (H_n / sigma_n - rho H_n-1 / sigma_n-1) / sqrt(1 - rho^2) (the
    Prais-Winsten transform, whose rows are independent with unit variance: J = H^T R^-1 H for the AR(1)
    covariance R; Prais & Winsten 1954, Cowles Commission Discussion Paper 383).

    Parameters
    ----------
    x0, tau_s, own_xy, sigma_rad, rho
        State, geometry and bearing noise (module docstring).

    Returns
    -------
    ndarray, shape (4, 4)
        J.
    """
    _, H, _ = bearing_model(x0, tau_s, own_xy)
    G = H / np.broadcast_to(np.asarray(sigma_rad, dtype=float), (len(H),))[:, None]
    if rho > 0.0:
        G = np.concatenate([G[:1], (G[1:] - rho * G[:-1]) / np.sqrt(1.0 - rho * rho)])
    return G.T @ G


def crb(x0_true, tau_s, own_xy, sigma_rad, rho: float = 0.0) -> np.ndarray:
    """Cramer-Rao bound on X0 for this geometry: the inverse Fisher information at the true state.

    Parameters
    ----------
    x0_true, tau_s, own_xy, sigma_rad, rho
        The true state, the geometry and the noise (module docstring).

    Returns
    -------
    ndarray, shape (4, 4)
        J^-1 at the true state (m^2, m^2/s, m^2/s^2).
    """
    return np.linalg.inv(fisher_information(x0_true, tau_s, own_xy, sigma_rad, rho))


def crb_position_sd_m(x0_true, tau_s, own_xy, sigma_rad, tau_end_s: float, rho: float = 0.0) -> float:
    """The CRB's position standard deviation sqrt(P_xx + P_yy) at time ``tau_end_s``: the bound on X0
    (:func:`crb`) carried to that time along the constant-velocity model, P = F J^-1 F^T with F = [[I, tau I],
    [0, I]] (the bound on a function of X0 is the bound on X0 mapped through its Jacobian; Van Trees, Detection,
    Estimation and Modulation Theory I, 1968, sec. 2.4.3).

    Parameters
    ----------
    tau_end_s : float
        The time (s since t0) of the position bounded, e.g. the solution's last row.
    x0_true, tau_s, own_xy, sigma_rad, rho
        As for :func:`crb` (module docstring); ``tau_s`` are the bearings' times.

    Returns
    -------
    float
        The bound's position sd (m); NaN when the geometry carries no information on some component (J singular).
    """
    J = fisher_information(x0_true, tau_s, own_xy, sigma_rad, rho)
    span = max(float(np.ptp(np.asarray(tau_s, float))), 1.0)
    D = np.diag([1.0, 1.0, 1.0 / span, 1.0 / span])  # velocity as metres over the record: columns of like size
    # A straight ownship leaves J singular in exact arithmetic but ~1e17-conditioned in floating point (inverting it
    # gave 1.4e10 m, which would make a "within 2x CRB" claim pass trivially); after a turn ~1e3.
    if not np.all(np.isfinite(J)) or np.linalg.cond(D @ J @ D) > 1e10:
        return float("nan")
    P0 = np.linalg.inv(J)
    F = cv_transition(float(tau_end_s))
    P = F @ P0 @ F.T
    v = P[0, 0] + P[1, 1]
    return float(np.sqrt(v)) if np.isfinite(v) and v >= 0 else float("nan")


def ownship_deviation_m(tau_s, own_xy) -> float:
    """Largest distance (m) of the ownship from its least-squares constant-velocity line.

    Parameters
    ----------
    tau_s, own_xy
        Times and ownship positions (module docstring).

    Returns
    -------
    float
        The largest distance (m).
    """
    tau = np.asarray(tau_s, dtype=float)
    A = np.column_stack([np.ones_like(tau), tau])
    coef, *_ = np.linalg.lstsq(A, own_xy, rcond=None)
    return float(np.max(np.linalg.norm(own_xy - A @ coef, axis=1)))


def check_observability(tau_s, own_xy, min_maneuver_m: float = MIN_MANEUVER_M) -> str | None:
    """A one-line message if the ownship has not maneuvered enough for bearings-only range, else None.

    Parameters
    ----------
    tau_s, own_xy
        The record's times and the ownship's positions then (module docstring).
    min_maneuver_m : float
        Smallest deviation (m) from the best constant-velocity line that makes range observable.

    Returns
    -------
    str or None
        The message naming the problem and the fix, or None when the maneuver suffices.
    """
    dev = ownship_deviation_m(tau_s, own_xy)
    if dev < min_maneuver_m:
        return (f"ownship has not maneuvered (it stays within {dev:.0f} m of a straight constant-velocity line): "
                "range is unobservable from bearings alone; use a record with a course or speed change, or em-map "
                "with SNR")
    return None


def observable_range_limit_m(tau_s, own_xy, sigma_rad: float) -> float:
    """Largest range (m) whose value a bearings-only record can resolve, from the ownship maneuver.

    Range enters the bearings only through the ownship's departure from a straight constant-velocity line
    (Nardone & Aidala 1981): a departure of ``dev`` metres turns the line of sight by about dev / R rad. With n
    bearings of noise sigma, a turn is resolved only if it exceeds the standard error sigma / sqrt(n) of their
    mean, so ranges beyond ``R_max = dev sqrt(n) / sigma`` are not determined by the data: the likelihood is flat
    out there, and an ML solution that lands beyond R_max is an artefact of the noise, not a measurement.

    Parameters
    ----------
    tau_s, own_xy, sigma_rad
        Times, ownship positions and a scalar bearing noise (module docstring).

    Returns
    -------
    float
        R_max (m).
    """
    n = len(np.asarray(tau_s))
    return ownship_deviation_m(tau_s, own_xy) * float(np.sqrt(n)) / float(sigma_rad)


def pseudo_linear_estimate(z_rad, tau_s, own_xy) -> np.ndarray:
    """Pseudo-linear X0 (Lindgren & Gong 1978): least squares over the bearing-line equations.

    Parameters
    ----------
    z_rad : ndarray, shape (n,)
        Measured bearings (rad, clockwise from north).
    tau_s, own_xy
        Their times and the ownship positions (module docstring).

    Returns
    -------
    ndarray, shape (4,)
        [x0, y0, vx, vy] at t0 (m, m/s).
    """
    c, s = np.cos(z_rad), np.sin(z_rad)
    A = np.column_stack([c, -s, tau_s * c, -tau_s * s])
    b = own_xy[:, 0] * c - own_xy[:, 1] * s
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    return x


def _damped_step(residual, x, e, J, cost: float, lam: float):
    """One Levenberg-Marquardt iteration (module doc): solve (J^T J + lam diag(J^T J)) delta = J^T e, raising
    lam tenfold until the cost does not rise (at most 30 tries). Returns ``(x, e, J, cost, lam, improved)``."""
    g = J.T @ e
    JTJ = J.T @ J
    D = np.diag(np.diag(JTJ))
    for _ in range(30):
        try:
            step = np.linalg.solve(JTJ + lam * D, g)
        except np.linalg.LinAlgError:
            lam *= 10.0
            continue
        # a trial step may land on the sensor (0 / 0) or overflow: its cost is not finite and the test below rejects it
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            e_new, J_new = residual(x + step)
            c_new = float(e_new @ e_new)
        if np.isfinite(c_new) and c_new <= cost:
            return x + step, e_new, J_new, c_new, max(lam / 10.0, 1e-12), True
        lam *= 10.0
    return x, e, J, cost, lam, False


def levenberg_marquardt(residual, x, e, J, max_iter: int, tol: float, *, finite_only: bool = False):
    """The Levenberg-Marquardt loop (Marquardt 1963) of :func:`_damped_step`s from ``x`` with residuals ``e`` and
    Jacobian ``J`` there: stops when a step fails to lower the cost or lowers it by less than ``tol`` (relative),
    or after ``max_iter`` steps; ``finite_only`` stops at once on a non-finite starting cost.

    Parameters
    ----------
    residual : callable
        ``residual(x) -> (e, J)``, whitened residuals and their Jacobian.
    x, e, J : ndarray
        Start, its residuals and Jacobian.
    max_iter : int
        Step limit.
    tol : float
        Relative cost decrease that ends the loop.
    finite_only : bool
        Take no step from a non-finite cost.

    Returns
    -------
    tuple
        (x, e, J, cost, iterations, converged).
    """
    cost = float(e @ e)
    lam, it, converged, rel = 1e-3, 0, False, np.inf
    while it < max_iter and (not finite_only or np.isfinite(cost)):
        it += 1
        x, e, J, c_new, lam, improved = _damped_step(residual, x, e, J, cost, lam)
        if improved:
            rel, cost = (cost - c_new) / max(cost, 1e-300), c_new
        if not improved or rel < tol:
            converged = improved or rel < tol
            break
    return x, e, J, cost, it, converged


def ml_bearings_only(z_rad, time_s, own_xy, sigma_rad, x_init=None, max_iter: int = 100, tol: float = 1e-10,
                     check: bool = True) -> BatchEstimate:
    """ML X0 from bearings by Gauss-Newton / Levenberg-Marquardt (module doc); stops when no damped step
    lowers the cost or the relative decrease falls below ``tol``.

    Parameters
    ----------
    z_rad, time_s : array_like, shape (n,)
        Bearings (rad, clockwise from north) and their strictly increasing times (s); n >= 5.
    own_xy : array_like, shape (n, 2)
        Ownship positions (m; x east, y north) at the bearing times.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise standard deviation (rad).
    x_init, max_iter, tol : array_like (4,) or None, int, float
        Start (None: the pseudo-linear estimate), iteration limit, relative cost decrease that ends the search.
    check : bool
        Raise :class:`InputError` when the ownship has not maneuvered (range unobservable).

    Returns
    -------
    BatchEstimate
        X0 at the first bearing's time, covariance (J^T J)^-1, iterations, convergence, cost C, method "ml".
    """
    z = np.asarray(z_rad, dtype=float)
    t = np.asarray(time_s, dtype=float)
    own = np.asarray(own_xy, dtype=float)
    require(z.ndim == 1 and len(z) == len(t) == len(own),
            "bearings, times and ownship positions must have the same length")
    require(len(z) >= 5, f"batch TMA needs at least 5 bearings, got {len(z)}")
    require(bool(np.all(np.diff(t) > 0)), "bearing times must increase strictly: sort the file and drop duplicates")
    tau = t - t[0]
    if check:
        msg = check_observability(tau, own)
        if msg:
            raise InputError(msg)
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), z.shape)
    x = pseudo_linear_estimate(z, tau, own) if x_init is None else np.asarray(x_init, dtype=float).copy()
    unit = bool(np.all(sig == 1.0))  # x / 1.0 is x exactly: equal weights skip the two divisions

    def residual(x):
        h, H, _ = bearing_model(x, tau, own)
        return (wrap_angle(z - h), H) if unit else (wrap_angle(z - h) / sig, H / sig[:, None])

    e, J = residual(x)
    x, e, J, cost, it, converged = levenberg_marquardt(residual, x, e, J, max_iter, tol)
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((4, 4), np.inf)
    return BatchEstimate(x0=x, covariance=cov, t0_s=float(t[0]), iterations=it, converged=bool(converged),
                         objective=cost, method="ml")
