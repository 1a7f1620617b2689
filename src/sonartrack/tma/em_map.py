"""EM/MAP target motion analysis with bearings, measured SNR and a propagation model
(paper P3, eqs. 19-29, after Streit & Walsh 2002; E and M steps derived here from the model).

Model, per frame n (time t_n, tau_n = t_n - t0, ownship o_n, bearing theta_n, SNR xi_n):
the target position P_n = F'_n X0 with F'_n = [[1, 0, tau_n, 0], [0, 1, 0, tau_n]], and a latent
range r on [r_min, r_max]:

    p(xi_n | r)      = N(xi_n; xi_bar(r), sigma_SNR^2),  xi_bar(r) = SL - TL(r) + DI - NL   (eq. 30)
    p(P_n | r)       = N(P_n; mu_n(r), r^2 Sigma_n),     mu_n(r) = o_n + r u_n,  u_n = [sin th, cos th]
    Sigma_n          = U_n diag(sigma_n^2, kappa^2) U_n^T, U_n = [[cos th, sin th], [-sin th, cos th]]

(cross-range spread r sigma_n from the bearing error, along-range spread r kappa: kappa is our
choice, see :data:`KAPPA`). With r uniform in area (measure r dr) the incomplete-data objective is

    L(X0) = sum_n log integral psi_n(r) r dr,   psi_n(r) = p(xi_n | r) N(F'_n X0; mu_n(r), r^2 Sigma_n)

E-step (eq. 24-25): p_n(r) = psi_n(r; X0_old) / integral psi_n(rho) rho d rho.
M-step: maximise sum_n E[log N(F'_n X0; mu_n(r), r^2 Sigma_n)] over X0. The r^2 in the covariance
and the r dr measure turn the expectations into integrals of p_n(r) dr / r (eqs. 26-28):

    A_n = F'_n^T Sigma_n^-1 F'_n  integral p_n(r) dr / r
    b_n = F'_n^T Sigma_n^-1       integral p_n(r) mu_n(r) dr / r
    X0_new = (sum_n A_n)^-1 sum_n b_n                                                       (eq. 29)

The integrals run on a logarithmic range grid (r dr = r^2 dlog r), which makes EM on a discrete
latent range with prior mass proportional to r_j^2: each iteration cannot decrease L (Dempster, Laird
& Rubin 1977), which the tests check. No derivative of the bearing function is needed.

Initialisation (tma/em_map_start.py; robust to the multimodal SNR of convergence zones): a grid search over tracks
through a point on the first bearing line and one on the last (ranges on a log grid), scored by the
direct bearing + SNR log-likelihood; EM starts from the best few in distinct range basins and from
the bearings-only ML estimate when there is one, and the highest final L wins.

Covariance. The inverse observed information P of L is the covariance when the model is exact; it is
consistent then (Monte Carlo NEES of the position ~ 2, tests/tma/test_em_map_covariance.py). But xi_bar
rests on a level SL + DI - NL that is never known exactly (a source level from a class, a nominal DI and
NL), and a level error b shifts every xi_bar(r) alike: the fitted range moves so that TL(r) absorbs b
(b / (dTL/dr) in range: 0.5 dB is 6 % on 20 log r), the SNR residuals stay white (the residual check
cannot see it), and P, built for b = 0, does not contain it. The estimator keeps b = 0 (P3 takes SL as
known); its covariance carries b ~ N(0, sigma_level^2) as a *consider* parameter (Tapley, Schutz & Born
2004, *Statistical Orbit Determination*, ch. 6: P_c = P + S P_bb S^T, S = dX0_hat/db). A real TL curve
is not monotonic in range (convergence zones, the ripple left after averaging), so S varies within a dB
and a level error can move the fit to another range basin; S sigma_level is therefore taken from the
estimator itself at the two symmetric sigma points of b (the unscented transform of a scalar with
n + kappa_UT = 1, weights 1/2: Julier & Uhlmann 2004, Proc. IEEE 92(3), the symmetric set):

    P_c = P + 1/2 sum_{+,-} (X0_hat(+-sigma_level) - X0_hat) (X0_hat(+-sigma_level) - X0_hat)^T

X0_hat(b) the solve with xi_bar + b (same starts, plus X0_hat). For a smooth TL and a small sigma_level this
is the linear consider covariance P + sigma_level^2 s s^T, s = P d2L/dX0 db (tested).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from sonartrack.core.errors import require
from sonartrack.tma.batch_ml import BatchEstimate

#: relative along-range spread of the position model. The latent r *is* the target's range, so the
#: exact model is kappa -> 0; a positive kappa smooths p(xi | r) over a window of relative width
#: kappa and biases the noise-free solution by O(kappa^2) with a smooth TL curve (more where TL has
#: interference ripple). 1 % keeps that bias far below the errors from noise, and EM (accelerated)
#: still converges in tens of iterations.
KAPPA = 0.01
#: log-range grid step as a fraction of kappa (the grid must resolve the along-range kernel)
GRID_STEP_OF_KAPPA = 0.5
#: standard deviation (dB) of the level SL + DI - NL that xi_bar assumes, carried in the covariance (module
#: doc, consider covariance). 1 dB: a level given as a number is rarely known better (a nominal DI alone,
#: 10 log10 N against a design figure, differs by ~0.5 dB on a 16-element array); 0 states the level as exact.
SIGMA_LEVEL_DB = 1.0


@dataclass(frozen=True, slots=True)
class FrameTerms:
    """Per-frame constants of the E and M steps, computed once per problem (they depend on the data only)."""

    sin: np.ndarray  # sin theta_n
    cos: np.ndarray  # cos theta_n
    rows: np.ndarray  # (n, 1) frame index, for gathering a window of the grid per frame
    sigma2: np.ndarray  # (n, 1) sigma_n^2
    log_norm: np.ndarray  # (n, 1) -log(2 pi sigma_n kappa)
    window: np.ndarray  # (1, 2 w + 1) offsets of the E-step window on the grid
    r_grid: np.ndarray  # the range grid r_j, contiguous (gathered with ``take``)
    r2_grid: np.ndarray  # r_j^2
    log_snr_lik: np.ndarray  # log p(xi_n | r_j) flattened, gathered at row_start + j
    row_start: np.ndarray  # (n, 1) offset of frame n's row in ``log_snr_lik``
    unit: np.ndarray  # (n, 2) u_n = [sin theta_n, cos theta_n]
    F: np.ndarray  # (n, 2, 4) F'_n
    FtS: np.ndarray  # (n, 4, 2) F'_n^T Sigma_n^-1


@dataclass(frozen=True, slots=True)
class EmProblem:
    """The data and model of one EM/MAP solve, precomputed on the range grid."""

    tau_s: np.ndarray
    own_xy: np.ndarray
    theta_rad: np.ndarray
    r_grid: np.ndarray
    log_snr_lik: np.ndarray  # (n, n_r): log p(xi_n | r_j); 0 where the SNR is missing
    sigma_rad: np.ndarray
    kappa: float
    snr_db: np.ndarray | None = None  # (n,) measured SNR xi_n (dB), NaN where missing; None: no SNR
    xi_bar_db: np.ndarray | None = None  # (n_r,) xi_bar(r_j) (dB)
    sigma_snr_db: float = float("nan")
    sigma_level_db: float = 0.0  # sd of the level SL + DI - NL (dB), a consider parameter of the covariance
    terms: FrameTerms = field(init=False, repr=False, compare=False)
    #: [(key, result)] of the last :func:`_e_step`
    memo: list = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "terms", _frame_terms(self))
        object.__setattr__(self, "memo", [None])


def _frame_terms(prob: EmProblem) -> FrameTerms:
    """The per-frame constants of :func:`_log_psi` and :func:`em_step` (Sigma_n^-1 as in the module doc)."""
    s, c = np.sin(prob.theta_rad), np.cos(prob.theta_rad)
    nr = len(prob.r_grid)
    step = np.log(prob.r_grid[1] / prob.r_grid[0]) if nr > 1 else 1.0
    w = min(int(np.ceil(WINDOW_KAPPAS * prob.kappa / step)), (nr - 1) // 2)
    # Sigma_n^-1 = U diag(1/sigma^2, 1/kappa^2) U^T with U's columns across [c, -s] and along [s, c]
    a, b = 1.0 / prob.sigma_rad**2, 1.0 / prob.kappa**2
    Si = np.empty((len(s), 2, 2))
    Si[:, 0, 0] = a * c * c + b * s * s
    Si[:, 1, 1] = a * s * s + b * c * c
    Si[:, 0, 1] = Si[:, 1, 0] = -a * c * s + b * s * c
    Fp = np.zeros((len(s), 2, 4))
    Fp[:, 0, 0] = Fp[:, 1, 1] = 1.0
    Fp[:, 0, 2] = Fp[:, 1, 3] = prob.tau_s
    return FrameTerms(sin=s, cos=c, rows=np.arange(len(s))[:, None], sigma2=prob.sigma_rad[:, None] ** 2,
                      log_norm=-np.log(2 * np.pi * prob.sigma_rad[:, None] * prob.kappa),
                      window=np.arange(2 * w + 1)[None, :], r_grid=np.ascontiguousarray(prob.r_grid),
                      r2_grid=np.ascontiguousarray(prob.r_grid) ** 2,
                      log_snr_lik=np.ascontiguousarray(prob.log_snr_lik).ravel(),
                      row_start=np.arange(len(s))[:, None] * nr, unit=np.column_stack([s, c]), F=Fp,
                      FtS=np.swapaxes(Fp, 1, 2) @ Si)


def make_problem(z_rad, snr_db, time_s, own_xy, sigma_rad, sigma_snr_db: float, snr_of_range: Callable,
                 r_min_m: float, r_max_m: float, kappa: float = KAPPA, n_range: int | None = None,
                 sigma_level_db: float = SIGMA_LEVEL_DB) -> EmProblem:
    """Precompute the range grid and log p(xi_n | r) (``snr_of_range(r) -> dB`` is xi_bar).

    The grid has ``n_range`` points (default: a step of kappa / 2 in log range).

    Parameters
    ----------
    z_rad, snr_db, time_s : array_like, shape (n,)
        Bearings (rad, clockwise from north), measured SNRs (dB; None or NaN entries: no SNR term) and strictly
        increasing frame times (s); n >= 3.
    own_xy : array_like, shape (n, 2)
        Ownship positions (m; x east, y north).
    sigma_rad : float or array_like, shape (n,)
        Bearing noise standard deviation (rad).
    sigma_snr_db : float
        SNR noise standard deviation sigma_SNR (dB).
    snr_of_range : callable
        xi_bar(r): predicted SNR (dB) at ranges r (m), eq. 30.
    r_min_m, r_max_m : float
        Range interval of the latent range (m).
    kappa : float
        Relative along-range spread of the position model (:data:`KAPPA`).
    n_range : int, optional
        Grid points.
    sigma_level_db : float
        Standard deviation of the level SL + DI - NL of ``snr_of_range`` (dB), carried in the covariance
        (:data:`SIGMA_LEVEL_DB`; module doc); 0: the level is exact.

    Returns
    -------
    EmProblem
        Times since the first frame, the grid and log p(xi_n | r_j), with the per-frame constants.
    """
    z = np.asarray(z_rad, dtype=float)
    t = np.asarray(time_s, dtype=float)
    own = np.asarray(own_xy, dtype=float)
    require(len(z) == len(t) == len(own) and len(z) >= 3, "em-map needs at least 3 frames of bearing, time and ownship")
    require(bool(np.all(np.diff(t) > 0)), "frame times must increase strictly: sort the file and drop duplicates")
    require(0 < r_min_m < r_max_m, f"range interval must satisfy 0 < r_min < r_max, got {r_min_m:g}..{r_max_m:g} m")
    require(sigma_snr_db > 0, "sigma_SNR must be positive")
    require(kappa > 0, "kappa must be positive")
    require(sigma_level_db >= 0, "sigma_level must be >= 0")
    if n_range is None:
        n_range = int(np.ceil(np.log(r_max_m / r_min_m) / (GRID_STEP_OF_KAPPA * kappa))) + 1
    r = np.geomspace(r_min_m, r_max_m, n_range)
    xi_bar = np.asarray(snr_of_range(r), dtype=float)
    require(xi_bar.shape == r.shape and bool(np.all(np.isfinite(xi_bar))),
            "the SNR model must give finite values on the range grid")
    xi = None
    if snr_db is None:
        ll = np.zeros((len(z), len(r)))
    else:
        xi = np.asarray(snr_db, dtype=float)
        ll = _snr_log_lik(xi, xi_bar, sigma_snr_db)
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), z.shape).copy()
    return EmProblem(t - t[0], own, z, r, ll, sig, float(kappa), xi, xi_bar, float(sigma_snr_db), float(sigma_level_db))


def _snr_log_lik(xi_db: np.ndarray, xi_bar_db: np.ndarray, sigma_snr_db: float) -> np.ndarray:
    """log p(xi_n | r_j) (n, n_r) of eq. 30; 0 on a frame without an SNR (NaN)."""
    ll = -0.5 * ((xi_db[:, None] - xi_bar_db[None, :]) / sigma_snr_db) ** 2 - np.log(np.sqrt(2 * np.pi) * sigma_snr_db)
    ll[~np.isfinite(xi_db)] = 0.0
    return ll


def level_shifted(prob: EmProblem, shift_db: float) -> EmProblem:
    """The same data with the SNR model raised by ``shift_db``: xi_bar(r) + shift (a level SL + DI - NL error).

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`) with SNRs.
    shift_db : float
        Added to xi_bar (dB).

    Returns
    -------
    EmProblem
        The problem of xi_bar + shift, everything else as ``prob``.
    """
    require(prob.snr_db is not None, "a level shift needs the SNRs")
    xi_bar = prob.xi_bar_db + float(shift_db)
    return EmProblem(prob.tau_s, prob.own_xy, prob.theta_rad, prob.r_grid,
                     _snr_log_lik(prob.snr_db, xi_bar, prob.sigma_snr_db), prob.sigma_rad, prob.kappa, prob.snr_db,
                     xi_bar, prob.sigma_snr_db, prob.sigma_level_db)


#: half-width of the range window of the E-step, in units of kappa (module doc: the along-range
#: kernel exp(-(a - r)^2 / (2 r^2 kappa^2)) is below e^-70 outside it)
WINDOW_KAPPAS = 12.0


def _log_psi(prob: EmProblem, x0, full: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """log psi_n(r_j) + log r_j^2 (the measure on the log grid) and the r_j it is evaluated at.

    Only a window of the grid around the peak of each frame's position factor is evaluated (the
    rest weighs < e^-70 relative); ``full=True`` evaluates the whole grid (the reference)."""
    lp, r, _ = _log_psi_eval(prob, x0, full)
    return lp, r


def _log_psi_eval(prob: EmProblem, x0, full: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_log_psi` and r_j^2."""
    T = prob.terms
    dx = x0[0] + x0[2] * prob.tau_s - prob.own_xy[:, 0]  # P_n - o_n; mu_n(r) - o_n = r u_n
    dy = x0[1] + x0[3] * prob.tau_s - prob.own_xy[:, 1]
    cross = dx * T.cos - dy * T.sin  # component across the bearing line (mu has none)
    along = dx * T.sin + dy * T.cos
    n, nr = prob.log_snr_lik.shape
    if not full and (along <= prob.r_grid[0]).any():
        full = True  # a track behind or at the ownship (far-off iterate): the mass is not near one range
    if full:
        J = np.broadcast_to(np.arange(nr), (n, nr))
    else:
        # the position factor peaks at r* = a + (c kappa / sigma)^2 / a (minimise
        # (c^2 / sigma^2 + (a - r)^2 / kappa^2) / r^2 over r) and is narrower than kappa in log r
        centre = along + (cross * prob.kappa / prob.sigma_rad) ** 2 / along
        j = prob.r_grid.searchsorted(np.maximum(centre, prob.r_grid[0]))
        width = T.window.shape[1]
        J = np.minimum(np.maximum(j - width // 2, 0), nr - width)[:, None] + T.window
    r, r2 = T.r_grid.take(J), T.r2_grid.take(J)
    m = (cross[:, None] ** 2 / T.sigma2 + (along[:, None] - r) ** 2 / prob.kappa**2) / r2
    # log_norm: the 1/r^2 cancels the r^2 measure
    return T.log_snr_lik.take(T.row_start + J) + T.log_norm - 0.5 * m, r, r2


def _e_step(prob: EmProblem, x0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The windowed E-step at ``x0``: (r_j, r_j^2, unnormalised posterior weights w_nj, their row sums, L(x0)).

    The last result is kept on the problem and returned again for the same ``x0`` (read-only arrays):
    EM evaluates each accepted iterate twice, its objective and then the next E-step."""
    key = np.asarray(x0, dtype=float).tobytes()
    last = prob.memo[0]  # read once: (key, result), replaced whole, so threads sharing a problem stay consistent
    if last is not None and last[0] == key:
        return last[1]
    lp, r, r2 = _log_psi_eval(prob, x0, False)
    mx = lp.max(axis=1, keepdims=True)
    w = np.exp(lp - mx)
    tot = w.sum(axis=1)
    out = r, r2, w, tot, float(np.sum(mx[:, 0] + np.log(tot)))
    prob.memo[0] = (key, out)
    return out


