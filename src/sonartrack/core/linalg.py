"""Small linear-algebra helpers for batches of covariance matrices."""

import numpy as np


def symmetrize(P):
    """Return ``(P + P^T) / 2`` over the last two axes: removes round-off asymmetry.

    Parameters
    ----------
    P : ndarray, shape (..., n, n)
        Matrices (e.g. covariances).

    Returns
    -------
    ndarray, shape (..., n, n)
        Their symmetric parts.
    """
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def is_spd(P, tol: float = 0.0) -> bool:
    """True when every matrix in ``P`` is symmetric and positive definite.

    Symmetry is checked to a relative 1e-9 (absolute 1e-12 of the largest entry), definiteness by a
    Cholesky factorisation of ``P - tol I``.

    Parameters
    ----------
    P : array_like, shape (..., n, n)
        Matrices.
    tol : float, default 0.0
        Smallest eigenvalue margin demanded (same units as P).

    Returns
    -------
    bool
        True if all are symmetric and ``P - tol I`` is positive definite.
    """
    P = np.asarray(P, dtype=float)
    if not np.allclose(P, np.swapaxes(P, -1, -2), rtol=1e-9, atol=1e-12 * max(1.0, float(np.abs(P).max(initial=0.0)))):
        return False
    try:
        np.linalg.cholesky(P - tol * np.eye(P.shape[-1]))
    except np.linalg.LinAlgError:
        return False
    return True


def block_diag2(a: float, b: float, n: int = 2):
    """The diagonal matrix ``diag(a I_n, b I_n)``: handy for [position, velocity] covariances.

    Parameters
    ----------
    a : float
        Value of the first n diagonal entries (e.g. a position variance, m^2).
    b : float
        Value of the last n diagonal entries (e.g. a velocity variance, m^2/s^2).
    n : int, default 2
        Size of each block.

    Returns
    -------
    ndarray, shape (2n, 2n)
        The diagonal matrix.
    """
    return np.diag(np.r_[np.full(n, a), np.full(n, b)])
