"""The modified-gain extended Kalman filter (MGEKF) update as a Stone Soup updater.

Song & Speyer, "A stochastic analysis of a modified gain extended Kalman filter with applications to
estimation with bearings only measurements", IEEE TAC 30(10), 1985; used by Yoo & Song (paper P2,
DIGEST P2). The gain and the state update are the EKF's; only the covariance update changes, with the
modified matrix G = g(z, x-) in place of the Jacobian H (filters/mgekf.py)::

    nu = z - h(x-)   (angles wrapped by Stone Soup's typed vectors),   S = H P- H^T + R,   K = P- H^T S^-1
    x+ = x- + K nu
    P+ = (I - K G) P- (I - K G)^T + K R K^T

G comes from the measurement model's ``modified_jacobian(state, measurement, exact)``; the bearing +
frequency model of paper P2 (stonesoup/models.py: :class:`BearingFrequency`) has one. Because G is
evaluated at the *measured* bearing, P keeps the information of the new measurement in the range direction,
which keeps the MGEKF from the EKF's early covariance collapse in bearings-only TMA.
"""

from __future__ import annotations

import numpy as np
from stonesoup.base import Property
from stonesoup.models.measurement import MeasurementModel
from stonesoup.types.array import CovarianceMatrix
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from sonartrack.core.errors import InputError
from sonartrack.filters.ekf import joseph_covariance


class MGEKFUpdater(ExtendedKalmanUpdater):
    r"""Modified-gain EKF update (Song & Speyer 1985; paper P2): the EKF's gain and mean update, and

    .. math::

        P_{k|k} = (I - K_k G_k) P_{k|k-1} (I - K_k G_k)^T + K_k R_k K_k^T, \qquad G_k = g(z_k, \hat x_{k|k-1})

    The measurement model must provide ``modified_jacobian(state, measurement, exact=False)`` (e.g.
    :class:`sonartrack.stonesoup.models.BearingFrequency`). ``use_joseph_cov`` has no effect: the MGEKF
    covariance is always in the Joseph-like form above.
    """

    measurement_model: MeasurementModel = Property(
        default=None,
        doc="Measurement model with jacobian() and modified_jacobian(state, measurement, exact); "
            "may instead come with each detection")
    exact: bool = Property(
        default=False,
        doc="Scale the bearing row by d / tan d (d the bearing residual) so that g (X - X_hat) equals the "
            "residual exactly instead of its tangent (models/passive.py)")

    def _posterior_covariance(self, hypothesis):
        """MGEKF covariance and the EKF gain ``K = P- H^T S^-1`` (module doc)."""
        model = self._check_measurement_model(hypothesis.measurement.measurement_model)
        if not hasattr(model, "modified_jacobian"):
            raise InputError(f"MGEKFUpdater needs a measurement model with modified_jacobian(state, measurement); "
                             f"{type(model).__name__} has none: use sonartrack.stonesoup.models.BearingFrequency")
        prediction = hypothesis.prediction
        meas_pred = hypothesis.measurement_prediction
        kalman_gain = np.asarray(meas_pred.cross_covar, float) @ np.linalg.inv(np.asarray(meas_pred.covar, float))
        G = model.modified_jacobian(prediction, hypothesis.measurement, exact=self.exact)
        R = np.asarray(model.covar(), dtype=float)
        P = joseph_covariance(np.asarray(prediction.covar, dtype=float), kalman_gain, G, R)
        return CovarianceMatrix(P), kalman_gain
