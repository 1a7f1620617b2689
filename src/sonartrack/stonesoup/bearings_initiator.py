"""A Stone Soup initiator for bearings-only detections: a range-parameterised mixture held until its range is known.

Stone Soup has no bearings-only initiator (its bearing-only example starts the track from the truth). This one
starts, for each unassociated bearing (or elevation + bearing) detection, Peach's bank of range-parameterised
EKFs along the measured line of sight (stonesoup/range_mixture.py: ranges in geometric progression over
[min_range, max_range], the same coefficient of variation C_R in each, equal weights), with a velocity prior of
known speed and unknown course. The bank is *held* inside the initiator: on each later scan it is predicted
with the tracker's transition model, takes the detection with the highest mixture likelihood inside its gate,
and every filter and weight is updated (Ristic et al. 2004, ch. 6). Its moment-matched Gaussian is handed to the
tracker once the range is known well enough for one EKF: the release rule is

    held detections >= min_detections   and   sd_r / r <= release_cv   and   w_1 + w_N <= max_edge_weight

with r and sd_r the collapsed Gaussian's range from the sensor and its sd along the line of sight, and w_1, w_N
the weights of the shortest- and longest-range filters: a mixture piled against an end of [min_range,
max_range] has its range from the prior's bound, not from the bearings (a constant bearing favours the far
filters, whose predicted bearings move least), and is not released. The track's
states are the collapsed Gaussians after each held detection (``GaussianStateUpdate``, one per detection, so the
track starts where the target was first seen), its last state the one the tracker continues from; the mixture at
release is in ``track.metadata["range_mixture"]`` (a Stone Soup ``GaussianMixture``). The first state is one
Gaussian because Stone Soup's Kalman predictors and updaters take one; the rule makes sure that Gaussian is an
honest summary (the mixture has become one narrow mode in range). A candidate that misses ``max_misses`` scans
running, or holds ``max_held`` detections without its range becoming known (no observer manoeuvre, no range
information), is dropped, not released with a meaningless range; ``dropped_unobservable`` counts the latter.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass, field

import numpy as np
from stonesoup.base import Property
from stonesoup.initiator.base import GaussianInitiator
from stonesoup.models.measurement import MeasurementModel
from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing, CartesianToElevationBearing
from stonesoup.models.transition import TransitionModel
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.mixture import GaussianMixture
from stonesoup.types.state import GaussianState, WeightedGaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate

from sonartrack.core.errors import InputError, require
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.filters.ekf import ekf_predict
from sonartrack.stonesoup.range_mixture import (
    angles_and_jacobian,
    collapse,
    component_positions,
    filters_for_cv,
    mixture_update,
    range_cv,
    range_subintervals,
)

#: track metadata key of the range mixture at release (a Stone Soup GaussianMixture)
RANGE_MIXTURE = "range_mixture"


@dataclass(slots=True, eq=False)  # held banks are compared by identity
class _Held:
    """One bank of range filters held in the initiator (arrays: x (N, n), P (N, n, n), log_w (N,))."""

    x: np.ndarray
    P: np.ndarray
    log_w: np.ndarray
    timestamp: datetime.datetime
    offset_m: np.ndarray
    states: list = field(default_factory=list)
    misses: int = 0


class RangeParameterisedInitiator(GaussianInitiator):
    """Starts tracks from bearings-only detections by a held range-parameterised EKF bank (module doc).

    Peach 1995; Ristic, Arulampalam & Gordon 2004, ch. 6. Detections need a ``Cartesian2DToBearing`` or
    ``CartesianToElevationBearing`` measurement model (their own, e.g. with the sensor's ``translation_offset``
    at the time of the detection, or :attr:`measurement_model`). The state is Stone Soup's constant-velocity
    layout: positions at the model's ``mapping``, velocities at :attr:`velocity_mapping`.
    """

    transition_model: TransitionModel = Property(
        doc="Linear-Gaussian transition model the held filters are predicted with (the tracker's own)")
    min_range: float = Property(default=100.0, doc="Shortest range the target may be at (m)")
    max_range: float = Property(default=20000.0, doc="Longest range the target may be at (m)")
    range_cv: float = Property(
        default=0.1, doc="Largest coefficient of variation sd_r / r of one range filter (sets the number of filters)")
    range_prior: str = Property(
        default="log-uniform", doc="Initial weights: 'log-uniform' (equal, Ristic et al.) or 'uniform' in range")
    target_speed: float = Property(
        default=5.0, doc="Typical target speed (m/s); the velocity prior is zero-mean with variance "
                         "target_speed^2 / 2 per axis (a known speed with a uniformly distributed course)")
    velocity_mapping: tuple = Property(
        default=None, doc="State indices of the velocities; None: each position index + 1 (Stone Soup's CV)")
    measurement_model: MeasurementModel = Property(
        default=None, doc="Bearing model for detections that carry none")
    release_cv: float = Property(
        default=0.2, doc="Hand the collapsed Gaussian to the tracker once its range sd / range is at most this")
    max_edge_weight: float = Property(
        default=0.01, doc="Release only while the first and last range filters hold at most this weight together")
    min_detections: int = Property(default=3, doc="Fewest detections held before a track is released")
    max_misses: int = Property(default=3, doc="Drop a held candidate after this many scans running without one")
    max_held: int = Property(
        default=200, doc="Drop a held candidate whose range is still unknown after this many detections")
    gate_probability: float = Property(
        default=0.9999, doc="A detection continues a held candidate if it falls in this gate of one of its filters")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        require(self.release_cv > 0.0, f"release_cv {self.release_cv} must be positive (sd_r / r)")
        require(self.min_detections >= 1, f"min_detections {self.min_detections}: need at least 1")
        n_filters = filters_for_cv(self.min_range, self.max_range, self.range_cv)
        self._range_m, self._range_sd_m, weight = range_subintervals(
            self.min_range, self.max_range, n_filters, self.range_prior)
        self._log_w0 = np.log(weight)
        self.holding: list[_Held] = []
        self.dropped_unobservable = 0

    @property
    def n_filters(self) -> int:
        """The number of range filters N_F in each held bank."""
        return len(self._range_m)

    def initiate(self, detections, timestamp, **kwargs):
        """Continue the held banks with this scan's detections, start banks on the rest, release the ready.

        Parameters
        ----------
        detections : set of Detection
            Unassociated bearing detections of the scan.
        timestamp : datetime.datetime
            The scan's time.

        Returns
        -------
        set of Track
            Tracks released this scan (states: the collapsed Gaussians, module doc).
        """
        free = sorted(detections, key=lambda det: (det.timestamp, tuple(np.ravel(det.state_vector).astype(float))))
        released = set()
        for held in list(self.holding):  # oldest first: the banks that know most choose first
            taken = self._continue(held, free, timestamp)
            if taken is not None:
                free.remove(taken)
            if self._ready(held):
                released.add(self._release(held))
            elif held.misses > self.max_misses or len(held.states) >= self.max_held:
                self.dropped_unobservable += held.misses <= self.max_misses
                self.holding.remove(held)
        for detection in free:
            held = self._start(detection)
            (released.add(self._release(held)) if self._ready(held) else self.holding.append(held))
        return released

    def _geometry(self, detection):
        """(model, position indices, velocity indices, sensor position (d,), rotation (3, 3)) of a detection."""
        model = detection.measurement_model or self.measurement_model
        if not isinstance(model, (Cartesian2DToBearing, CartesianToElevationBearing)):
            raise InputError(f"RangeParameterisedInitiator needs bearing detections (Cartesian2DToBearing or "
                             f"CartesianToElevationBearing); got {type(model).__name__}: give the detections "
                             f"(or measurement_model) a bearing model")
        position = tuple(model.mapping)
        velocity = tuple(self.velocity_mapping or [i + 1 for i in position])
        require(model.ndim_state == 2 * len(position) and len(velocity) == len(position),
                f"state of {model.ndim_state} dimensions: the initiator needs positions {position} and "
                f"velocities {velocity} only (constant velocity)")
        offset = np.asarray(model.translation_offset, float).ravel()[:len(position)]
        return model, position, velocity, offset, np.asarray(model.rotation_matrix, float)

    def _start(self, detection) -> _Held:
        """A bank on one detection: positions along its line of sight, the velocity prior (class doc)."""
        model, position, velocity, offset, rotation = self._geometry(detection)
        z = np.asarray(detection.state_vector, float).ravel()
        pos, pos_covar = component_positions(z, np.diag(np.asarray(model.covar(), float)), self._range_m,
                                             self._range_sd_m, offset, rotation)
        n, n_filters = model.ndim_state, self.n_filters
        x = np.zeros((n_filters, n))
        P = np.zeros((n_filters, n, n))
        x[:, position] = pos
        P[np.ix_(range(n_filters), position, position)] = pos_covar
        P[:, velocity, velocity] = self.target_speed ** 2 / 2.0
        held = _Held(x, P, self._log_w0.copy(), detection.timestamp, offset)
        self._record(held, detection)
        return held

    def _continue(self, held: _Held, free, timestamp):
        """Predict ``held`` to the scan and update it with its most likely gated detection; that detection."""
        dt = (timestamp - held.timestamp).total_seconds()
        if dt > 0:
            F = self.transition_model.matrix(time_interval=datetime.timedelta(seconds=dt))
            Q = self.transition_model.covar(time_interval=datetime.timedelta(seconds=dt))
            held.x, held.P = ekf_predict(held.x, held.P, np.asarray(F, float), np.asarray(Q, float))
            held.timestamp = timestamp
        best, best_loglik = None, -np.inf
        for detection in free:
            model, position, _, offset, rotation = self._geometry(detection)
            h, dh_dp = angles_and_jacobian(held.x[:, position], offset, rotation)
            H = np.zeros(h.shape + (model.ndim_state,))
            H[:, :, position] = dh_dp
            z = np.asarray(detection.state_vector, float).ravel()
            result = mixture_update(held.x, held.P, held.log_w, z, h, H, np.asarray(model.covar(), float))
            if result[4].min() <= chi2_quantile(self.gate_probability, len(z)) and result[3] > best_loglik:
                best, best_loglik, best_result, best_offset = detection, result[3], result, offset
        if best is None:
            held.misses += 1
            return None
        held.x, held.P, held.log_w = best_result[:3]
        held.misses, held.offset_m = 0, best_offset
        self._record(held, best)
        return best

    def _record(self, held: _Held, detection) -> None:
        """Append the bank's collapsed Gaussian after ``detection`` to its states."""
        mean, covar = collapse(held.x, held.P, held.log_w)
        held.states.append(GaussianStateUpdate(mean.reshape(-1, 1), covar, timestamp=detection.timestamp,
                                               hypothesis=SingleHypothesis(None, detection)))

    def _ready(self, held: _Held) -> bool:
        """The release rule (module doc)."""
        if len(held.states) < self.min_detections:
            return False
        _, position, *_ = self._geometry(held.states[-1].hypothesis.measurement)
        state = held.states[-1]
        _, cv = range_cv(np.asarray(state.state_vector, float).ravel()[list(position)],
                         np.asarray(state.covar, float)[np.ix_(position, position)], held.offset_m)
        edge_weight = float(np.exp(held.log_w[0]) + (np.exp(held.log_w[-1]) if self.n_filters > 1 else 0.0))
        return cv <= self.release_cv and edge_weight <= self.max_edge_weight

    def _release(self, held: _Held) -> Track:
        """The track of a ready bank; removed from the held banks."""
        if held in self.holding:
            self.holding.remove(held)
        weights = np.exp(held.log_w)
        mixture = GaussianMixture([WeightedGaussianState(x.reshape(-1, 1), P, timestamp=held.timestamp, weight=w)
                                   for x, P, w in zip(held.x, held.P, weights, strict=True)])
        return Track(list(held.states), init_metadata={RANGE_MIXTURE: mixture})


def collapsed_state(mixture: GaussianMixture) -> GaussianState:
    """The moment-matched Gaussian of a Stone Soup ``GaussianMixture`` (range_mixture.collapse).

    Parameters
    ----------
    mixture : GaussianMixture
        Weighted Gaussian components (weights need not sum to 1).

    Returns
    -------
    GaussianState
        Mean and covariance of the mixture, at its components' timestamp.
    """
    x = np.array([np.asarray(c.state_vector, float).ravel() for c in mixture])
    P = np.array([np.asarray(c.covar, float) for c in mixture])
    log_w = np.log([float(c.weight) for c in mixture])
    mean, covar = collapse(x, P, log_w)
    return GaussianState(mean.reshape(-1, 1), covar, timestamp=mixture[0].timestamp)