def objective(prob: EmProblem, x0, full: bool = False) -> float:
    """L(X0) = sum_n log sum_j psi_n(r_j) r_j^2 (dlog r dropped: a constant).

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    x0 : array_like, shape (4,)
        [x0, y0, vx, vy] at the first frame (m, m/s).
    full : bool
        Evaluate the whole range grid (the reference) instead of a window around each frame's peak.

    Returns
    -------
    float
        L(X0).
    """
    if not full:
        return _e_step(prob, np.asarray(x0, dtype=float))[4]
    lp, _ = _log_psi(prob, np.asarray(x0, dtype=float), full)
    mx = lp.max(axis=1, keepdims=True)
    return float(np.sum(mx[:, 0] + np.log(np.exp(lp - mx).sum(axis=1))))


def em_step(prob: EmProblem, x0) -> tuple[np.ndarray, float]:
    """One E and M step from ``x0``: (X0_new, L(x0)).

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    x0 : ndarray, shape (4,)
        Current X0 (m, m/s).

    Returns
    -------
    x0_new : ndarray, shape (4,)
        X0 of eq. 29.
    L : float
        L at ``x0``.
    """
    r, r2, w, tot, L = _e_step(prob, x0)
    q = w / tot[:, None]  # posterior mass of r_j
    e_inv_r2 = (q / r2).sum(axis=1)  # E[1/r^2] = integral p_n dr / r
    e_inv_r = (q / r).sum(axis=1)  # mu_n(r) / r^2 = o_n / r^2 + u_n / r
    T = prob.terms
    m_mean = prob.own_xy * e_inv_r2[:, None] + T.unit * e_inv_r[:, None]  # E[mu / r^2]
    A = np.einsum("nij,njk,n->ik", T.FtS, T.F, e_inv_r2)
    bb = np.einsum("nij,nj->i", T.FtS, m_mean)
    return np.linalg.solve(A, bb), L


