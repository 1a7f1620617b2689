"""Paper P2's passive bearing + frequency measurement, and the relative motion it goes with, as Stone Soup models.

State order -- sonartrack's relative, observer-centred state (models/relative_motion.py), *not* Stone Soup's
usual [x, vx, y, vy]::

    X = [x, y, vx, vy, f0]    target minus observer position (m; x east, y north) and velocity (m/s),
                              and the emitted frequency f0 (Hz)

Measurement (Yoo & Song, paper P2, eq. 3; DIGEST P2; the bearing clockwise from north as in DESIGN.md)::

    z = h(X) + v,   h(X) = [ b, f ],   b = atan2(x, y),   f = f0 (1 - rdot / c),   rdot = (x vx + y vy) / r
    v ~ N(0, R),    R = diag(sigma_b^2, sigma_f^2)   (rad^2, Hz^2); a 1 x 1 R measures the bearing alone

The bearing is returned as a Stone Soup :class:`~stonesoup.types.angle.Bearing`, so that Stone Soup's
updaters wrap the innovation z - h(X) to [-pi, pi) themselves. The Jacobian and Song & Speyer's modified
matrix (the MGEKF's g(z, X_hat), stonesoup/mgekf.py) come from models/passive.py, where their derivation is.

Motion (P2 eq. 2, discretised exactly for a constant-velocity target; models/relative_motion.py)::

    X_k+1 = F X_k - u_k + w_k,    F = [[I, T I, 0], [0, I, 0], [0, 0, 1]]
    Q = [[q T^3/3 I, q T^2/2 I, 0], [q T^2/2 I, q T I, 0], [0, 0, q_f0 T]]

The observer's own motion u_k (models/relative_motion.py: ``observer_inputs``) enters Stone Soup as a
control input: ``KalmanPredictor(RelativeConstantVelocity(q), control_model=observer_control_model())``
and ``predict(prior, timestamp, control_input=State(u_k))`` give x- = F x + (-I) u_k.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property
from stonesoup.models.base import TimeVariantModel
from stonesoup.models.control.linear import LinearControlModel
from stonesoup.models.measurement.nonlinear import NonLinearGaussianMeasurement
from stonesoup.models.transition.linear import LinearGaussianTransitionModel
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector, StateVectors

from sonartrack.core.errors import require
from sonartrack.filters.ekf import gaussian_loglik
from sonartrack.models.passive import SOUND_SPEED_MPS, bf_jacobian, bf_measurement, modified_matrix
from sonartrack.models.relative_motion import STATE_DIM, relative_process_noise, relative_transition


def _as_float_columns(state) -> np.ndarray:
    """The state vector(s) of ``state`` as a float array (n, N)."""
    return np.asarray(np.asarray(state.state_vector, dtype=float)).reshape(STATE_DIM, -1)


class BearingFrequency(NonLinearGaussianMeasurement):
    r"""Bearing + frequency of a target seen from the observer (paper P2, eq. 3), on the relative state
    [x, y, vx, vy, f0] (module doc).

    .. math::

        b = \operatorname{atan2}(x, y), \qquad f = f_0 \left(1 - \frac{x v_x + y v_y}{c\, r}\right)

    ``noise_covar`` is 2 x 2 (rad^2, Hz^2) for [bearing, frequency] or 1 x 1 for the bearing alone.
    :meth:`modified_jacobian` is the MGEKF's g(z, X_hat) (Song & Speyer 1985): bearing row modified,
    frequency row the Jacobian's (it is not modifiable while f0 is a state, models/passive.py).
    """

    ndim_state: int = Property(default=STATE_DIM, doc="Number of state dimensions: 5, [x, y, vx, vy, f0]")
    mapping: Sequence[int] = Property(default=(0, 1, 2, 3, 4), doc="The whole relative state is read")
    sound_speed_mps: float = Property(default=SOUND_SPEED_MPS, doc="Speed of sound c (m/s)")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        require(self.ndim_state == STATE_DIM, "BearingFrequency reads the 5-entry state [x, y, vx, vy, f0]")
        require(self.noise_covar.shape in ((1, 1), (2, 2)),
                "noise_covar must be 2 x 2 (bearing rad^2, frequency Hz^2) or 1 x 1 (bearing alone)")

    @property
    def ndim_meas(self) -> int:
        """2 (bearing, frequency), or 1 with a 1 x 1 ``noise_covar`` (bearing alone)."""
        return self.noise_covar.shape[0]

    def _typed_vector(self) -> np.ndarray:
        return np.array([[Bearing(0.0)], [0.0]], dtype=object)[: self.ndim_meas]

    def function(self, state, noise=False, **kwargs):
        """h(X) (+ noise), as a typed StateVector (one state) or StateVectors (several columns).

        Parameters
        ----------
        state : State
            Relative state(s) [x, y, vx, vy, f0] (m, m/s, Hz), one column or N columns.
        noise : bool or array_like
            True: add a draw of :meth:`rvs`; False/None: none; an array: added as given.
        **kwargs
            Passed to :meth:`rvs`.

        Returns
        -------
        StateVector or StateVectors, shape (m, 1) or (m, N)
            Bearing (rad clockwise from north, a Stone Soup Bearing) and, when m = 2, frequency (Hz).
        """
        X = _as_float_columns(state)
        h = bf_measurement(X.T, self.sound_speed_mps)[:, : self.ndim_meas].T  # (m, N)
        if isinstance(noise, bool) or noise is None:
            noise = self.rvs(num_samples=X.shape[1], **kwargs) if noise else 0.0
        out = self._typed_vector() + h + noise
        return StateVector(out) if out.shape[1] == 1 else StateVectors(out)

    def jacobian(self, state, **kwargs) -> np.ndarray:
        """dh/dX (m, 5) at the state (models/passive.py: ``bf_jacobian``).

        Parameters
        ----------
        state : State
            Relative state [x, y, vx, vy, f0] (its first column is used).
        **kwargs
            Not used (Stone Soup's signature).

        Returns
        -------
        ndarray, shape (m, 5)
            Rows d b / dX (rad per state unit) and, when m = 2, d f / dX (Hz per state unit).
        """
        return bf_jacobian(_as_float_columns(state)[:, 0], self.sound_speed_mps)[: self.ndim_meas]

    def modified_jacobian(self, state, measurement, exact: bool = False) -> np.ndarray:
        """Song & Speyer's modified matrix G = g(z, X_hat) (m, 5): the Jacobian with its bearing row replaced
        by ``[cos z, -sin z, 0, 0, 0] / (x_hat sin z + y_hat cos z)`` (models/passive.py: ``modified_matrix``).

        Parameters
        ----------
        state : State
            Predicted relative state X_hat [x, y, vx, vy, f0].
        measurement : State or Detection
            The measurement z: bearing (rad) first, then frequency (Hz) when measured.
        exact : bool
            Scale the bearing row by d / tan d, d = wrap(z - b_hat), so that g (X - X_hat) = z - b_hat exactly
            (models/passive.py: ``bearing_modified_row``).

        Returns
        -------
        ndarray, shape (m, 5)
            G: the modified bearing row, then the frequency row of the Jacobian.
        """
        z = np.asarray(measurement.state_vector, dtype=float).ravel()
        x_hat = _as_float_columns(state)[:, 0]
        return modified_matrix(z[: self.ndim_meas], x_hat, self.jacobian(state), exact=exact)

    def rvs(self, num_samples: int = 1, **kwargs):
        """Noise samples v ~ N(0, R), the bearing row typed as a Bearing.

        Parameters
        ----------
        num_samples : int
            Number of samples N.
        **kwargs
            Passed to Stone Soup's ``rvs``.

        Returns
        -------
        ndarray, shape (m, N)
            Samples (rad for the bearing, Hz for the frequency).
        """
        return self._typed_vector() + super().rvs(num_samples, **kwargs)

    def logpdf(self, state1, state2, **kwargs):
        """log N(z - h(X); 0, R) with the bearing residual wrapped to [-pi, pi).

        Parameters
        ----------
        state1 : State
            The measurement z.
        state2 : State
            The state(s) X (one or N columns).
        **kwargs
            Passed to :meth:`function`.

        Returns
        -------
        float or ndarray, shape (N,)
            The log density, one value per state column.
        """
        nu = np.asarray(state1.state_vector - self.function(state2, **kwargs), dtype=float).T  # (N, m)
        R = np.asarray(self.covar(), dtype=float)
        ll = gaussian_loglik(nu, R, np.linalg.inv(R))
        return ll[0] if ll.shape == (1,) else ll


class RelativeConstantVelocity(LinearGaussianTransitionModel, TimeVariantModel):
    r"""Relative constant-velocity motion of [x, y, vx, vy, f0] (paper P2, eq. 2, discretised; module doc).

    .. math::

        F = \begin{bmatrix} I & T I & 0 \\ 0 & I & 0 \\ 0 & 0 & 1 \end{bmatrix}, \qquad
        Q = \begin{bmatrix} q T^3/3\, I & q T^2/2\, I & 0 \\ q T^2/2\, I & q T\, I & 0 \\ 0 & 0 & q_{f_0} T
        \end{bmatrix}

    The observer's motion is the control input (:func:`observer_control_model`).
    """

    noise_diff_coeff: float = Property(doc="Target white-noise acceleration intensity q (m^2/s^3)")
    f0_noise_diff_coeff: float = Property(default=0.0, doc="Random-walk intensity q_f0 of f0 (Hz^2/s)")

    @property
    def ndim_state(self) -> int:
        """5: the relative state [x, y, vx, vy, f0]."""
        return STATE_DIM

    def matrix(self, time_interval, **kwargs) -> np.ndarray:
        """F over ``time_interval`` (a datetime.timedelta).

        Parameters
        ----------
        time_interval : datetime.timedelta
            The prediction interval T.
        **kwargs
            Not used (Stone Soup's signature).

        Returns
        -------
        ndarray, shape (5, 5)
            The transition matrix F (class doc).
        """
        return relative_transition(time_interval.total_seconds())

    def covar(self, time_interval, **kwargs) -> CovarianceMatrix:
        """Q over ``time_interval`` (a datetime.timedelta).

        Parameters
        ----------
        time_interval, **kwargs
            As :meth:`matrix`.

        Returns
        -------
        CovarianceMatrix, shape (5, 5)
            The process noise Q (class doc) with ``noise_diff_coeff`` (m^2/s^3) and ``f0_noise_diff_coeff`` (Hz^2/s).
        """
        dt_s = time_interval.total_seconds()
        return CovarianceMatrix(relative_process_noise(dt_s, self.noise_diff_coeff, self.f0_noise_diff_coeff))


def observer_control_model() -> LinearControlModel:
    """The observer's motion as a Stone Soup control model: B = -I (5 x 5), no control noise, so that a
    KalmanPredictor given ``control_input=State(u_k)`` predicts x- = F x - u_k (module doc).

    Returns
    -------
    LinearControlModel
        Control matrix -I and a zero control noise (5 x 5).
    """
    return LinearControlModel(control_matrix=-np.eye(STATE_DIM), control_noise=np.zeros((STATE_DIM, STATE_DIM)))
