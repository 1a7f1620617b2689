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


def covariance_max(P, Q) -> np.ndarray:
    """The smallest covariance at least ``P`` and at least ``Q`` along each axis of their joint eigenbasis.

    With P = L L^T (Cholesky) and L^-1 Q L^-T = V diag(w) V^T, the pair is diagonalised at once by L V (Muirhead,
    Aspects of Multivariate Statistical Theory, 1982, Theorem A9.9): P = (L V) I (L V)^T, Q = (L V) diag(w) (L V)^T.
    The result (L V) diag(max(w, 1)) (L V)^T exceeds each in the Loewner order (R - P and R - Q positive
    semi-definite), is P itself when P >= Q and Q itself when Q >= P, and for commuting (e.g. diagonal) matrices is
    their element-wise maximum. Used to keep an estimate from claiming less uncertainty than another one of the same
    quantity that is known to be at least as informed.

    Parameters
    ----------
    P : array_like, shape (n, n)
        A symmetric positive definite matrix.
    Q : array_like, shape (n, n)
        A symmetric positive semi-definite matrix.

    Returns
    -------
    ndarray, shape (n, n)
        The symmetric matrix R described above.
    """
    P, Q = symmetrize(np.asarray(P, float)), symmetrize(np.asarray(Q, float))
    L = np.linalg.cholesky(P)
    Li = np.linalg.inv(L)
    w, V = np.linalg.eigh(symmetrize(Li @ Q @ Li.T))
    B = L @ V
    return symmetrize((B * np.maximum(w, 1.0)) @ B.T)
