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
    """Kalman time update: ``x- = F x``, ``P- = F P F^T + Q`` (Bar-Shalom, Li, Kirubarajan 2001, sec. 5.2).

    Parameters
    ----------
    x : ndarray, shape (..., n)
        State estimate at k-1, in the state's own units (e.g. [x, y, vx, vy] in m and m/s).
    P : ndarray, shape (..., n, n)
        Its covariance (state units squared).
    F : ndarray, shape (n, n) or (..., n, n)
        State transition matrix over the step (broadcast over the batch).
    Q : ndarray, shape (n, n) or (..., n, n)
        Process noise covariance over the step (state units squared).

    Returns
    -------
    x_pred : ndarray, shape (..., n)
        Predicted state.
    P_pred : ndarray, shape (..., n, n)
        Predicted covariance, symmetrized.
    """
    x_pred = np.einsum("...ij,...j->...i", F, x)
    P_pred = F @ P @ np.swapaxes(F, -1, -2) + Q
    return x_pred, symmetrize(P_pred)


def kf_innovation(x_pred, P_pred, z, H, R):
    """Innovation ``nu = z - H x-`` and its covariance ``S = H P- H^T + R``.

    Parameters
    ----------
    x_pred, P_pred : ndarray, shapes (..., n) and (..., n, n)
        Predicted state and covariance.
    z : ndarray, shape (..., m)
        Measurement (measurement units, e.g. m for a position).
    H : ndarray, shape (m, n) or (..., m, n)
        Measurement matrix.
    R : ndarray, shape (m, m) or (..., m, m)
        Measurement noise covariance (measurement units squared).

    Returns
    -------
    nu : ndarray, shape (..., m)
        Innovation (no angle wrapping: use filters.ekf.innovation for angular rows).
    S : ndarray, shape (..., m, m)
        Innovation covariance, symmetrized.
    """
    nu = z - np.einsum("...ij,...j->...i", H, x_pred)
    S = H @ P_pred @ np.swapaxes(H, -1, -2) + R
    return nu, symmetrize(S)


def kf_gain(P_pred, H, S_inv):
    """Kalman gain ``K = P- H^T S^-1``.

    Parameters
    ----------
    P_pred : ndarray, shape (..., n, n)
        Predicted covariance.
    H : ndarray, shape (m, n) or (..., m, n)
        Measurement matrix.
    S_inv : ndarray, shape (..., m, m)
        Inverse of the innovation covariance.

    Returns
    -------
    ndarray, shape (..., n, m)
        The gain K.
    """
    return P_pred @ np.swapaxes(H, -1, -2) @ S_inv


def joseph_update(x_pred, P_pred, nu, K, H, R):
    """State and Joseph-form covariance update from a given gain.

    ``x+ = x- + K nu``; ``P+ = (I - K H) P- (I - K H)^T + K R K^T``
    (Bar-Shalom, Li, Kirubarajan 2001, sec. 5.2.3): it stays symmetric positive definite under round-off and
    is exact for any gain K.

    Parameters
    ----------
    x_pred, P_pred : ndarray, shapes (..., n) and (..., n, n)
        Predicted state and covariance.
    nu : ndarray, shape (..., m)
        Innovation.
    K : ndarray, shape (..., n, m)
        Gain.
    H : ndarray, shape (m, n) or (..., m, n)
        Measurement matrix.
    R : ndarray, shape (m, m) or (..., m, m)
        Measurement noise covariance.

    Returns
    -------
    x_upd : ndarray, shape (..., n)
        Updated state.
    P_upd : ndarray, shape (..., n, n)
        Updated covariance, symmetrized.
    """
    n = P_pred.shape[-1]
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    A = np.eye(n) - K @ H
    P_upd = A @ P_pred @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2)
    return x_upd, symmetrize(P_upd)


def kf_update(x_pred, P_pred, z, H, R):
    """Linear Kalman measurement update (Joseph form), equations in the module docstring.

    Parameters
    ----------
    x_pred, P_pred : ndarray, shapes (..., n) and (..., n, n)
        Predicted state and covariance (state units, e.g. m and m/s).
    z : ndarray, shape (..., m)
        Measurement.
    H : ndarray, shape (m, n) or (..., m, n)
        Measurement matrix.
    R : ndarray, shape (m, m) or (..., m, m)
        Measurement noise covariance (measurement units squared).

    Returns
    -------
    x_upd : ndarray, shape (..., n)
        Updated state.
    P_upd : ndarray, shape (..., n, n)
        Updated covariance.
    nu : ndarray, shape (..., m)
        Innovation ``z - H x-``.
    S : ndarray, shape (..., m, m)
        Innovation covariance.

    Raises
    ------
    numpy.linalg.LinAlgError
        If S is singular.
    """
    nu, S = kf_innovation(x_pred, P_pred, z, H, R)
    K = kf_gain(P_pred, H, np.linalg.inv(S))
    x_upd, P_upd = joseph_update(x_pred, P_pred, nu, K, H, R)
    return x_upd, P_upd, nu, S
