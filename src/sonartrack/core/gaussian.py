"""Gaussian densities and Mahalanobis distances, vectorised over leading (batch) axes.

All functions broadcast: an innovation array of shape (..., m) goes with a covariance of shape
(..., m, m). For the 2-D measurements that dominate tracking the 2 x 2 inverse and determinant are
written out in closed form, which is several times faster than ``np.linalg`` on small batches.
"""

import numpy as np

LOG_2PI = float(np.log(2.0 * np.pi))


def inv_and_logdet(S):
    """Inverse and log-determinant of symmetric positive-definite matrices.

    Closed form for m = 2 (``inv = [[d, -b], [-b, a]] / det``) and m = 1; ``np.linalg`` otherwise.

    Parameters
    ----------
    S : array_like, shape (..., m, m)
        Covariance matrices (e.g. innovation covariances).

    Returns
    -------
    S_inv : ndarray, shape (..., m, m)
        Inverses.
    logdet : ndarray, shape (...)
        Natural log of the determinants.

    Raises
    ------
    numpy.linalg.LinAlgError
        If any determinant (or variance) is not positive (singular or indefinite S).
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
    """Squared Mahalanobis distance ``d2 = nu^T S^-1 nu``.

    Parameters
    ----------
    nu : ndarray, shape (..., m)
        Innovations.
    S_inv : ndarray, shape (..., m, m)
        Inverse innovation covariances.

    Returns
    -------
    ndarray, shape (...)
        Squared distances (dimensionless).
    """
    return np.einsum("...i,...ij,...j->...", nu, S_inv, nu)


def gaussian_logpdf(nu, S):
    """Log-density ``log N(nu; 0, S) = -0.5 (m log 2 pi + log|S| + nu^T S^-1 nu)``.

    Parameters
    ----------
    nu : ndarray, shape (..., m)
        Innovations (measurement units).
    S : ndarray, shape (..., m, m)
        Their covariances (measurement units squared).

    Returns
    -------
    ndarray, shape (...)
        Log-densities (natural log, per unit of measurement volume).
    """
    S_inv, logdet = inv_and_logdet(S)
    m = np.shape(nu)[-1]
    return -0.5 * (m * LOG_2PI + logdet + mahalanobis_sq(nu, S_inv))


def gaussian_logpdf_from_inv(d2, logdet, m):
    """Log-density ``-0.5 (m log 2 pi + log|S| + d2)`` from a precomputed distance and log-determinant.

    Parameters
    ----------
    d2 : float or ndarray
        Squared Mahalanobis distance ``nu^T S^-1 nu``.
    logdet : float or ndarray
        ``log|S|``, broadcast with ``d2``.
    m : int
        Measurement dimension.

    Returns
    -------
    float or ndarray
        ``log N(nu; 0, S)``.
    """
    return -0.5 * (m * LOG_2PI + logdet + d2)


def logsumexp(a, axis=-1):
    """Numerically safe ``log(sum(exp(a)))`` along ``axis`` (NumPy only).

    Parameters
    ----------
    a : array_like
        Log-values.
    axis : int, default -1
        Axis summed over.

    Returns
    -------
    ndarray
        ``a`` reduced over ``axis``; a row of -inf gives -inf.
    """
    a = np.asarray(a, dtype=float)
    amax = np.max(a, axis=axis, keepdims=True)
    amax = np.where(np.isfinite(amax), amax, 0.0)
    with np.errstate(divide="ignore"):  # an all -inf row is log(0) = -inf, by design
        out = np.log(np.sum(np.exp(a - amax), axis=axis, keepdims=True)) + amax
    return np.squeeze(out, axis=axis)


def chi2_quantile(q, dof):
    """The chi-square(dof) quantile q: 2 P^-1(dof / 2, q), P the regularised lower incomplete gamma function.

    The formula ``scipy.stats.chi2.ppf`` evaluates (equal to the bit; tests), without importing scipy.stats, which
    costs about 0.3 s of every command line that reaches it.

    Parameters
    ----------
    q : float or array_like
        Probability, 0 < q < 1.
    dof : float or array_like
        Degrees of freedom (> 0); broadcasts with ``q``.

    Returns
    -------
    float or ndarray
        The quantile(s).
    """
    from scipy.special import gammaincinv

    out = 2.0 * gammaincinv(np.asarray(dof, float) / 2.0, q)
    return float(out) if np.ndim(out) == 0 else out
