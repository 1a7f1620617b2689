"""Modified-gain extended Kalman filter (MGEKF) update on arrays.

Song & Speyer, "A stochastic analysis of a modified gain extended Kalman filter with applications
to estimation with bearings only measurements", IEEE Trans. Automatic Control 30(10), 1985; as used
by Yoo & Song (paper P2, DIGEST P2). The state update and the gain are the EKF's; only the
covariance update changes, using the modified matrix G = g(z, x-) in place of the Jacobian H::

    nu = z - h(x-)  (bearing wrapped),     S = H P- H^T + R,      K = P- H^T S^-1
    x+ = x- + K nu
    P+ = (I - K G) P- (I - K G)^T + K R K^T

For the bearing + frequency measurement, G's bearing row is Song & Speyer's
g = [cos z, -sin z, 0, 0, 0] / (x_hat sin z + y_hat cos z) and its frequency row is the Jacobian,
because the frequency function is not modifiable while f0 is a state (derivation in
models/passive.py). Since g is evaluated at the *measured* bearing it carries the information of the
new measurement into P, which is what keeps the MGEKF's covariance from collapsing too early along
the range direction (the EKF's classic failure in bearings-only TMA).
"""

from __future__ import annotations

import numpy as np

from sonartrack.filters.ekf import ekf_gain, innovation, joseph_covariance
from sonartrack.models.passive import modified_matrix


def mgekf_update(x_pred, P_pred, z, hx, H, G, R, angle_rows=(0,)):
    """MGEKF measurement update with a given modified matrix G (Song & Speyer 1985; module docstring).

    The state update and gain are the EKF's; the covariance uses G in place of H in the Joseph form.

    Parameters
    ----------
    G : ndarray, shape (..., m, n)
        Modified matrix (used for P+ only; H serves S and K).
    x_pred, P_pred, z, hx, H, R, angle_rows
        As :func:`~sonartrack.filters.ekf.ekf_update` (bearing in rad, clockwise from north, in row 0 of z; R in
        rad^2, Hz^2).

    Returns
    -------
    x_upd, P_upd, nu, S, S_inv : ndarray
        As :func:`~sonartrack.filters.ekf.ekf_update`, P_upd from G.
    """
    nu = innovation(z, hx, angle_rows)
    S, S_inv, K = ekf_gain(P_pred, H, R)
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    return x_upd, joseph_covariance(P_pred, K, G, R), nu, S, S_inv


def mgekf_update_bf(x_pred, P_pred, z, hx, H, R, exact: bool = False):
    """MGEKF update for bearing (+ frequency) measurements, G from :func:`models.passive.modified_matrix`.

    Parameters
    ----------
    x_pred, P_pred : ndarray, shapes (..., 5) and (..., 5, 5)
        Predicted relative state and covariance (state order in models/passive.py).
    z : ndarray, shape (..., m), m = 1 or 2
        Measured bearing (rad, clockwise from north) and, if m = 2, frequency (Hz).
    hx : ndarray, shape (..., m)
        Predicted measurement.
    H : ndarray, shape (..., m, 5)
        Jacobian at x-.
    R : ndarray, shape (..., m, m)
        Measurement noise covariance (rad^2, Hz^2).
    exact : bool, default False
        Passed to ``modified_matrix``: scale the bearing row by d / tan d (d = wrapped z - b_hat) so that
    g (X - X_hat) = z - b_hat exactly instead of tan(z - b_hat) (Song & Speyer's printed row).

    Returns
    -------
    x_upd, P_upd, nu, S, S_inv
        As :func:`mgekf_update`.
    """
    G = modified_matrix(z, x_pred, H, exact=exact)
    return mgekf_update(x_pred, P_pred, z, hx, H, G, R)