def _squarem_step(prob: EmProblem, x, L_x: float, scale) -> tuple[np.ndarray, float]:
    """One SQUAREM iteration from ``x`` (see :func:`em_map`): (X0_new, L(X0_new)), with L(X0_new) >= L(x)."""
    x1, _ = em_step(prob, x)
    x2, _ = em_step(prob, x1)
    r, v = (x1 - x) * scale, (x2 - 2 * x1 + x) * scale
    nv = float(np.linalg.norm(v))
    a = -float(np.linalg.norm(r)) / nv if nv > 0 else -1.0
    a = min(a, -1.0)
    while True:
        x_sq = x - (2 * a * r - a * a * v) / scale
        x_new, _ = em_step(prob, x_sq)
        L_new = objective(prob, x_new)
        if np.isfinite(L_new) and L_new >= L_x:
            return x_new, L_new
        if a == -1.0:  # plain EM from x2 cannot decrease L
            return x2, objective(prob, x2)
        a = min((a - 1.0) / 2.0, -1.0)


def em_map(prob: EmProblem, x_init, max_iter: int = 500, tol: float = 1e-10,
           accelerate: bool = True) -> tuple[np.ndarray, int, list[float]]:
    """Iterate EM from ``x_init``; (X0, iterations, L history (one value per accepted iterate)).

    EM converges slowly here: the latent range is almost determined by X0 (a small kappa), so each
    step moves X0 only a little along the range direction. ``accelerate`` uses SQUAREM (Varadhan &
    Roland 2008, scheme S3): two EM steps r = M(x) - x, v = M(M(x)) - 2 M(x) + x, the extrapolation
    x - 2 a r + a^2 v with a = -|r| / |v| (<= -1), then one EM step from there; the result is kept
    only if L did not decrease, else a is halved towards -1 (plain EM), so L never decreases.
    Stops when L changes by less than ``tol`` (relative) and the position by less than 1e-7 of the range.

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    x_init : array_like, shape (4,)
        Start (m, m/s).
    max_iter : int
        Iteration limit.
    tol : float
        Relative change of L that ends the iteration.
    accelerate : bool
        Use SQUAREM.

    Returns
    -------
    x0 : ndarray, shape (4,)
        Final X0.
    iterations : int
        Iterations run.
    history : list of float
        L at the start and after each iteration.
    """
    x = np.asarray(x_init, dtype=float)
    L_x = objective(prob, x)
    history: list[float] = [L_x]
    scale = np.array([1.0, 1.0, 100.0, 100.0])  # put m and m/s on comparable footing for the step length
    it = 0
    while it < max_iter:
        it += 1
        if accelerate:
            x_new, L_new = _squarem_step(prob, x, L_x, scale)
        else:
            x_new, _ = em_step(prob, x)
            L_new = objective(prob, x_new)
        step = float(np.hypot(*(x_new[:2] - x[:2])))
        rng = float(np.hypot(*(x_new[:2] - prob.own_xy[0])))
        done = abs(L_new - L_x) <= tol * max(abs(L_new), 1.0) and step <= 1e-7 * max(rng, 1.0)
        x, L_x = x_new, L_new
        history.append(L_x)
        if done:
            break
    return x, it, history


