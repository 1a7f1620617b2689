"""Leg-wise bearings-only TMA: maximum likelihood over piecewise-constant-velocity target motion, its CRB and
observability per leg.

Model. The target's position is continuous and its velocity constant on each of K + 1 legs separated by the
change times c_1 < ... < c_K. With t0 the first bearing's time (c_0 = t0, c_K+1 = +inf) and the leg exposures

    a_k(t) = clip(t - c_k-1, 0, c_k - c_k-1)                 (time spent on leg k up to t)

the position is p(t) = p0 + sum_k a_k(t) v_k, linear in the parameters theta = [x0, y0, vx_1, vy_1, ...,
vx_K+1, vy_K+1] (state order [x, y, vx, vy] of DESIGN.md); K = 0 is the constant-velocity model of
tma/batch_ml.py. The bearing is h_n = atan2(dx_n, dy_n) with (dx_n, dy_n) = p(t_n) - o_n, and with
g_n = [dy_n, -dx_n] / r_n^2 (batch_ml eq. 16, the position part) the Jacobian rows are

    dh_n/dp0 = g_n,   dh_n/dv_k = a_k(t_n) g_n,   dh_n/dc_k = g_n . (v_k - v_k+1) 1[t_n > c_k]

(moving c_k later by dc keeps leg k for dc longer instead of leg k+1 after c_k). The ML minimises
C = sum_n wrap(z_n - h_n)^2 / sigma_n^2 by Gauss-Newton with the Levenberg-Marquardt safeguard of
tma/batch_ml.py (its :func:`~sonartrack.tma.batch_ml.levenberg_marquardt`, Marquardt 1963), from the pseudo-linear
start generalised to legs (each bearing line is linear in theta: x(t) cos z - y(t) sin z = ox cos z - oy sin z;
Lindgren & Gong 1978).

Change times. C is continuous in c_k (the position is) and smooth between bearing times, with a kink where c_k
crosses one; it can have several local minima along c_k. So the change times are refined in two stages: (1) a
profile of the cost over each change time in turn, on a grid of the midpoints between bearings within
``search_half_width_s`` of the current time (theta re-fitted, warm-started, at every grid point; the minimum
found by the grid is global along that axis), then (2) Gauss-Newton over theta and all the c_k jointly from
there, which finds the minimum between the bearings and gives the covariance of all parameters, so that a leg's
course and speed sds include the uncertainty of its end points.

Uncertainty. The covariance is the inverse Fisher information J = G^T G (G the Jacobian over sigma) at the
estimate; at the true parameters it is the Cramer-Rao bound (Nardone, Lindgren & Gong, IEEE Trans. AC 29(9),
775-787, 1984, for K = 0; the same argument holds for any smooth parametrised track). A function of the
parameters (a leg's course, speed, range) gets the bound mapped through its gradient (Van Trees 1968, sec.
2.4.3). Per leg: the state [x, y, vx, vy] at the leg's end and its covariance, the range there and its sd, and
the condition number of the leg state's information in correlation form (scale-free: 1 is perfect, 1e8 is a
direction the bearings do not see). A leg whose range sd exceeds ``max_range_sd_fraction`` of its range (the
value of the verdict's ``max_range_sd_fraction``, tma/settings.py) is not determined and says so.

The fit's own verdict. The covariance is the bound of the *model*: a zig the segmentation missed leaves a leg
whose velocity was not constant, and its covariance then claims far too much (the manoeuvring-target study, before
this check: 26 of 91 determined current legs beyond 5 of their own sds, every one on a record with a missed zig).
So the fit's residuals are tested as ``sonartrack tma`` tests a constant-velocity fit (tma/motion_verdict.py): the
lag-1 whiteness test of tma/record_checks.py (:func:`~sonartrack.tma.record_checks.whiteness_check`, at
``motion_alpha``; no stated sd needed, the bearings' resolution as its floor) on the whitened residuals of each
leg, and of the whole record; and their chi-square against the stated sd (chi-square(n - p) upper tail at
``motion_alpha``: a missed zig whose residuals the lag-1 test does not see still adds misfit; with the sd estimated
from the same residuals it cannot fail). A leg whose residuals reject it is not determined, reason
``target manoeuvred: residuals reject constant velocity on leg k, largest A-B s`` (the span from
:func:`~sonartrack.tma.record_checks.residual_span`); since the position is continuous, one leg's misfit biases
the others', so every other leg is then not determined either (reason: leg k's).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import require
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.core.units import KNOT_MPS
from sonartrack.tma.batch_ml import bearing_model, levenberg_marquardt
from sonartrack.tma.record_checks import residual_span, whiteness_check
from sonartrack.tma.settings import VerdictSettings
from sonartrack.tma.verdict import DIVERGED, MANOEUVRED

#: a leg whose range sd exceeds this fraction of its range is not determined (as verdict.max_range_sd_fraction)
MAX_RANGE_SD_FRACTION = 1.0
#: no ship is faster (m/s): the verdict's bound (tma/settings.py VerdictSettings.max_speed_mps)
MAX_SPEED_MPS = VerdictSettings().max_speed_mps
#: each leg needs at least this many bearings strictly inside it
MIN_BEARINGS_PER_LEG = 2
#: significance of the leg fit's whiteness tests (each leg's and the whole record's; as verdict.alpha)
MOTION_ALPHA = 1e-3
#: the bearings' resolution (deg), the whiteness test's floor (as tma/motion_verdict.py's SIGMA_FLOOR_DEG)
RESOLUTION_DEG = 0.01


@dataclass(frozen=True, slots=True)
class Leg:
    """One leg of constant velocity: its span, course and speed with sds, and how well its range is known.

    ``start_s``/``end_s`` are change times (the first leg starts at the first bearing, the last ends at the
    last); their sds are 0 where fixed. ``state``/``state_cov``: [x, y, vx, vy] (m, m/s) at ``end_s`` and its
    covariance (the inverse Fisher information mapped to the leg). ``reason`` is "" for a determined leg."""

    start_s: float
    end_s: float
    start_sd_s: float
    end_sd_s: float
    course_deg: float
    course_sd_deg: float
    speed_kn: float
    speed_sd_kn: float
    state: np.ndarray
    state_cov: np.ndarray
    range_m: float
    range_sd_m: float
    information_condition: float
    determined: bool
    reason: str

    @property
    def relative_range_sd(self) -> float:
        """Range sd over range at the leg's end (inf when the range is 0)."""
        return self.range_sd_m / self.range_m if self.range_m > 0 else float("inf")


