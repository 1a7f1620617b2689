"""Extended Kalman filter steps on arrays (batched over leading axes, e.g. IMM modes).

Shapes: x (..., n), P (..., n, n), z (..., m), hx = h(x-) (..., m), H = dh/dx at x- (..., m, n),
R (..., m, m). Functions return new arrays and never mutate their inputs.

Equations (Bar-Shalom, Li, Kirubarajan 2001, sec. 10.3.2; the same steps as FilterPy's
``ExtendedKalmanFilter``, which tests/filters/test_ekf.py checks against)::

    predict:  x- = F x + b,            P- = F P F^T + Q          (b: known input term, e.g. -u)
    update:   nu = z - h(x-)   (angular components wrapped to (-pi, pi])
              S = H P- H^T + R,        K = P- H^T S^-1
              x+ = x- + K nu,          P+ = (I - K H) P- (I - K H)^T + K R K^T   (Joseph form)

The mode likelihood used by an IMM is N(nu; 0, S). The arguments are named as in filters/kalman.py's module
docstring (H is the Jacobian dh/dx at x-); ``hx`` is the predicted measurement h(x-) and ``angle_rows`` the
measurement components that are angles (rad), wrapped to (-pi, pi] in the innovation.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.linalg import symmetrize
from sonartrack.filters.kalman import joseph_covariance, kf_predict


def ekf_predict(x, P, F, Q, b=None):
    """EKF time update ``x- = F x + b``, ``P- = F P F^T + Q`` (Bar-Shalom et al. 2001, sec. 10.3.2).

    Parameters
    ----------
    x, P, F, Q : ndarray
        As :func:`~sonartrack.filters.kalman.kf_predict`; F may be the Jacobian of a nonlinear motion model at x.
    b : ndarray, shape (n,) or (..., n), optional
        Known input term added to the prediction (e.g. minus the observer's displacement in a relative
        state); None for none.

    Returns
    -------
    x_pred, P_pred : ndarray, shapes (..., n) and (..., n, n)
        Predicted state and covariance (symmetrized).
    """
    x_pred, P_pred = kf_predict(x, P, F, Q)
    return (x_pred if b is None else x_pred + b), P_pred


def innovation(z, hx, angle_rows=(0,)):
    """Innovation ``nu = z - h(x-)`` with the angular components wrapped to (-pi, pi].

    Parameters
    ----------
    z : array_like, shape (..., m)
        Measurement (angles in rad).
    hx : array_like, shape (..., m)
        Predicted measurement h(x-), same units.
    angle_rows : sequence of int, default (0,)
        Components that are angles (rad) and are wrapped; indices beyond m are ignored.

    Returns
    -------
    ndarray, shape (..., m)
        The innovation (a new array).
    """
    nu = np.array(np.asarray(z, float) - np.asarray(hx, float), copy=True)
    for i in angle_rows:
        if i < nu.shape[-1]:
            nu[..., i] = wrap_angle(nu[..., i])
    return nu


def ekf_gain(P_pred, H, R):
    """Innovation covariance ``S = H P- H^T + R``, its inverse, and the gain ``K = P- H^T S^-1``.

    Parameters
    ----------
    P_pred, H, R : ndarray, shapes (..., n, n), (..., m, n), (..., m, m)
        Predicted covariance, Jacobian at x- and measurement noise (e.g. rad^2 for a bearing; module docstring).

    Returns
    -------
    S : ndarray, shape (..., m, m)
        Innovation covariance, symmetrized.
    S_inv : ndarray, shape (..., m, m)
        Its inverse.
    K : ndarray, shape (..., n, m)
        The gain.
    """
    PHt = P_pred @ np.swapaxes(H, -1, -2)
    S = symmetrize(H @ PHt + R)
    S_inv = np.linalg.inv(S)
    return S, S_inv, PHt @ S_inv


def ekf_update(x_pred, P_pred, z, hx, H, R, angle_rows=(0,)):
    """EKF measurement update (Joseph form), equations in the module docstring.

    Parameters
    ----------
    x_pred, P_pred, z, hx, H, R : ndarray
        Prediction, measurement (angles in rad), predicted measurement, Jacobian, noise (module docstring).
    angle_rows : sequence of int, default (0,)
        Measurement components wrapped to (-pi, pi] in the innovation.

    Returns
    -------
    x_upd, P_upd : ndarray, shapes (..., n) and (..., n, n)
        Updated state and covariance.
    nu : ndarray, shape (..., m)
        Wrapped innovation.
    S, S_inv : ndarray, shape (..., m, m)
        Innovation covariance and its inverse (for the likelihood N(nu; 0, S)).

    Raises
    ------
    numpy.linalg.LinAlgError
        If S is singular.
    """
    nu = innovation(z, hx, angle_rows)
    S, S_inv, K = ekf_gain(P_pred, H, R)
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    return x_upd, joseph_covariance(P_pred, K, H, R), nu, S, S_inv


def gaussian_loglik(nu, S, S_inv):
    """Log-density ``log N(nu; 0, S)`` of innovations (the IMM mode likelihood).

    ``-0.5 (m log 2 pi + log det S + nu^T S^-1 nu)``.

    Parameters
    ----------
    nu : ndarray, shape (..., m)
        Innovations.
    S : ndarray, shape (..., m, m)
        Innovation covariance.
    S_inv : ndarray, shape (..., m, m)
        Its inverse.

    Returns
    -------
    ndarray, shape (...)
        Log-likelihood (natural log; the density is per unit of each measurement component).
    """
    m = nu.shape[-1]
    _, logdet = np.linalg.slogdet(S)
    d2 = np.einsum("...i,...ij,...j->...", nu, S_inv, nu)
    return -0.5 * (m * np.log(2.0 * np.pi) + logdet + d2)