def observed_information(prob: EmProblem, x0, scale=None) -> np.ndarray:
    """-Hessian of L at X0 by central differences (the covariance of the estimate is its inverse).

    Parameters
    ----------
    prob, x0 : EmProblem, array_like (4,)
        The data and model (:func:`make_problem`), and X0 (m, m/s) where the Hessian is taken.
    scale : array_like, shape (4,), optional
        Difference steps; default 1e-3 of the range (m) for the position and 1e-3 m/s for the velocity.

    Returns
    -------
    ndarray, shape (4, 4)
        The observed information.
    """
    x0 = np.asarray(x0, dtype=float)
    rng = float(np.hypot(*(x0[:2] - prob.own_xy[0])))
    h = np.array([1e-3 * rng, 1e-3 * rng, 1e-3, 1e-3]) if scale is None else np.asarray(scale)
    Hm = np.empty((4, 4))
    f0 = objective(prob, x0)
    for i in range(4):
        for j in range(i, 4):
            ei, ej = np.eye(4)[i] * h[i], np.eye(4)[j] * h[j]
            if i == j:
                v = (objective(prob, x0 + ei) - 2 * f0 + objective(prob, x0 - ei)) / h[i] ** 2
            else:
                v = (objective(prob, x0 + ei + ej) - objective(prob, x0 + ei - ej) - objective(prob, x0 - ei + ej)
                     + objective(prob, x0 - ei - ej)) / (4 * h[i] * h[j])
            Hm[i, j] = Hm[j, i] = -v
    return Hm