@dataclass(frozen=True, slots=True)
class LegFit:
    """A leg-wise ML solution: parameters theta (module doc) at ``t0_s``, the change times, the covariance of
    [theta, change times (only if refined)], the legs, and the position at the last bearing with its covariance."""

    params: np.ndarray
    change_times_s: np.ndarray
    covariance: np.ndarray
    t0_s: float
    t_end_s: float
    legs: tuple[Leg, ...]
    position_end_m: np.ndarray
    position_end_cov: np.ndarray
    objective: float
    dof: int
    iterations: int
    converged: bool
    refined: bool
    #: whitened residuals wrap(z - h) / sigma at the bearings, and the motion test's phrase ("" when it passed or
    #: was not run)
    residuals: np.ndarray | None = None
    motion_note: str = ""

    @property
    def manoeuvre_rejected(self) -> bool:
        """Whether the fit's residuals reject the piecewise-constant-velocity model (module doc)."""
        return bool(self.motion_note)

    def position_at(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n, 2) (m) and their covariances (n, 2, 2) at times ``t_s`` (s, same clock as ``t0_s``)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        L = np.stack([_state_map(self.params, self.change_times_s, self.t0_s, ti, self.refined)[:2] for ti in t])
        return _positions(self.params, self.change_times_s, self.t0_s, t), L @ self.covariance @ np.swapaxes(L, 1, 2)


