"""Multi-frame target detection (track-before-detect) on a range-Doppler plane.

Im & Kim 1996, "Multiframe target detection for guidance-purposed target detection systems"
(paper P1). K frames of M cells each; a track theta = (theta_1 .. theta_K) picks one cell per frame.

Optimal test (extended Neyman-Pearson, eq. 9), in log space here:

    S(y) = log sum_{theta} c_theta LR_theta  ><  log lambda

    log LR_theta = a sum_k y_{k,theta_k} - K log(1 + rho),   a = rho / (2 (1 + rho))      (eq. 10)

Track prior from a Kalman predictor driven by the cell centres v (eqs. 16-19), track-independent
covariances:

    w_k = Phi { w_{k-1} + B_{k-1} (B_{k-1} + R)^-1 (v_{theta_{k-1}} - w_{k-1}) } + u_{k-1}   (eq. 16)
    B_k = Phi { I - B_{k-1} (B_{k-1} + R)^-1 } B_{k-1} Phi^T + Q                             (eq. 17)
    c_theta = c A^K prod_k N(v_{theta_k}; w_k, B_k)                                          (eq. 19)

"w_1 arbitrary, B_1 large": we take the limit B_1 -> infinity, in which the first update returns
the cell centre with covariance R, so w_2 = Phi v_{theta_1} + u_1 and B_2 = Phi R Phi^T + Q, and the
first frame's prior is flat; we set it to 1/M (a uniform first cell), which fixes the constant c
so that the c_theta sum to about 1 (each later factor A N(v; w_k, B_k) sums to about 1 over the
cells when the plane covers the prediction and the cells are small against B_k). Passing ``b1``
and ``w1`` to :func:`kalman_prior` runs the literal recursion instead.

Log weight of a track (eq. 21, with the 2-D normaliser 1 / (2 pi |B_k|^(1/2)); the paper prints
|B_k| without the square root) and its pruning score (eq. 22):

    I_theta = J_theta / 2 + const,
    J_theta = sum_k [ rho / (1 + rho) y_{k,theta_k} - (v_{theta_k} - w_k)^T B_k^-1 (v_{theta_k} - w_k) ]
    const   = -K log(1 + rho) - log M + sum_{k>=2} [ log A - log 2 pi - log|B_k| / 2 ]

Because const is the same for every track, ranking by J is ranking by c_theta LR_theta.

Suboptimal detector (sec. IV, eq. 20): keep the N best tracks; each frame extend each to every
cell (N x M branches), score by J, keep the best N. At the last frame the statistic sums over all
N x M branches of that frame (they are already scored; keeping only N of them would throw
information away for nothing), so with N >= M^(K-1) nothing is ever pruned and the statistic is
the exhaustive one.

Restricted branching (``restrict=True``): a branch p -> m has J = J_p + g y_m - d2_pm with
g = rho/(1+rho); with gamma = g max_m y_{k,m} + d2_ref + margin, every cell with d2 > gamma scores at
least ``margin`` below the parent's branch to its reference cell (the cell nearest its prediction,
whose distance is d2_ref), i.e. its weight is below exp(-margin/2) times that branch's. With
margin = 2 (log M - log tol) the cells left out weigh less than ``tol`` of what the kept ones do,
frame by frame: the statistic moves by a relative ~tol and the best tracks not at all. Only the
bounding box of the ellipse d2 <= gamma is branched to.

Prior density option ``prior_density``: "centre" evaluates N(v; w_k, B_k) at the cell centre
(eq. 19 as printed). With the paper's numbers the range prediction (sd ~ 11-16 m) is smaller than a
range cell (54 m), so the flat-density assumption behind eq. 19 fails in range and the per-frame
prior mass over the plane swings between ~0.2 and ~2 with the prediction's offset inside a cell.
"smoothed" uses N(v; w_k, B_k + R) instead (the cell average of the density, to second order),
which sums to 1 within a few per cent; both leave J-ranking equivalent to weight ranking.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.core.gaussian import LOG_2PI, inv_and_logdet, logsumexp
from sonartrack.models.range_doppler import RangeDopplerGrid, ar_input_gain, ar_process_noise, ar_transition
from sonartrack.models.swerling import db_to_ratio

PRIOR_DENSITIES = ("centre", "smoothed")
#: what the decision statistic sums at the last frame (see pruned_detect)
FINAL_SUMS = ("branches", "kept")
#: default tolerance of the restricted branching (relative weight of the cells left out)
RESTRICT_TOL = 1e-12
#: the exhaustive detector refuses planes with more tracks than this
MAX_EXHAUSTIVE_TRACKS = 4_000_000


@dataclass(frozen=True, slots=True)
class KalmanPrior:
    """The track-independent part of the Kalman-predictor prior for K frames (eqs. 16, 17, 19).

    For frame k (0-based): ``B[k]`` prediction covariance (NaN for k = 0 in the B_1 -> infinity
    limit), ``S_inv[k]`` / ``log_norm[k]`` the inverse covariance and log normaliser of the density
    used in eq. 19 (``log_norm[0] = -log M`` in the limit), and the predictor step
    ``w_{k+1} = F[k] w_k + L[k] v_{theta_k} + u[k]`` with ``F = Phi (I - G)``, ``L = Phi G``,
    ``G = B (B + R)^-1``; ``w1`` is the prediction for frame 0.
    """

    B: np.ndarray
    S_inv: np.ndarray
    log_norm: np.ndarray
    F: np.ndarray
    L: np.ndarray
    u: np.ndarray
    w1: np.ndarray

    @property
    def n_frames(self) -> int:
        return len(self.log_norm)


@dataclass(frozen=True, slots=True)
class MftdResult:
    """Decision statistic S = log sum c_theta LR_theta and the best tracks, best first.

    ``tracks`` (n, K, 2) holds [range index, Doppler index] per frame; ``log_weights`` (n,) their
    log c_theta LR_theta; ``n_branches`` counts the scored branches (work done).
    """

    statistic: float
    tracks: np.ndarray
    log_weights: np.ndarray
    n_branches: int


def kalman_prior(grid: RangeDopplerGrid, period_s: float, sigma_a_mps2: float, n_frames: int,
                 own_accel_mps2=None, prior_density: str = "centre", b1=None, w1=None) -> KalmanPrior:
    """Covariances and predictor gains of eqs. 16-17 for ``n_frames`` frames on ``grid``.

    ``own_accel_mps2``: the known inputs u_1..u_{K-1} (scalar or K-1 values, m/s^2), entering as
    g u_k with g = [T^2/2, T] (eq. 23). ``b1``/``w1``: a finite B_1 and its w_1 (literal eq. 16-19);
    by default the B_1 -> infinity limit with a uniform first cell.
    """
    from sonartrack.sim.range_doppler import own_accel_array

    require(n_frames >= 1, f"K (frames) must be at least 1, got {n_frames}")
    require(prior_density in PRIOR_DENSITIES, f"prior_density must be one of {PRIOR_DENSITIES}, got '{prior_density}'")
    require(period_s > 0, f"frame period must be positive, got {period_s}")
    require(sigma_a_mps2 >= 0, f"sigma_a must be non-negative, got {sigma_a_mps2}")
    K = int(n_frames)
    Phi, Q, R = ar_transition(period_s), ar_process_noise(period_s, sigma_a_mps2), grid.R
    u = np.zeros((K, 2))
    u[: K - 1] = np.outer(own_accel_array(own_accel_mps2, K), ar_input_gain(period_s))
    B = np.full((K, 2, 2), np.nan)
    S_inv = np.zeros((K, 2, 2))
    log_norm = np.zeros(K)
    F = np.zeros((K, 2, 2))
    L = np.zeros((K, 2, 2))
    log_area = np.log(grid.cell_area)
    smooth = prior_density == "smoothed"
    I2 = np.eye(2)
    if b1 is None:
        log_norm[0] = -np.log(grid.n_cells)
        P = R  # lim_{B_1 -> inf} (I - B_1 (B_1 + R)^-1) B_1 = R
        F[0], L[0] = 0.0, Phi
        w_first = np.zeros(2) if w1 is None else np.asarray(w1, dtype=float)
    else:
        B[0] = np.asarray(b1, dtype=float)
        w_first = np.zeros(2) if w1 is None else np.asarray(w1, dtype=float)
        P = None
    for k in range(K):
        if k > 0 or b1 is not None:
            if k > 0:
                B[k] = Phi @ P @ Phi.T + Q
            Sk = B[k] + R if smooth else B[k]
            inv, logdet = inv_and_logdet(Sk)
            S_inv[k] = inv
            log_norm[k] = log_area - LOG_2PI - 0.5 * logdet
            G = B[k] @ np.linalg.inv(B[k] + R)
            P = (I2 - G) @ B[k]
            P = 0.5 * (P + P.T)
            F[k], L[k] = Phi @ (I2 - G), Phi @ G
    return KalmanPrior(B, S_inv, log_norm, F, L, u, w_first)


# ---------------------------------------------------------------------------------------------
def validate_frames(frames) -> np.ndarray:
    """Check a K x Nr x Nd stack of square-law cell values; return it as float64 (one-line errors)."""
    try:
        y = np.asarray(frames, dtype=float)
    except (TypeError, ValueError):
        raise InputError("frames must be a numeric K x Nr x Nd array of cell values") from None
    require(y.ndim == 3, f"frames must be a K x Nr x Nd array (rank 3); got rank {y.ndim} with shape {y.shape}: "
                         "stack the frames along the first axis")
    require(y.shape[0] >= 1, "frames hold K = 0 frames: K must be at least 1")
    require(y.shape[1] >= 1 and y.shape[2] >= 1, f"frames have an empty plane (shape {y.shape}): need Nr, Nd >= 1")
    bad = ~np.isfinite(y)
    if bad.any():
        first = tuple(int(v) for v in np.argwhere(bad)[0])
        raise InputError(f"frames contain {int(bad.sum())} NaN/inf cell value(s) (first at frame, range, Doppler "
                         f"index {first}): clean or drop those frames")
    if not (y >= 0).all():
        raise InputError(f"frames contain negative cell values (min {y.min():.3g}): square-law cell values are "
                         "powers, >= 0; pass |x|^2, not x")
    return y


def _check(y: np.ndarray, grid: RangeDopplerGrid, prior: KalmanPrior) -> None:
    require(y.shape[1:] == (grid.n_range, grid.n_doppler),
            f"frames are {y.shape[1]} x {y.shape[2]} cells but the grid is {grid.n_range} x {grid.n_doppler}")
    require(prior.n_frames == y.shape[0], f"the prior is for K = {prior.n_frames} frames but {y.shape[0]} were given")


def _constant(prior: KalmanPrior, snr: float) -> float:
    return float(np.sum(prior.log_norm) - prior.n_frames * np.log1p(snr))


def track_log_weights(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, tracks) -> np.ndarray:
    """log c_theta LR_theta (eq. 21) of explicit tracks (n, K, 2) [range idx, Doppler idx]: the reference.

    Runs the Kalman predictor of eq. 16 along each track and sums eq. 19 and eq. 10 term by term.
    """
    y = np.asarray(frames, dtype=float)
    tracks = np.asarray(tracks, dtype=np.int64)
    n, K = tracks.shape[:2]
    centres = grid.centres()
    flat = tracks[..., 0] * grid.n_doppler + tracks[..., 1]
    v = centres[flat]  # (n, K, 2)
    a = snr / (2.0 * (1.0 + snr))
    w = np.broadcast_to(prior.w1, (n, 2)).copy()
    out = np.full(n, -K * np.log1p(snr))
    for k in range(K):
        d = v[:, k] - w
        d2 = np.einsum("ni,ij,nj->n", d, prior.S_inv[k], d)
        out += a * y[k].ravel()[flat[:, k]] + prior.log_norm[k] - 0.5 * d2
        w = w @ prior.F[k].T + v[:, k] @ prior.L[k].T + prior.u[k]
    return out


def exhaustive_detect(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, n_best: int = 5) -> MftdResult:
    """The optimal statistic (eq. 9) over all M^K tracks: feasible only on tiny planes."""
    y = validate_frames(frames)
    _check(y, grid, prior)
    K, M = y.shape[0], grid.n_cells
    require(float(M) ** K <= MAX_EXHAUSTIVE_TRACKS,
            f"exhaustive detection needs M^K = {M}^{K} tracks (> {MAX_EXHAUSTIVE_TRACKS}): use pruned_detect")
    flat = np.array(list(itertools.product(range(M), repeat=K)), dtype=np.int64).reshape(-1, K)
    tracks = np.stack([flat // grid.n_doppler, flat % grid.n_doppler], axis=-1)
    lw = track_log_weights(y, grid, prior, snr, tracks)
    order = np.argsort(-lw, kind="stable")[:n_best]
    return MftdResult(float(logsumexp(lw)), tracks[order], lw[order], len(lw))


def _window(what: np.ndarray, prior: KalmanPrior, k: int, grid: RangeDopplerGrid, centres: np.ndarray,
            ymax: float, g: float, margin: float):
    """Cells to branch to from each parent (n, W) flat indices and validity, or None for all cells.

    The box around each parent's nearest cell covers the ellipse d2 <= gamma (module doc).
    """
    Sinv = prior.S_inv[k]
    if not np.any(Sinv):
        return None
    dr, dv = grid.range_cell_m, grid.range_rate_cell_mps
    ic = np.clip(np.floor((what[:, 0] - grid.range_min_m) / dr), 0, grid.n_range - 1).astype(np.int64)
    jc = np.clip(np.floor((what[:, 1] - grid.range_rate_min_mps) / dv), 0, grid.n_doppler - 1).astype(np.int64)
    d = centres[ic * grid.n_doppler + jc] - what
    d2_ref = np.einsum("ni,ij,nj->n", d, Sinv, d)
    gamma = g * ymax + float(d2_ref.max()) + margin
    S = np.linalg.inv(Sinv)
    hr = int(np.ceil(np.sqrt(gamma * S[0, 0]) / dr)) + 1
    hd = int(np.ceil(np.sqrt(gamma * S[1, 1]) / dv)) + 1
    if 2 * hr + 1 >= grid.n_range and 2 * hd + 1 >= grid.n_doppler:
        return None
    hr, hd = min(hr, grid.n_range), min(hd, grid.n_doppler)
    oi = np.arange(-hr, hr + 1)
    oj = np.arange(-hd, hd + 1)
    ii = ic[:, None, None] + oi[None, :, None]
    jj = jc[:, None, None] + oj[None, None, :]
    ok = (ii >= 0) & (ii < grid.n_range) & (jj >= 0) & (jj < grid.n_doppler)
    cells = np.clip(ii, 0, grid.n_range - 1) * grid.n_doppler + np.clip(jj, 0, grid.n_doppler - 1)
    n = len(what)
    return cells.reshape(n, -1), ok.reshape(n, -1)


def _pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final):
    """Validated frames, N and the number of best tracks to return (shared by both pruned detectors)."""
    y = np.asarray(frames, dtype=float) if checked else validate_frames(frames)
    if not checked:
        _check(y, grid, prior)
        require(int(n_tracks) >= 1, f"N (tracks kept) must be at least 1, got {n_tracks}")
        require(0.0 < tol < 1.0, f"restriction tolerance must be in (0, 1), got {tol}")
        require(final in FINAL_SUMS, f"final must be one of {FINAL_SUMS}, got '{final}'")
    N = int(n_tracks)
    return y, N, N if n_best is None else int(n_best)


def pruned_detect(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, n_tracks: int,
                  restrict: bool = True, tol: float = RESTRICT_TOL, n_best: int | None = None,
                  checked: bool = False, final: str = "branches") -> MftdResult:
    """The N-best pruned detector (sec. IV, eqs. 20-22), vectorised over the N x M branches of a frame.

    ``restrict`` branches only to cells whose prior is not negligible (module doc; ``tol`` bounds
    the relative weight left out). ``n_best`` tracks are returned (default N). ``checked=True``
    skips input validation (the caller has done it). ``final``: "branches" sums the statistic over
    all N x M branches of the last frame (our default, module doc); "kept" sums over the N tracks
    kept after the last pruning, eq. 20 to the letter.
    """
    y, N, n_best = _pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final)
    K, M = y.shape[0], grid.n_cells
    yf = y.reshape(K, M)
    centres = grid.centres()
    g = snr / (1.0 + snr)
    margin = 2.0 * (np.log(M) - np.log(tol))
    # parents: score J, prediction w for the frame to come, cell history
    J = np.zeros(1)
    what = prior.w1[None, :].copy()
    hist = np.zeros((1, 0), dtype=np.int64)
    n_branches = 0
    for k in range(K):
        win = _window(what, prior, k, grid, centres, float(yf[k].max()), g, margin) if restrict else None
        if win is None:
            cells = np.broadcast_to(np.arange(M), (len(J), M))
            valid = None
        else:
            cells, valid = win
        d = centres[cells] - what[:, None, :]
        Sinv = prior.S_inv[k]
        d2 = Sinv[0, 0] * d[..., 0] ** 2 + 2.0 * Sinv[0, 1] * d[..., 0] * d[..., 1] + Sinv[1, 1] * d[..., 1] ** 2
        Jb = J[:, None] + g * yf[k][cells] - d2
        if valid is not None:
            Jb = np.where(valid, Jb, -np.inf)
            n_branches += int(valid.sum())
        else:
            n_branches += Jb.size
        Jb = Jb.ravel()
        last = k == K - 1
        keep_n = (max(n_best, N) if final == "kept" else n_best) if last else N
        if keep_n < Jb.size:
            top = np.argpartition(-Jb, keep_n - 1)[:keep_n]
        else:
            top = np.arange(Jb.size)
        top = top[np.argsort(-Jb[top], kind="stable")]
        top = top[np.isfinite(Jb[top])]
        parent, cell = np.divmod(top, cells.shape[1])
        cell = cells[parent, cell]
        if last:
            const = _constant(prior, snr)
            summed = Jb if final == "branches" else Jb[top[:N]]
            stat = float(logsumexp(0.5 * summed)) + const
            top, parent, cell = top[:n_best], parent[:n_best], cell[:n_best]
            hist = np.concatenate([hist[parent], cell[:, None]], axis=1)
            tracks = np.stack([hist // grid.n_doppler, hist % grid.n_doppler], axis=-1)
            return MftdResult(stat, tracks, 0.5 * Jb[top] + const, n_branches)
        v = centres[cell]
        what = what[parent] @ prior.F[k].T + v @ prior.L[k].T + prior.u[k]
        J = Jb[top]
        hist = np.concatenate([hist[parent], cell[:, None]], axis=1)
    raise AssertionError("unreachable")  # pragma: no cover


def pruned_detect_fast(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, n_tracks: int,
                       restrict: bool = True, tol: float = RESTRICT_TOL, n_best: int | None = None,
                       checked: bool = False, final: str = "branches") -> MftdResult:
    """:func:`pruned_detect` compiled with numba (``detection/mftd_kernel.py``): same arguments, same
    result (the restricted window is chosen per track, so it leaves out at most what the reference does)."""
    from sonartrack.detection.mftd_kernel import pruned_kernel

    y, N, n_best = _pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final)
    K, M = y.shape[0], grid.n_cells
    S_cov = np.zeros_like(prior.S_inv)
    for k in range(K):
        if np.any(prior.S_inv[k]):
            S_cov[k] = np.linalg.inv(prior.S_inv[k])
    half, hist, J, n_branches = pruned_kernel()(
        np.ascontiguousarray(y.reshape(K, M)), grid.n_range, grid.n_doppler, grid.range_cell_m,
        grid.range_rate_cell_mps, grid.range_min_m, grid.range_rate_min_mps, prior.S_inv, S_cov, prior.F, prior.L,
        prior.u, np.asarray(prior.w1, dtype=float), snr / (1.0 + snr), N, n_best, bool(restrict),
        2.0 * (np.log(M) - np.log(tol)), final == "kept")
    const = _constant(prior, snr)
    tracks = np.stack([hist // grid.n_doppler, hist % grid.n_doppler], axis=-1)
    return MftdResult(float(half) + const, tracks, 0.5 * J + const, int(n_branches))


@functools.lru_cache(maxsize=64)
def cached_prior(grid: RangeDopplerGrid, period_s: float, sigma_a_mps2: float, n_frames: int,
                 prior_density: str = "centre") -> KalmanPrior:
    """:func:`kalman_prior` without own-sensor input, memoised (Monte Carlo trials reuse it)."""
    return kalman_prior(grid, period_s, sigma_a_mps2, n_frames, None, prior_density)


@dataclass(frozen=True, slots=True)
class MftdDetector:
    """The pruned MFTD detector with its model: ``detect(frames)`` -> :class:`MftdResult`.

    ``snr_db``: design SNR rho (dB) at the square-law input; ``n_tracks``: N. Cell sizes and the
    plane come from ``grid``; the prior for each K is built on first use.
    """

    grid: RangeDopplerGrid
    snr_db: float = 5.0
    period_s: float = 2.0
    sigma_a_mps2: float = 1.0
    n_tracks: int = 10
    prior_density: str = "centre"
    restrict: bool = True
    final: str = "branches"
    compiled: bool = True

    @property
    def snr(self) -> float:
        return float(db_to_ratio(self.snr_db))

    def prior(self, n_frames: int, own_accel_mps2=None) -> KalmanPrior:
        if own_accel_mps2 is None:
            return cached_prior(self.grid, float(self.period_s), float(self.sigma_a_mps2), int(n_frames),
                                self.prior_density)
        return kalman_prior(self.grid, self.period_s, self.sigma_a_mps2, n_frames, own_accel_mps2, self.prior_density)

    def detect(self, frames, own_accel_mps2=None, n_best: int | None = None, checked: bool = False) -> MftdResult:
        y = np.asarray(frames, dtype=float) if checked else validate_frames(frames)
        prior = self.prior(y.shape[0], own_accel_mps2)
        run = pruned_detect_fast if self.compiled else pruned_detect
        return run(y, self.grid, prior, self.snr, self.n_tracks, restrict=self.restrict, n_best=n_best,
                   final=self.final, checked=checked)