def _best_run(prob: EmProblem, starts, max_iter: int):
    """(X0, iterations, L history) of the EM run from ``starts`` that ends with the highest L."""
    best = None
    for s in starts:
        x, it, hist = em_map(prob, s, max_iter=max_iter)
        if np.all(np.isfinite(x)) and (best is None or hist[-1] > best[2][-1]):
            best = (x, it, hist)
    return best


def _starts(prob: EmProblem, extra_starts) -> list[np.ndarray]:
    """The grid search's starts and the extra ones (None skipped)."""
    from sonartrack.tma.em_map_start import grid_initialisation  # it imports this module

    return [*grid_initialisation(prob), *[np.asarray(s, dtype=float) for s in extra_starts if s is not None]]


def level_covariance(prob: EmProblem, x0, extra_starts=(), max_iter: int = 500) -> np.ndarray:
    """The level's part of the consider covariance (module doc): 1/2 sum over b = +-sigma_level of
    (X0_hat(b) - X0_hat)(X0_hat(b) - X0_hat)^T, X0_hat(b) the solve of :func:`level_shifted` (b).

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`); ``prob.sigma_level_db`` is sigma_level.
    x0 : array_like, shape (4,)
        X0_hat, the solution of ``prob`` (m, m/s); a start of the shifted solves too.
    extra_starts : iterable of array_like (4,) or None
        The other starts of the solve (as :func:`solve_em_map`).
    max_iter : int
        Iteration limit of each EM run.

    Returns
    -------
    ndarray, shape (4, 4)
        The term (m^2, m^2/s, m^2/s^2); zeros when sigma_level is 0 or there are no SNRs.
    """
    x0 = np.asarray(x0, dtype=float)
    out = np.zeros((4, 4))
    if prob.sigma_level_db == 0.0 or prob.snr_db is None or not np.isfinite(prob.snr_db).any():
        return out
    for b in (prob.sigma_level_db, -prob.sigma_level_db):
        shifted = level_shifted(prob, b)
        d = _best_run(shifted, [*_starts(shifted, extra_starts), x0], max_iter)[0] - x0
        out += 0.5 * np.outer(d, d)
    return out


