"""Linear Kalman filter steps on arrays (batched over any leading axes).

Shapes: state x (..., n), covariance P (..., n, n), measurement z (..., m), H (m, n) or (..., m, n),
R (..., m, m). Every function returns new arrays and never mutates its inputs.

Equations (Bar-Shalom, Li, Kirubarajan, *Estimation with Applications to Tracking and Navigation*,
2001, sec. 5.2):

    predict:  x- = F x,             P- = F P F^T + Q
    update:   nu = z - H x-,        S = H P- H^T + R,      K = P- H^T S^-1
              x+ = x- + K nu,       P+ = (I - K H) P- (I - K H)^T + K R K^T   (Joseph form)

The Joseph form keeps P+ symmetric positive definite under round-off (sec. 5.2.3).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.linalg import symmetrize


def kf_predict(x, P, F, Q):
    """Time update: ``x- = F x``, ``P- = F P F^T + Q`` (F, Q broadcast over the batch)."""
    x_pred = np.einsum("...ij,...j->...i", F, x)
    P_pred = F @ P @ np.swapaxes(F, -1, -2) + Q
    return x_pred, symmetrize(P_pred)


def kf_innovation(x_pred, P_pred, z, H, R):
    """Innovation ``nu = z - H x-`` and its covariance ``S = H P- H^T + R``."""
    nu = z - np.einsum("...ij,...j->...i", H, x_pred)
    S = H @ P_pred @ np.swapaxes(H, -1, -2) + R
    return nu, symmetrize(S)


def kf_gain(P_pred, H, S_inv):
    """Kalman gain ``K = P- H^T S^-1``."""
    return P_pred @ np.swapaxes(H, -1, -2) @ S_inv


def joseph_update(x_pred, P_pred, nu, K, H, R):
    """``x+ = x- + K nu``; ``P+ = (I - K H) P- (I - K H)^T + K R K^T`` (Joseph form)."""
    n = P_pred.shape[-1]
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    A = np.eye(n) - K @ H
    P_upd = A @ P_pred @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2)
    return x_upd, symmetrize(P_upd)


def kf_update(x_pred, P_pred, z, H, R):
    """Measurement update (Joseph form). Returns ``x+, P+, nu, S``.

    Raises ``numpy.linalg.LinAlgError`` if S is singular.
    """
    nu, S = kf_innovation(x_pred, P_pred, z, H, R)
    K = kf_gain(P_pred, H, np.linalg.inv(S))
    x_upd, P_upd = joseph_update(x_pred, P_pred, nu, K, H, R)
    return x_upd, P_upd, nu, S
