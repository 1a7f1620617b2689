"""What the two N-best pruned MFTD detectors share (paper P1, sec. IV): the result record, the
argument checks, the restriction margin and the cell bookkeeping.

The NumPy reference (``mftd_reference.pruned_detect``) and the compiled detector
(``mftd.pruned_detect_fast``) take the same arguments and return the same :class:`MftdResult`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.detection.frames import check_frames_match, validate_frames

#: what the decision statistic sums at the last frame: all N x M scored branches, or the N kept (eq. 20)
FINAL_SUMS = ("branches", "kept")
#: default tolerance of the restricted branching (relative weight of the cells left out)
RESTRICT_TOL = 1e-12


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


def pruned_args(frames, grid, prior, n_tracks, tol, n_best, checked, final) -> tuple[np.ndarray, int, int]:
    """Validated frames, N and the number of best tracks to return (``checked=True``: trust the caller).

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values.
    grid : RangeDopplerGrid
        The plane.
    prior : KalmanPrior
        Track prior (its K must match).
    n_tracks : int
        N, tracks kept (>= 1).
    tol : float
        Restriction tolerance, in (0, 1).
    n_best : int or None
        Best tracks to return; None for N.
    checked : bool
        Skip the checks.
    final : str
        "branches" or "kept".

    Returns
    -------
    y : ndarray, shape (K, Nr, Nd)
        Frames as float.
    N : int
        Tracks kept.
    n_best : int
        Tracks returned.

    Raises
    ------
    InputError
        If a check fails.
    """
    y = np.asarray(frames, dtype=float) if checked else validate_frames(frames)
    if not checked:
        check_frames_match(y, grid, prior.n_frames)
        require(int(n_tracks) >= 1, f"N (tracks kept) must be at least 1, got {n_tracks}")
        require(0.0 < tol < 1.0, f"restriction tolerance must be in (0, 1), got {tol}")
        require(final in FINAL_SUMS, f"final must be one of {FINAL_SUMS}, got '{final}'")
    N = int(n_tracks)
    return y, N, N if n_best is None else int(n_best)


def restriction_margin(n_cells: int, tol: float) -> float:
    """``margin = 2 (log M - log tol)``: cells scoring this far below a parent's reference branch are negligible.

    They weigh less than tol / M each, so all M of them less than ``tol`` of the kept weight (module doc
    of mftd).

    Parameters
    ----------
    n_cells : int
        M, cells in the plane.
    tol : float
        Relative weight allowed to be left out.

    Returns
    -------
    float
        The margin on the score J (twice a natural-log weight).
    """
    return 2.0 * (np.log(n_cells) - np.log(tol))


def flat_to_cells(flat: np.ndarray, n_doppler: int) -> np.ndarray:
    """Row-major flat cell numbers ``m = i n_doppler + j`` to [range index i, Doppler index j].

    Parameters
    ----------
    flat : ndarray of int, shape (...)
        Flat cell numbers.
    n_doppler : int
        Doppler cells per range row.

    Returns
    -------
    ndarray of int, shape (..., 2)
        [i, j].
    """
    return np.stack([flat // n_doppler, flat % n_doppler], axis=-1)
