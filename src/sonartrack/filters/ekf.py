"""Extended Kalman filter steps on arrays (batched over leading axes, e.g. IMM modes).

Shapes: x (..., n), P (..., n, n), z (..., m), hx = h(x-) (..., m), H = dh/dx at x- (..., m, n),
R (..., m, m). Functions return new arrays and never mutate their inputs.

Equations (Bar-Shalom, Li, Kirubarajan 2001, sec. 10.3.2; the same steps as FilterPy's
``ExtendedKalmanFilter``, which tests/filters/test_ekf.py checks against)::

    predict:  x- = F x + b,            P- = F P F^T + Q          (b: known input term, e.g. -u)
    update:   nu = z - h(x-)   (angular components wrapped to (-pi, pi])
              S = H P- H^T + R,        K = P- H^T S^-1
              x+ = x- + K nu,          P+ = (I - K H) P- (I - K H)^T + K R K^T   (Joseph form)

The mode likelihood used by an IMM is N(nu; 0, S).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.linalg import symmetrize


def ekf_predict(x, P, F, Q, b=None):
    """``x- = F x + b``, ``P- = F P F^T + Q`` (F, Q, b broadcast over the batch)."""
    x_pred = np.einsum("...ij,...j->...i", F, x)
    if b is not None:
        x_pred = x_pred + b
    P_pred = F @ P @ np.swapaxes(F, -1, -2) + Q
    return x_pred, symmetrize(P_pred)


def innovation(z, hx, angle_rows=(0,)):
    """``nu = z - h(x-)`` with the components in ``angle_rows`` wrapped to (-pi, pi]."""
    nu = np.array(np.asarray(z, float) - np.asarray(hx, float), copy=True)
    for i in angle_rows:
        if i < nu.shape[-1]:
            nu[..., i] = wrap_angle(nu[..., i])
    return nu


def ekf_gain(P_pred, H, R):
    """Innovation covariance ``S = H P- H^T + R``, its inverse, and the gain ``K = P- H^T S^-1``."""
    PHt = P_pred @ np.swapaxes(H, -1, -2)
    S = symmetrize(H @ PHt + R)
    S_inv = np.linalg.inv(S)
    return S, S_inv, PHt @ S_inv


def joseph_covariance(P_pred, K, G, R):
    """``(I - K G) P- (I - K G)^T + K R K^T``: G = H for the EKF, the modified matrix for the MGEKF."""
    n = P_pred.shape[-1]
    A = np.eye(n) - K @ G
    return symmetrize(A @ P_pred @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2))


def ekf_update(x_pred, P_pred, z, hx, H, R, angle_rows=(0,)):
    """EKF measurement update. Returns ``x+, P+, nu, S, S_inv``.

    Raises ``numpy.linalg.LinAlgError`` if S is singular.
    """
    nu = innovation(z, hx, angle_rows)
    S, S_inv, K = ekf_gain(P_pred, H, R)
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    return x_upd, joseph_covariance(P_pred, K, H, R), nu, S, S_inv


def gaussian_loglik(nu, S, S_inv):
    """log N(nu; 0, S) for innovations nu (..., m) (the IMM mode likelihood)."""
    m = nu.shape[-1]
    _, logdet = np.linalg.slogdet(S)
    d2 = np.einsum("...i,...ij,...j->...", nu, S_inv, nu)
    return -0.5 * (m * np.log(2.0 * np.pi) + logdet + d2)
