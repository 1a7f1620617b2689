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
    """MGEKF update with a given modified matrix G. Returns ``x+, P+, nu, S, S_inv``."""
    nu = innovation(z, hx, angle_rows)
    S, S_inv, K = ekf_gain(P_pred, H, R)
    x_upd = x_pred + np.einsum("...ij,...j->...i", K, nu)
    return x_upd, joseph_covariance(P_pred, K, G, R), nu, S, S_inv


def mgekf_update_bf(x_pred, P_pred, z, hx, H, R, exact: bool = False):
    """MGEKF update for bearing (+ frequency) rows: G from :func:`models.passive.modified_matrix`."""
    G = modified_matrix(z, x_pred, H, exact=exact)
    return mgekf_update(x_pred, P_pred, z, hx, H, G, R)
