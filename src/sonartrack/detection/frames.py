"""Checks on a K x Nr x Nd stack of square-law range-Doppler cell values (the detector's input).

Every check fails with a one-line :class:`InputError` that names the problem and the fix.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import InputError, require


def validate_frames(frames) -> np.ndarray:
    """Check a stack of square-law cell values and return it as float64 (one-line errors).

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values (powers).

    Returns
    -------
    ndarray of float64, shape (K, Nr, Nd)
        The same values.

    Raises
    ------
    InputError
        If the stack is not numeric, not rank 3, empty, holds NaN/inf or a negative value.
    """
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


def check_frames_match(y: np.ndarray, grid, n_prior_frames: int) -> None:
    """Require the frames to cover ``grid`` cell for cell and to hold as many frames as the prior was built for.

    Parameters
    ----------
    y : ndarray, shape (K, Nr, Nd)
        Frames.
    grid : RangeDopplerGrid
        The detector's plane.
    n_prior_frames : int
        K of the prior.

    Raises
    ------
    InputError
        If the plane or the number of frames differ.
    """
    require(y.shape[1:] == (grid.n_range, grid.n_doppler),
            f"frames are {y.shape[1]} x {y.shape[2]} cells but the grid is {grid.n_range} x {grid.n_doppler}")
    require(n_prior_frames == y.shape[0], f"the prior is for K = {n_prior_frames} frames but {y.shape[0]} were given")