def leg_exposure_s(time_s, t0_s: float, change_times_s) -> np.ndarray:
    """Time spent on each leg up to each time: a_k(t) = clip(t - c_k-1, 0, c_k - c_k-1) (module doc).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Times (s).
    t0_s : float
        Start of the first leg (s): the reference time of p0.
    change_times_s : array_like, shape (K,)
        Change times (s), increasing.

    Returns
    -------
    ndarray, shape (n, K + 1)
        a_k(t_n) (s).
    """
    t = np.asarray(time_s, dtype=float)[:, None]
    edges = np.concatenate([[t0_s], np.asarray(change_times_s, dtype=float), [np.inf]])
    return np.clip(t - edges[:-1], 0.0, edges[1:] - edges[:-1])


def _positions(params, change_times_s, t0_s, time_s) -> np.ndarray:
    """p(t) = p0 + sum_k a_k(t) v_k, shape (n, 2)."""
    A = leg_exposure_s(time_s, t0_s, change_times_s)
    return params[:2] + A @ np.asarray(params[2:], dtype=float).reshape(-1, 2)


def leg_bearing_model(params, change_times_s, time_s, own_xy, t0_s: float, with_change_times: bool = False):
    """Predicted bearings h (n,), Jacobian (n, 2K + 4 [+ K]) and ranges (n,) of the leg-wise track (module doc).

    The bearing depends only on the target's position relative to the ownship, so the position part of batch_ml's
    :func:`~sonartrack.tma.batch_ml.bearing_model` evaluated for a fixed point p0 seen from the ownship moved by
    -(p(t) - p0) gives h and g_n; the velocity and change-time columns are g_n scaled as in the module doc.

    Parameters
    ----------
    params : array_like, shape (2K + 4,)
        theta = [x0, y0, vx_1, vy_1, ..., vx_K+1, vy_K+1] (m, m/s) at ``t0_s``.
    change_times_s : array_like, shape (K,)
        Change times (s).
    time_s : array_like, shape (n,)
        Bearing times (s).
    own_xy : ndarray, shape (n, 2)
        Ownship positions (m; x east, y north).
    t0_s : float
        Reference time of p0 (s).
    with_change_times : bool
        Append the K columns dh/dc_k.

    Returns
    -------
    h, J, r : ndarray
        Bearings (rad), Jacobian, ranges (m).
    """
    p = np.asarray(params, dtype=float)
    t = np.asarray(time_s, dtype=float)
    A = leg_exposure_s(t, t0_s, change_times_s)
    V = p[2:].reshape(-1, 2)
    h, H, r = bearing_model(np.r_[p[:2], 0.0, 0.0], t - t0_s, own_xy - A @ V)
    g = H[:, :2]
    cols = [g, (A[:, :, None] * g[:, None, :]).reshape(len(t), -1)]
    if with_change_times:
        c = np.asarray(change_times_s, dtype=float)
        cols.append((t[:, None] > c) * (g @ (V[:-1] - V[1:]).T))
    return h, np.concatenate(cols, axis=1), r


def fisher_information_legs(params, change_times_s, time_s, own_xy, sigma_rad, t0_s: float,
                            with_change_times: bool = False) -> np.ndarray:
    """J = G^T G, G = Jacobian / sigma: the bearings' Fisher information about theta [and the change times].

    Parameters
    ----------
    params, change_times_s, time_s, own_xy, t0_s, with_change_times
        As :func:`leg_bearing_model`.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise sd (rad).

    Returns
    -------
    ndarray, shape (P, P)
        J, P = 2K + 4 [+ K].
    """
    _, Jac, _ = leg_bearing_model(params, change_times_s, time_s, own_xy, t0_s, with_change_times)
    G = Jac / np.broadcast_to(np.asarray(sigma_rad, dtype=float), (len(Jac),))[:, None]
    return G.T @ G


