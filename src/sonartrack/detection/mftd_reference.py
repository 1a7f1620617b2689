"""Readable NumPy MFTD (paper P1): explicit track weights, the exhaustive optimum and the pruned detector.

The references the compiled kernel (``mftd_kernel.py``) is tested against; equations in the module
doc of ``detection/mftd.py``:

* :func:`track_log_weights`: log c_theta LR_theta of given tracks, term by term (eqs. 10, 16, 19, 21);
* :func:`exhaustive_detect`: the optimal statistic log sum_theta c_theta LR_theta over all M^K tracks (eq. 9);
* :func:`pruned_detect`: the N-best pruned detector (sec. IV, eqs. 20-22), vectorised over the
  N x M branches of a frame.
"""

from __future__ import annotations

import itertools

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.gaussian import logsumexp
from sonartrack.detection.frames import check_frames_match, validate_frames
from sonartrack.detection.prior import KalmanPrior, prior_constant
from sonartrack.detection.pruned import RESTRICT_TOL, MftdResult, flat_to_cells, pruned_args, restriction_margin
from sonartrack.models.range_doppler import RangeDopplerGrid

#: the exhaustive detector refuses planes with more tracks than this
MAX_EXHAUSTIVE_TRACKS = 4_000_000


def track_log_weights(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, tracks) -> np.ndarray:
    """``log c_theta LR_theta`` (paper P1, eq. 21) of explicit tracks, term by term: the reference.

    Runs the Kalman predictor of eq. 16 along each track and sums eq. 19 and eq. 10:
    ``sum_k [ a y_{k,theta_k} + log_norm_k - d2_k / 2 ] - K log(1 + rho)``, a = rho / (2 (1 + rho)).

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values (noise mean 2).
    grid : RangeDopplerGrid
        The plane.
    prior : KalmanPrior
        Track prior for K frames.
    snr : float
        Design SNR rho (linear).
    tracks : array_like of int, shape (n, K, 2)
        [range index, Doppler index] per frame.

    Returns
    -------
    ndarray, shape (n,)
        Log weights (natural log).
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
    """The optimal statistic ``log sum_theta c_theta LR_theta`` over all M^K tracks (paper P1, eq. 9): tiny planes only.

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values (noise mean 2).
    grid : RangeDopplerGrid
        The plane (M cells).
    prior : KalmanPrior
        Track prior for K frames.
    snr : float
        Design SNR rho (linear).
    n_best : int, default 5
        Best tracks returned.

    Returns
    -------
    MftdResult
        Statistic, best tracks and their log weights; ``n_branches`` = M^K.

    Raises
    ------
    InputError
        If M^K exceeds 4 000 000 tracks, or the frames are malformed.
    """
    y = validate_frames(frames)
    check_frames_match(y, grid, prior.n_frames)
    K, M = y.shape[0], grid.n_cells
    require(float(M) ** K <= MAX_EXHAUSTIVE_TRACKS,
            f"exhaustive detection needs M^K = {M}^{K} tracks (> {MAX_EXHAUSTIVE_TRACKS}): use pruned_detect")
    flat = np.array(list(itertools.product(range(M), repeat=K)), dtype=np.int64).reshape(-1, K)
    tracks = flat_to_cells(flat, grid.n_doppler)
    lw = track_log_weights(y, grid, prior, snr, tracks)
    order = np.argsort(-lw, kind="stable")[:n_best]
    return MftdResult(float(logsumexp(lw)), tracks[order], lw[order], len(lw))


def _window(what: np.ndarray, Sinv: np.ndarray, grid: RangeDopplerGrid, centres: np.ndarray, gy_max: float,
            margin: float):
    """Cells to branch to from each parent (n, W) flat indices and validity, or None for all cells.

    One box for all parents, around each parent's nearest cell, covering the ellipse
    d2 <= gamma = g max_m y_{k,m} + max_p d2_ref,p + margin (module doc of mftd).
    """
    if not np.any(Sinv):
        return None
    dr, dv = grid.range_cell_m, grid.range_rate_cell_mps
    ic = np.clip(np.floor((what[:, 0] - grid.range_min_m) / dr), 0, grid.n_range - 1).astype(np.int64)
    jc = np.clip(np.floor((what[:, 1] - grid.range_rate_min_mps) / dv), 0, grid.n_doppler - 1).astype(np.int64)
    d = centres[ic * grid.n_doppler + jc] - what
    d2_ref = np.einsum("ni,ij,nj->n", d, Sinv, d)
    gamma = gy_max + float(d2_ref.max()) + margin
    S = np.linalg.inv(Sinv)
    hr = int(np.ceil(np.sqrt(gamma * S[0, 0]) / dr)) + 1
    hd = int(np.ceil(np.sqrt(gamma * S[1, 1]) / dv)) + 1
    if 2 * hr + 1 >= grid.n_range and 2 * hd + 1 >= grid.n_doppler:
        return None
    hr, hd = min(hr, grid.n_range), min(hd, grid.n_doppler)
    ii = ic[:, None, None] + np.arange(-hr, hr + 1)[None, :, None]
    jj = jc[:, None, None] + np.arange(-hd, hd + 1)[None, None, :]
    ok = (ii >= 0) & (ii < grid.n_range) & (jj >= 0) & (jj < grid.n_doppler)
    cells = np.clip(ii, 0, grid.n_range - 1) * grid.n_doppler + np.clip(jj, 0, grid.n_doppler - 1)
    n = len(what)
    return cells.reshape(n, -1), ok.reshape(n, -1)


def _branch_scores(J, what, yk, Sinv, grid, centres, g, margin, restrict):
    """Eq. 22 for every branch p -> m of one frame: J_b = J_p + g y_{k,m} - d2_pm, with
    d2_pm = (v_m - w_p)^T S^-1 (v_m - w_p). Returns the scores (P * W,), the cells (P, W) and how
    many branches were scored (cells outside a restricted window score -inf)."""
    win = _window(what, Sinv, grid, centres, g * float(yk.max()), margin) if restrict else None
    if win is None:
        cells, valid = np.broadcast_to(np.arange(grid.n_cells), (len(J), grid.n_cells)), None
    else:
        cells, valid = win
    d = centres[cells] - what[:, None, :]
    d2 = Sinv[0, 0] * d[..., 0] ** 2 + 2.0 * Sinv[0, 1] * d[..., 0] * d[..., 1] + Sinv[1, 1] * d[..., 1] ** 2
    Jb = J[:, None] + g * yk[cells] - d2
    if valid is None:
        return Jb.ravel(), cells, Jb.size
    return np.where(valid, Jb, -np.inf).ravel(), cells, int(valid.sum())


def _best_branches(Jb: np.ndarray, keep_n: int) -> np.ndarray:
    """Indices of the ``keep_n`` largest finite scores, best first (the pruning of eq. 20)."""
    top = np.argpartition(-Jb, keep_n - 1)[:keep_n] if keep_n < Jb.size else np.arange(Jb.size)
    top = top[np.argsort(-Jb[top], kind="stable")]
    return top[np.isfinite(Jb[top])]


def pruned_detect(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, n_tracks: int,
                  restrict: bool = True, tol: float = RESTRICT_TOL, n_best: int | None = None,
                  checked: bool = False, final: str = "branches") -> MftdResult:
    """The N-best pruned detector (paper P1, sec. IV, eqs. 20-22), vectorised over the N x M branches of a frame.

    Parameters
    ----------
    frames, grid, prior, snr
        The square-law cells (noise mean 2), the plane, the track prior for K frames and the design SNR rho
        (linear), as :func:`track_log_weights`.
    n_tracks : int
        N, tracks kept after each frame's pruning.
    restrict : bool, default True
        Branch only to cells whose prior is not negligible (module doc of mftd).
    tol : float, default 1e-12
        Bound on the relative weight the restriction leaves out.
    n_best : int, optional
        Best tracks returned (default N).
    checked : bool, default False
        True skips input validation.
    final : {"branches", "kept"}, default "branches"
        Sum the statistic over all N x M last-frame branches (our default), or over the N kept (eq. 20).

    Returns
    -------
    MftdResult
        Statistic S (natural log) and the best tracks, best first.
    """
    y, N, n_best = pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final)
    K = y.shape[0]
    yf = y.reshape(K, grid.n_cells)
    centres, g, margin = grid.centres(), snr / (1.0 + snr), restriction_margin(grid.n_cells, tol)
    # the kept tracks: score J, prediction w for the frame to come (eq. 16), cell history
    J, what, hist = np.zeros(1), prior.w1[None, :].copy(), np.zeros((1, 0), dtype=np.int64)
    n_branches = 0
    for k in range(K):
        Jb, cells, n = _branch_scores(J, what, yf[k], prior.S_inv[k], grid, centres, g, margin, restrict)
        n_branches += n
        last = k == K - 1
        keep_n = (max(n_best, N) if final == "kept" else n_best) if last else N
        top = _best_branches(Jb, keep_n)
        parent, col = np.divmod(top, cells.shape[1])
        cell = cells[parent, col]
        hist = np.concatenate([hist[parent], cell[:, None]], axis=1)
        if last:
            const = prior_constant(prior, snr)
            summed = Jb if final == "branches" else Jb[top[:N]]
            stat = float(logsumexp(0.5 * summed)) + const
            tracks = flat_to_cells(hist[:n_best], grid.n_doppler)
            return MftdResult(stat, tracks, 0.5 * Jb[top[:n_best]] + const, n_branches)
        what = what[parent] @ prior.F[k].T + centres[cell] @ prior.L[k].T + prior.u[k]  # eq. 16
        J = Jb[top]
    raise AssertionError("unreachable")  # pragma: no cover
