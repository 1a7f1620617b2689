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

Where the pieces are: the prior (eqs. 16-19, 21's constant) in ``detection/prior.py``; the NumPy
references (explicit track weights, exhaustive optimum, pruned detector) in
``detection/mftd_reference.py``; the compiled pruned detector in ``detection/mftd_kernel.py``; this
module holds the detector's settings (:class:`MftdSettings`) and the detector (:class:`MftdDetector`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.detection.frames import validate_frames
from sonartrack.detection.mftd_reference import pruned_detect
from sonartrack.detection.prior import KalmanPrior, cached_prior, kalman_prior, prior_constant
from sonartrack.detection.pruned import RESTRICT_TOL, MftdResult, flat_to_cells, pruned_args, restriction_margin
from sonartrack.models.range_doppler import RangeDopplerGrid
from sonartrack.models.swerling import db_to_ratio


class MftdSettings(Settings):
    """The MFTD detector's model and pruning (paper P1): defaults are the paper's (sec. V) and ours."""

    snr_db: float = setting(5.0, "design SNR rho of a target cell at the square-law input (eq. 7)", unit="dB",
                           ge=-100, le=100)
    period_s: float = setting(2.0, "frame period T, the CPI of the motion model (eq. 23)", unit="s", gt=0,
                             le=3600)
    sigma_a_mps2: float = setting(1.0, "standard deviation sigma_a of the target's range acceleration (eq. 23)",
                                  unit="m/s^2", gt=0, le=1000)
    n_tracks: int = setting(10, "tracks N kept after each frame's pruning (sec. IV)", unit="1", ge=1,
                            le=100_000)
    prior_density: Literal["smoothed", "centre"] = setting(
        "smoothed", "track prior per cell: 'smoothed' N(v; w, B + R), or 'centre' N(v; w, B) (eq. 19 as printed)",
        unit="1")
    restrict: bool = setting(True, "branch only to cells whose prior weight is not negligible (relative 1e-12)",
                             unit="1")
    final: Literal["branches", "kept"] = setting(
        "branches", "the statistic sums all N x M last-frame branches, or only the N kept (eq. 20)", unit="1")
    compiled: bool = setting(True, "run the numba kernel (false: the NumPy reference)", unit="1")

    @property
    def snr(self) -> float:
        """Design SNR rho as a linear power ratio."""
        return float(db_to_ratio(self.snr_db))


def pruned_detect_fast(frames, grid: RangeDopplerGrid, prior: KalmanPrior, snr: float, n_tracks: int,
                       restrict: bool = True, tol: float = RESTRICT_TOL, n_best: int | None = None,
                       checked: bool = False, final: str = "branches") -> MftdResult:
    """The N-best pruned MFTD detector compiled with numba (paper P1, sec. IV, eqs. 20-22).

    Same arguments and result as :func:`~sonartrack.detection.mftd_reference.pruned_detect` (the
    restricted window is chosen per track, so it leaves out at most what the reference does).

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values on the noise model's scale (noise mean 2).
    grid : RangeDopplerGrid
        The plane.
    prior : KalmanPrior
        Track prior for K frames (detection/prior.py).
    snr : float
        Design SNR rho (linear power ratio).
    n_tracks : int
        N, tracks kept after each frame's pruning.
    restrict : bool, default True
        Branch only to cells whose prior weight is not negligible.
    tol : float, default 1e-12
        Relative weight the restriction may leave out.
    n_best : int, optional
        Best tracks returned (default N).
    checked : bool, default False
        True: the caller validated the inputs.
    final : {"branches", "kept"}, default "branches"
        The statistic sums all N x M last-frame branches, or only the N kept (eq. 20).

    Returns
    -------
    MftdResult
        Statistic S = log sum c_theta LR_theta (natural log) and the best tracks, best first.
    """
    from sonartrack.detection.mftd_kernel import pruned_kernel

    y, N, n_best = pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final)
    K, M = y.shape[0], grid.n_cells
    plane = (grid.n_range, grid.n_doppler, grid.range_cell_m, grid.range_rate_cell_mps, grid.range_min_m,
             grid.range_rate_min_mps)
    arrays = (prior.S_inv, prior.S_cov, prior.F, prior.L, prior.u, np.asarray(prior.w1, dtype=float))
    half, hist, J, n_branches = pruned_kernel()(np.ascontiguousarray(y.reshape(K, M)), plane, arrays, snr / (1.0 + snr),
                                                restriction_margin(M, tol), N, n_best, bool(restrict), final == "kept")
    const = prior_constant(prior, snr)
    return MftdResult(float(half) + const, flat_to_cells(hist, grid.n_doppler), 0.5 * J + const, int(n_branches))


@dataclass(frozen=True, slots=True)
class MftdDetector:
    """The pruned MFTD detector on a plane: ``detect(frames)`` -> :class:`MftdResult`.

    ``settings`` (:class:`MftdSettings`) hold the design SNR, the motion model and N; the prior for
    each K is built on first use (and memoised without own-sensor input).
    """

    grid: RangeDopplerGrid
    settings: MftdSettings = field(default_factory=MftdSettings)

    @property
    def snr(self) -> float:
        """Design SNR rho as a linear power ratio (from the settings)."""
        return self.settings.snr

    def prior(self, n_frames: int, own_accel_mps2=None) -> KalmanPrior:
        """Kalman-predictor track prior for ``n_frames`` frames on this plane (paper P1, eqs. 16-19).

        Parameters
        ----------
        n_frames : int
            K, frames in the stack.
        own_accel_mps2 : float or sequence of float, optional
            Known own-sensor inputs u_1..u_{K-1} (m/s^2); None: no input, and the prior is memoised.

        Returns
        -------
        KalmanPrior
            The prior.
        """
        s = self.settings
        if own_accel_mps2 is None:
            return cached_prior(self.grid, float(s.period_s), float(s.sigma_a_mps2), int(n_frames), s.prior_density)
        return kalman_prior(self.grid, s.period_s, s.sigma_a_mps2, n_frames, own_accel_mps2, s.prior_density)

    def detect(self, frames, own_accel_mps2=None, n_best: int | None = None, checked: bool = False) -> MftdResult:
        """Run the pruned detector on a stack of frames.

        Parameters
        ----------
        frames : array_like, shape (K, Nr, Nd)
            Square-law cell values on the noise model's scale; Nr x Nd must match the plane.
        own_accel_mps2 : float or sequence of float, optional
            Known own-sensor inputs u_1..u_{K-1} (m/s^2).
        n_best : int, optional
            Best tracks returned (default N).
        checked : bool, default False
            True: the caller validated the frames.

        Returns
        -------
        MftdResult
            Statistic and best tracks.

        Raises
        ------
        InputError
            If the frames are malformed or do not match the plane.
        """
        y = np.asarray(frames, dtype=float) if checked else validate_frames(frames)
        prior = self.prior(y.shape[0], own_accel_mps2)
        s = self.settings
        run = pruned_detect_fast if s.compiled else pruned_detect
        return run(y, self.grid, prior, self.snr, s.n_tracks, restrict=s.restrict, n_best=n_best, final=s.final,
                   checked=checked)