def _state_map(params, change_times_s, t0_s: float, t_s: float, with_change_times: bool, leg: int | None = None):
    """L (4, P): d[x, y, vx, vy](t) / d[theta, c]; the velocity of ``leg`` (default: the leg holding t)."""
    c = np.asarray(change_times_s, dtype=float)
    K = len(c)
    a = leg_exposure_s([t_s], t0_s, c)[0]
    k = int(np.searchsorted(c, t_s, side="left")) if leg is None else leg
    L = np.zeros((4, 2 * K + 4 + (K if with_change_times else 0)))
    L[0, 0] = L[1, 1] = 1.0
    L[0, 2:2 * K + 4:2] = L[1, 3:2 * K + 4:2] = a
    L[2, 2 + 2 * k] = L[3, 3 + 2 * k] = 1.0
    if with_change_times:
        V = np.asarray(params[2:], dtype=float).reshape(-1, 2)
        L[:2, 2 * K + 4:] = ((V[:-1] - V[1:]) * (t_s > c)[:, None]).T
    return L


def _lm(residual, x, max_iter: int, tol: float):
    """Levenberg-Marquardt as tma/batch_ml.ml_bearings_only runs it; returns (x, e, J, cost, iterations, converged)."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        e, J = residual(x)
    return levenberg_marquardt(residual, x, e, J, max_iter, tol, finite_only=True)


def _residual_fn(z, t, own, sig, t0, change_times_s=None):
    """Whitened residuals and Jacobian of theta (change times fixed) or of [theta, c] (``change_times_s`` None:
    they are the last K entries of x; an order that is not strictly increasing inside the record gives NaN)."""
    n_c = None if change_times_s is None else np.asarray(change_times_s, dtype=float)

    def residual(x):
        if n_c is None:
            K = (len(x) - 4) // 3
            theta, c = x[:2 * K + 4], x[2 * K + 4:]
            if not (np.all(np.diff(np.r_[t[0], c, t[-1]]) > 0)):
                return np.full(len(z), np.nan), np.full((len(z), len(x)), np.nan)
        else:
            theta, c = x, n_c
        h, Jac, _ = leg_bearing_model(theta, c, t, own, t0, with_change_times=n_c is None)
        return wrap_angle(z - h) / sig, Jac / sig[:, None]

    return residual


def pseudo_linear_legs(z_rad, time_s, own_xy, t0_s: float, change_times_s) -> np.ndarray:
    """Pseudo-linear theta: least squares over the bearing-line equations (module doc; Lindgren & Gong 1978).

    Parameters
    ----------
    z_rad, time_s : ndarray, shape (n,)
        Bearings (rad) and times (s).
    own_xy : ndarray, shape (n, 2)
        Ownship positions (m).
    t0_s : float
        Reference time of p0 (s).
    change_times_s : array_like, shape (K,)
        Change times (s).

    Returns
    -------
    ndarray, shape (2K + 4,)
        theta.
    """
    c, s = np.cos(z_rad), np.sin(z_rad)
    A = leg_exposure_s(time_s, t0_s, change_times_s)
    M = np.column_stack([c, -s, (A[:, :, None] * np.stack([c, -s], axis=1)[:, None, :]).reshape(len(c), -1)])
    x, *_ = np.linalg.lstsq(M, own_xy[:, 0] * c - own_xy[:, 1] * s, rcond=None)
    return x


def checked_bearings(time_s, bearing_rad, own_xy_m, sigma_rad, needs: str, min_n: int = 0):
    """A bearings record as float arrays (t, z, own, sd broadcast to (n,)), with a one-line :class:`InputError` for
    what a user can get wrong; ``needs`` says what the caller needs (the shape error's text) and ``min_n`` the fewest
    bearings."""
    t = np.asarray(time_s, dtype=float)
    z = np.asarray(bearing_rad, dtype=float)
    own = np.asarray(own_xy_m, dtype=float)
    require(t.ndim == 1 and z.shape == t.shape and own.shape == (len(t), 2) and len(t) >= min_n,
            f"{needs}; got {t.shape}, {z.shape}, {own.shape}")
    require(bool(np.all(np.isfinite(t)) and np.all(np.isfinite(z)) and np.all(np.isfinite(own))),
            "times, bearings and ownship positions must be finite: drop the rows with NaN or inf")
    require(bool(np.all(np.diff(t) > 0)), "bearing times must increase strictly: sort the record and drop duplicates")
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), t.shape)
    require(bool(np.all(np.isfinite(sig)) and np.all(sig > 0)), "the bearing sd must be positive and finite (rad)")
    return t, z, own, sig


def _check_inputs(time_s, bearing_rad, own_xy_m, sigma_rad, change_times_s):
    """Arrays as float, with a one-line :class:`InputError` for what a user can get wrong."""
    t, z, own, sig = checked_bearings(time_s, bearing_rad, own_xy_m, sigma_rad, "leg-wise TMA needs times and "
                                      "bearings of one length n and ownship positions of shape (n, 2)")
    c = np.atleast_1d(np.asarray(change_times_s, dtype=float)) if change_times_s is not None else np.empty(0)
    require(c.ndim == 1 and bool(np.all(np.isfinite(c))), "change times must be finite numbers (s)")
    require(bool(np.all(np.diff(np.r_[t[0], c, t[-1]]) > 0)),
            f"change times must increase strictly inside the record ({t[0]:g} to {t[-1]:g} s); got {list(c)}")
    counts = np.diff(np.searchsorted(t, np.r_[t[0] - 1.0, c, t[-1] + 1.0], side="right"))
    short = [k + 1 for k, m in enumerate(counts) if m < MIN_BEARINGS_PER_LEG]
    require(not short, f"leg(s) {short} hold fewer than {MIN_BEARINGS_PER_LEG} bearings: merge them with a "
                       "neighbour (drop a change time) or use a record with more bearings")
    require(len(t) >= 2 * len(c) + 5, f"{len(c) + 1} legs need at least {2 * len(c) + 5} bearings, got {len(t)}")
    return t, z, own, sig, c


def _profile_change_times(z, t, own, sig, theta, c, search_half_width_s: float):
    """Stage (1) of the module doc: each change time in turn set to the grid point (midpoints between bearings
    within ``search_half_width_s``, each leg keeping its bearings) of least cost, theta re-fitted warm."""
    mid = 0.5 * (t[1:] + t[:-1])
    for k in range(len(c)):
        lo = c[k - 1] if k else t[0]
        hi = c[k + 1] if k + 1 < len(c) else t[-1]
        i_lo = np.searchsorted(t, lo, side="right") + MIN_BEARINGS_PER_LEG - 1  # bearings of leg k before the grid
        i_hi = np.searchsorted(t, hi, side="left") - MIN_BEARINGS_PER_LEG
        grid = mid[i_lo:i_hi]
        grid = grid[np.abs(grid - c[k]) <= search_half_width_s]
        best = (np.inf, c[k], theta)
        for ck in grid:
            trial = c.copy()
            trial[k] = ck
            th, _, _, cost, _, _ = _lm(_residual_fn(z, t, own, sig, t[0], trial), theta.copy(), 20, 1e-8)
            if cost < best[0]:
                best = (cost, ck, th)
        c[k], theta = best[1], best[2]
    return theta, c


def _initial_fit(z, t, own, sig, c, params_init, max_iter: int, tol: float):
    """Theta by Levenberg-Marquardt at fixed change times from ``params_init``, else from the better of two starts:
    the pseudo-linear estimate, and a target at rest 10 km out along the first bearing. The second is there
    because the ownship's own track satisfies every bearing-line equation: when the ownship moves on legs the
    pseudo-linear least squares can return it (range 0), a start the ML cannot leave."""
    if params_init is not None:
        return _lm(_residual_fn(z, t, own, sig, t[0], c), np.asarray(params_init, float).copy(), max_iter, tol)
    far = np.r_[own[0] + 10_000.0 * np.array([np.sin(z[0]), np.cos(z[0])]), np.zeros(2 * len(c) + 2)]
    fits = [_lm(_residual_fn(z, t, own, sig, t[0], c), x, max_iter, tol)
            for x in (pseudo_linear_legs(z, t, own, t[0], c), far)]
    return min(fits, key=lambda f: f[3] if np.isfinite(f[3]) else np.inf)


def fit_legs(time_s, bearing_rad, own_xy_m, sigma_rad, change_times_s, *, refine: bool = True,
             search_half_width_s: float = 900.0, params_init=None, max_iter: int = 100, tol: float = 1e-10,
             max_range_sd_fraction: float = MAX_RANGE_SD_FRACTION,
             motion_alpha: float | None = MOTION_ALPHA, max_speed_mps: float = MAX_SPEED_MPS) -> LegFit:
    """Leg-wise bearings-only ML (module doc): piecewise-constant velocity, continuous position, velocity changes
    at ``change_times_s``; with ``refine`` the change times are estimated too (profile, then joint Gauss-Newton).

    Parameters
    ----------
    time_s, bearing_rad : array_like, shape (n,)
        Strictly increasing times (s) and bearings (rad, clockwise from north).
    own_xy_m : array_like, shape (n, 2)
        Ownship positions (m; x east, y north) at the bearing times.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise sd (rad).
    change_times_s : array_like, shape (K,)
        Change times (s), strictly inside the record and increasing, each leg holding >= 2 bearings; K = 0 is the
        constant-velocity ML.
    refine : bool
        Estimate the change times (starting from ``change_times_s``); else hold them fixed.
    search_half_width_s : float
        Half-width (s) of the profile grid around each given change time.
    params_init : array_like (2K + 4,) or None
        Start for theta (None: the pseudo-linear estimate).
    max_iter, tol : int, float
        Levenberg-Marquardt iteration limit and relative cost decrease that ends it.
    max_range_sd_fraction : float
        A leg whose range sd exceeds this fraction of its range is not determined.
    motion_alpha : float or None
        Significance of the fit's own whiteness tests (module doc); None: not tested.
    max_speed_mps : float
        A fit with a leg faster than this is no ship's track (a missed zig, or a range the bearings do not fix):
        no leg of it is determined (:func:`_speed_rejection`).

    Returns
    -------
    LegFit
        Parameters, change times, covariance (inverse Fisher information at the estimate), legs (not determined
        where the residuals reject them), final position.
    """
    t, z, own, sig, c = _check_inputs(time_s, bearing_rad, own_xy_m, sigma_rad, change_times_s)
    theta, e, Jac, cost, it, conv = _initial_fit(z, t, own, sig, c, params_init, max_iter, tol)
    refined = bool(refine and len(c))
    if refined:
        theta, c = _profile_change_times(z, t, own, sig, theta, c.copy(), search_half_width_s)
        x, e, Jac, cost, it2, conv = _lm(_residual_fn(z, t, own, sig, t[0]), np.r_[theta, c], max_iter, tol)
        theta, c, it = x[:2 * len(c) + 4], x[2 * len(c) + 4:], it + it2
    cov = _inverse_information(Jac)
    legs = tuple(_leg_summary(theta, c, cov, t, own, k, refined, max_range_sd_fraction) for k in range(len(c) + 1))
    note = "" if motion_alpha is None else motion_rejection(t, e, sig, c, Jac.shape[1], motion_alpha)
    if note := note or _speed_rejection(legs, max_speed_mps):
        legs = tuple(replace(leg, determined=False, reason=note) for leg in legs)
    L = _state_map(theta, c, t[0], t[-1], refined)[:2]
    with np.errstate(invalid="ignore"):
        p_cov = L @ cov @ L.T
    return LegFit(params=theta, change_times_s=c, covariance=cov, t0_s=float(t[0]), t_end_s=float(t[-1]), legs=legs,
                  position_end_m=_positions(theta, c, t[0], t[-1:])[0], position_end_cov=p_cov, objective=cost,
                  dof=len(t) - Jac.shape[1], iterations=it, converged=bool(conv), refined=refined,
                  residuals=np.asarray(e, float), motion_note=note)


def motion_rejection(time_s, residual, sigma_rad, change_times_s, n_params: int, alpha: float) -> str:
    """The leg fit's own verdict (module doc): "" when its whitened residuals pass the whiteness test on every leg
    and over the record, else the reason naming the first leg that fails (or the record) and its span.

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        Bearing times (s).
    residual : ndarray, shape (n,)
        Whitened residuals wrap(z - h) / sigma of the leg fit.
    sigma_rad : ndarray, shape (n,)
        Bearing noise sd (rad): the resolution floor is whitened by it.
    change_times_s : ndarray, shape (K,)
        The fit's change times (s).
    n_params : int
        Parameters fitted over the record (2K + 4 [+ K]).
    alpha : float
        Significance of each test.

    Returns
    -------
    str
        "" or "target manoeuvred: residuals reject constant velocity on leg k, largest A-B s".
    """
    t, w = np.asarray(time_s, float), np.asarray(residual, float)
    floor = float(np.radians(RESOLUTION_DEG) / np.median(sigma_rad))
    if not np.all(np.isfinite(w)):
        return ""
    leg_of = np.searchsorted(np.asarray(change_times_s, float), t, side="left")
    K = len(change_times_s)
    for k in range(K + 1):
        sel = leg_of == k
        if sel.sum() >= 8 and not whiteness_check(w[sel], alpha, floor, n_params=4).white:
            return _span_reason(f"on leg {k + 1}" if K else "on its one leg", t[sel], w[sel])
    if K and not whiteness_check(w, alpha, floor, n_params=n_params).white:
        return _span_reason("over the record's legs", t, w)
    dof = len(w) - n_params
    if dof > 0 and float(w @ w) > chi2_quantile(1.0 - alpha, dof):  # more misfit than the stated noise allows
        return _span_reason(f"(chi-square {float(w @ w):.0f} for {dof} degrees of freedom at the stated sd)", t, w)
    return ""


def _span_reason(where: str, t, w) -> str:
    span = residual_span(t, w, 1.0)
    at = f", largest {span[0]:.0f}-{span[1]:.0f} s" if span is not None else ""
    return f"{MANOEUVRED}: residuals reject constant velocity {where}{at}"


def _course_speed(v, P):
    """Course (deg, 0..360 clockwise from north), its sd, speed (kn) and its sd from velocity v and covariance P."""
    speed = float(np.hypot(v[0], v[1]))
    course = float(np.degrees(np.arctan2(v[0], v[1])) % 360.0)
    if speed == 0.0:
        return course, float("inf"), 0.0, float(np.sqrt(np.trace(P) / 2) / KNOT_MPS)
    gs, gc = v / speed, np.array([v[1], -v[0]]) / speed**2  # d speed / dv, d course / dv (rad)
    with np.errstate(invalid="ignore"):
        return course, float(np.degrees(np.sqrt(gc @ P @ gc))), speed / KNOT_MPS, float(np.sqrt(gs @ P @ gs) / KNOT_MPS)


def _leg_summary(theta, c, cov, t, own, k: int, refined: bool, max_range_sd_fraction: float) -> Leg:
    """Leg k's span, course and speed with sds, its state at its end and how well its range is determined."""
    K = len(c)
    start, end = (t[0] if k == 0 else c[k - 1]), (t[-1] if k == K else c[k])
    sd_c = np.sqrt(np.diag(cov)[2 * K + 4:]) if refined else np.zeros(K)
    L = _state_map(theta, c, t[0], end, refined, leg=k)
    with np.errstate(invalid="ignore"):
        P = L @ cov @ L.T
    state = np.r_[_positions(theta, c, t[0], [end])[0], theta[2 + 2 * k:4 + 2 * k]]
    course, course_sd, speed, speed_sd = _course_speed(state[2:], P[2:, 2:])
    d = state[:2] - np.array([np.interp(end, t, own[:, 0]), np.interp(end, t, own[:, 1])])
    rng = float(np.hypot(*d))
    u = d / rng if rng > 0 else np.zeros(2)
    with np.errstate(invalid="ignore"):
        rng_sd = float(np.sqrt(u @ P[:2, :2] @ u))
    cond = _correlation_condition(P)
    determined = bool(np.isfinite(rng_sd) and rng_sd <= max_range_sd_fraction * rng)
    reason = "" if determined else (
        f"range not determined on leg {k + 1}: its sd exceeds {max_range_sd_fraction:g} of the range (information "
        f"condition {cond:.2g})")  # no number for a range the bearings do not give
    return Leg(start_s=float(start), end_s=float(end), start_sd_s=float(sd_c[k - 1]) if k else 0.0,
               end_sd_s=float(sd_c[k]) if k < K else 0.0, course_deg=course, course_sd_deg=course_sd,
               speed_kn=speed, speed_sd_kn=speed_sd, state=state, state_cov=P, range_m=rng, range_sd_m=rng_sd,
               information_condition=cond, determined=determined, reason=reason)


def _inverse_information(Jac) -> np.ndarray:
    """(J^T J)^-1 of the whitened Jacobian J: the fit's covariance (the CRB at the estimate); inf where singular."""
    try:
        return np.linalg.inv(Jac.T @ Jac)
    except np.linalg.LinAlgError:
        return np.full((Jac.shape[1],) * 2, np.inf)


def _speed_rejection(legs, max_speed_mps: float) -> str:
    """The reason no leg of a fit is determined when one of its legs is faster than ``max_speed_mps`` (m/s), else
    "". The legs share the fit's positions, so one impossible leg (seen on a record with a missed zig: 696 kn on
    its first leg while the last printed 40 km for a target at 4-12 km) discredits the others."""
    fast = [(k, leg.speed_kn) for k, leg in enumerate(legs) if not leg.speed_kn * KNOT_MPS <= max_speed_mps]
    if not fast:
        return ""
    k, speed_kn = max(fast, key=lambda f: f[1] if np.isfinite(f[1]) else np.inf)
    return (f"{DIVERGED}: leg {k + 1} at {speed_kn:.0f} kn, faster than any ship ({max_speed_mps / KNOT_MPS:.0f} kn): "
            "a zig missed, or ranges the bearings do not fix")


def _correlation_condition(P) -> float:
    """Condition number of the correlation matrix of P (= that of the information D J D in correlation form)."""
    with np.errstate(invalid="ignore"):  # a negative variance (a covariance broken by rounding): NaN, refused below
        d = np.sqrt(np.diag(P))
    if not np.all(np.isfinite(P)) or np.any(d <= 0):
        return float("inf")
    with np.errstate(over="ignore", invalid="ignore"):
        R = P / np.outer(d, d)
    if not np.all(np.isfinite(R)):  # sds near the float limit (a fit run off to 1e16 m): nothing is determined
        return float("inf")
    try:
        w = np.linalg.eigvalsh(R)
    except np.linalg.LinAlgError:
        return float("inf")
    return float(w[-1] / w[0]) if w[0] > 0 else float("inf")


def crb_legs(params_true, change_times_s, time_s, own_xy, sigma_rad, *, with_change_times: bool = False):
    """Cramer-Rao bound of the leg-wise model at the true parameters, and per leg the bound on the leg's state
    [x, y, vx, vy] at its end (the bound mapped through the state's gradient; module doc).

    Parameters
    ----------
    params_true : array_like, shape (2K + 4,)
        True theta at the first bearing's time.
    change_times_s : array_like, shape (K,)
        True change times (s).
    time_s : array_like, shape (n,)
        Bearing times (s).
    own_xy : ndarray, shape (n, 2)
        Ownship positions (m).
    sigma_rad : float or array_like, shape (n,)
        Bearing noise sd (rad).
    with_change_times : bool
        The change times are unknown too (the bound of a fit with ``refine``).

    Returns
    -------
    crb : ndarray, shape (P, P)
        J^-1 over [theta (, c)].
    leg_crbs : ndarray, shape (K + 1, 4, 4)
        Per leg, the bound on [x, y, vx, vy] at the leg's end.
    """
    t = np.asarray(time_s, dtype=float)
    c = np.atleast_1d(np.asarray(change_times_s, dtype=float))
    B = np.linalg.inv(fisher_information_legs(params_true, c, t, own_xy, sigma_rad, t[0], with_change_times))
    ends = np.r_[c, t[-1]]
    Ls = [_state_map(params_true, c, t[0], ends[k], with_change_times, leg=k) for k in range(len(c) + 1)]
    return B, np.stack([L @ B @ L.T for L in Ls])
