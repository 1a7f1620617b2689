"""Small linear-algebra helpers for batches of covariance matrices."""

import numpy as np


def symmetrize(P):
    """Return (P + P^T) / 2 over the last two axes: removes round-off asymmetry."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def is_spd(P, tol: float = 0.0) -> bool:
    """True when every matrix in P (..., n, n) is symmetric and positive definite."""
    P = np.asarray(P, dtype=float)
    if not np.allclose(P, np.swapaxes(P, -1, -2), rtol=1e-9, atol=1e-12 * max(1.0, float(np.abs(P).max(initial=0.0)))):
        return False
    try:
        np.linalg.cholesky(P - tol * np.eye(P.shape[-1]))
    except np.linalg.LinAlgError:
        return False
    return True


def block_diag2(a: float, b: float, n: int = 2):
    """diag(a I_n, b I_n): handy for [position, velocity] covariances."""
    return np.diag(np.r_[np.full(n, a), np.full(n, b)])
