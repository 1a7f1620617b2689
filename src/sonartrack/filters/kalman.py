"""Linear Kalman filter steps on arrays (batched over any leading axes).

Shapes: state x (..., n), covariance P (..., n, n), measurement z (..., m), H (m, n) or (..., m, n),
R (..., m, m). Every function returns new arrays and never mutates its inputs.

Equations (Bar-Shalom, Li, Kirubarajan, *Estimation with Applications to Tracking and Navigation*,
2001, sec. 5.2):

    predict:  x- = F x,             P- = F P F^T + Q
    update:   nu = z - H x-,        S = H P- H^T + R,      K = P- H^T S^-1
              x+ = x- + K nu,       P+ = (I - K H) P- (I - K H)^T + K R K^T   (Joseph form)

The Joseph form keeps P+ symmetric positive definite under round-off (sec. 5.2.3).

Arguments the functions here (and filters/ekf.py) share; their docstrings name only what differs:

- ``x``, ``P``: the state estimate at k-1, in the state's own units (e.g. [x, y, vx, vy] in m and m/s, x east,
  y north), and its covariance (state units squared);
- ``F``, ``Q``: the state transition matrix over the step and the process noise covariance over it (state units
  squared), shape (n, n) or batched;
- ``x_pred``, ``P_pred``: the predicted state and covariance x-, P-;
- ``z``: the measurement (measurement units, e.g. m for a position, rad for a bearing);
- ``H``: the measurement matrix (for an EKF the Jacobian dh/dx at x-), shape (m, n) or batched;
- ``R``: the measurement noise covariance (measurement units squared), shape (m, m) or batched;
- ``nu``, ``S``, ``S_inv``, ``K``: innovation, its covariance and inverse, gain.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.linalg import symmetrize


def kf_predict(x, P, F, Q):
    """Kalman time update: ``x- = F x``, ``P- = F P F^T + Q`` (Bar-Shalom, Li, Kirubarajan 2001, sec. 5.2).

    Parameters
    ----------
    x, P, F, Q : ndarray
        State (..., n) and covariance (..., n, n) at k-1, transition and process noise over the step (module
        docstring; F and Q broadcast over the batch).

    Returns
    -------
    x_pred, P_pred : ndarray, shapes (..., n) and (..., n, n)
        Predicted state and covariance (symmetrized).
    """
    x_pred = np.einsum("...ij,...j->...i", F, x)
    P_pred = F @ P @ np.swapaxes(F, -1, -2) + Q
    return x_pred, symmetrize(P_pred)


def kf_innovation(x_pred, P_pred, z, H, R):
    """Innovation ``nu = z - H x-`` and its covariance ``S = H P- H^T + R``.

    Parameters
    ----------
    x_pred, P_pred, z, H, R : ndarray
        Prediction, measurement and its model (module docstring).

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
    """Kalman gain ``K = P- H^T S^-1`` (shape (..., n, m)) from the predicted covariance, the measurement matrix and
    the inverse innovation covariance (module docstring)."""
    return P_pred @ np.swapaxes(H, -1, -2) @ S_inv


def joseph_covariance(P_pred, K, G, R):
    """Joseph-form covariance update ``(I - K G) P- (I - K G)^T + K R K^T``, symmetrized (shape (..., n, n)).

    G = H gives the Kalman filter and the EKF (Bar-Shalom, Li, Kirubarajan 2001, sec. 5.2.3): it stays symmetric
    positive definite under round-off and is exact for any gain K; the MGEKF passes its modified matrix (Song &
    Speyer 1985; filters/mgekf.py). ``P_pred``, ``K``, ``R`` as in the module docstring; ``G`` (..., m, n).
    """
    n = P_pred.shape[-1]
    A = np.eye(n) - K @ G
    return symmetrize(A @ P_pred @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2))


def joseph_update(x_pred, P_pred, nu, K, H, R):
    """State and Joseph-form covariance update from a given gain: ``x+ = x- + K nu`` and
    :func:`joseph_covariance` with G = H.

    Parameters
    ----------
    x_pred, P_pred, nu, K, H, R : ndarray
        Prediction, innovation, gain, measurement model (module docstring).

    Returns
    -------
    x_upd, P_upd : ndarray, shapes (..., n) and (..., n, n)
        Updated state and covariance (symmetrized).
    """
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    return x_upd, joseph_covariance(P_pred, K, H, R)


def kf_update(x_pred, P_pred, z, H, R):
    """Linear Kalman measurement update (Joseph form), equations in the module docstring.

    Parameters
    ----------
    x_pred, P_pred, z, H, R : ndarray
        Prediction (state units, e.g. m and m/s), measurement and its model (module docstring).

    Returns
    -------
    x_upd, P_upd : ndarray, shapes (..., n) and (..., n, n)
        Updated state and covariance.
    nu, S : ndarray, shapes (..., m) and (..., m, m)
        Innovation ``z - H x-`` and its covariance.

    Raises
    ------
    numpy.linalg.LinAlgError
        If S is singular.
    """
    nu, S = kf_innovation(x_pred, P_pred, z, H, R)
    K = kf_gain(P_pred, H, np.linalg.inv(S))
    x_upd, P_upd = joseph_update(x_pred, P_pred, nu, K, H, R)
    return x_upd, P_upd, nu, S
