"""Gaussian densities and Mahalanobis distances, vectorised over leading (batch) axes.

All functions broadcast: an innovation array of shape (..., m) goes with a covariance of shape
(..., m, m). For the 2-D measurements that dominate tracking the 2 x 2 inverse and determinant are
written out in closed form, which is several times faster than ``np.linalg`` on small batches.
"""

import numpy as np

LOG_2PI = float(np.log(2.0 * np.pi))


def inv_and_logdet(S):
    """Inverse and log-determinant of symmetric positive-definite matrices S (..., m, m).

    Closed form for m = 2 (``inv = [[d, -b], [-b, a]] / det``); Cholesky-free ``np.linalg`` otherwise.
    Raises ``np.linalg.LinAlgError`` if any determinant is not positive (singular or indefinite S).
    """
    S = np.asarray(S, dtype=float)
    m = S.shape[-1]
    if m == 2:
        a, b, c, d = S[..., 0, 0], S[..., 0, 1], S[..., 1, 0], S[..., 1, 1]
        det = a * d - b * c
        if np.any(~(det > 0.0)):
            raise np.linalg.LinAlgError("covariance is singular or not positive definite")
        inv = np.empty_like(S)
        inv[..., 0, 0] = d / det
        inv[..., 1, 1] = a / det
        inv[..., 0, 1] = -b / det
        inv[..., 1, 0] = -c / det
        return inv, np.log(det)
    if m == 1:
        v = S[..., 0, 0]
        if np.any(~(v > 0.0)):
            raise np.linalg.LinAlgError("variance is not positive")
        return 1.0 / S, np.log(v)
    sign, logdet = np.linalg.slogdet(S)
    if np.any(sign <= 0):
        raise np.linalg.LinAlgError("covariance is singular or not positive definite")
    return np.linalg.inv(S), logdet


def mahalanobis_sq(nu, S_inv):
    """Squared Mahalanobis distance ``nu^T S^-1 nu`` for innovations nu (..., m), S_inv (..., m, m)."""
    return np.einsum("...i,...ij,...j->...", nu, S_inv, nu)


def gaussian_logpdf(nu, S):
    """log N(nu; 0, S) = -0.5 (m log 2 pi + log|S| + nu^T S^-1 nu), broadcast over leading axes."""
    S_inv, logdet = inv_and_logdet(S)
    m = np.shape(nu)[-1]
    return -0.5 * (m * LOG_2PI + logdet + mahalanobis_sq(nu, S_inv))


def gaussian_logpdf_from_inv(d2, logdet, m):
    """log N given a precomputed squared Mahalanobis distance ``d2`` and ``log|S|``."""
    return -0.5 * (m * LOG_2PI + logdet + d2)


def logsumexp(a, axis=-1):
    """Numerically safe ``log(sum(exp(a)))`` along ``axis`` (NumPy only; -inf rows give -inf)."""
    a = np.asarray(a, dtype=float)
    amax = np.max(a, axis=axis, keepdims=True)
    amax = np.where(np.isfinite(amax), amax, 0.0)
    with np.errstate(divide="ignore"):  # an all -inf row is log(0) = -inf, by design
        out = np.log(np.sum(np.exp(a - amax), axis=axis, keepdims=True)) + amax
    return np.squeeze(out, axis=axis)