def solve_em_map(prob: EmProblem, t0_s: float = 0.0, extra_starts=(), max_iter: int = 500,
                 covariance: bool = True) -> BatchEstimate:
    """EM/MAP X0 with the robust initialisation (module doc) and its covariance: the inverse observed
    information plus the level's consider term (:func:`level_covariance`, module doc; ``covariance=False`` skips
    it: NaN).

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    t0_s : float
        Time of the first frame (s), stored in the estimate.
    extra_starts : iterable of array_like (4,) or None
        More starts (e.g. the bearings-only ML estimate); None entries are skipped.
    max_iter : int
        Iteration limit of each EM run.
    covariance : bool
        Compute the covariance (inverse observed information + :func:`level_covariance`; NaN when not positive
        definite). The level's term solves the problem twice more.

    Returns
    -------
    BatchEstimate
        The start whose EM run ends with the highest L, method "em-map".
    """
    extra_starts = list(extra_starts)  # used again by the level's solves
    x, it, hist = _best_run(prob, _starts(prob, extra_starts), max_iter)
    if not covariance:
        return BatchEstimate(x0=x, covariance=np.full((4, 4), np.nan), t0_s=float(t0_s), iterations=it,
                             converged=it < max_iter, objective=hist[-1], method="em-map")
    info = observed_information(prob, x)
    try:
        cov = np.linalg.inv(info) + level_covariance(prob, x, extra_starts, max_iter)
        if not np.all(np.linalg.eigvalsh(0.5 * (cov + cov.T)) > 0):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        cov = np.full((4, 4), np.nan)
    return BatchEstimate(x0=x, covariance=cov, t0_s=float(t0_s), iterations=it, converged=it < max_iter,
                         objective=hist[-1], method="em-map")
