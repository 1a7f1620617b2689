"""Gaussian IMM as Stone Soup components: the IMM state, predictor and updater.

Stone Soup has no Gaussian IMM (its PRs #142 and #1257 are unmerged) and no IPDA (PR #784 is open). Here
they are, built on Stone Soup's own bases and types, with the generic IMM steps of filters/imm.py inside
and Stone Soup predictors/updaters as the mode-matched filters (Blom & Bar-Shalom 1988; Bar-Shalom, Li,
Kirubarajan 2001, sec. 11.6.6). With Pi[i, j] = P(mode j at k | mode i at k-1)::

    interaction    c_j = sum_i Pi[i, j] mu_i,   mu_{i|j} = Pi[i, j] mu_i / c_j
                   x0_j = sum_i mu_{i|j} x_i,   P0_j = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T)
    mode filters   x-_j, P-_j = predictors[j].predict(x0_j, P0_j);   x_j, P_j = updater.update(x-_j, P-_j, z)
    mode update    mu_j = c_j Lambda_j / sum_l c_l Lambda_l,   Lambda_j = N(nu_j; 0, S_j)
    combination    x = sum_j mu_j x_j,   P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)

**State type (the choice).** :class:`IMMState` subclasses Stone Soup's ``GaussianState``: its
``state_vector`` and ``covar`` are the combined (IMM output) estimate, so every Stone Soup part that reads
a Gaussian (metrics, plotters, Mahalanobis gates, Kalman hypothesisers, deleters) reads the IMM's output
unchanged; the mode-conditioned means ``(r, n)``, covariances ``(r, n, n)`` and mode probabilities ``(r,)``
ride along as arrays in filters/imm.py's layout. It is not a ``GaussianMixture``: a mixture's
components are independent and reducing it would lose the mode identity that the next interaction needs.
A prediction's ``mode_probabilities`` are the predicted c_j, an update's the posterior mu_j.

The IMM-IPDA of paper P4 on these parts is stonesoup/imm_ipda.py.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property
from stonesoup.models.base import LinearModel
from stonesoup.models.measurement import MeasurementModel
from stonesoup.models.transition import TransitionModel
from stonesoup.predictor import Predictor
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import (
    GaussianMeasurementPrediction,
    GaussianStatePrediction,
    MeasurementPrediction,
    Prediction,
)
from stonesoup.types.state import GaussianState, State, StateMutableSequence
from stonesoup.types.update import Update
from stonesoup.updater import Updater
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater

from sonartrack.core.errors import InputError, require
from sonartrack.filters.ekf import gaussian_loglik
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update, validate_transition_matrix


class IMMState(GaussianState):
    """Gaussian IMM state: the combined estimate as a GaussianState, plus the r mode-conditioned estimates.

    Built without ``mode_means`` it is a one-mode IMM of the Gaussian itself. :meth:`from_modes` builds it
    from the modes with ``x = sum_j mu_j x_j``, ``P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)``.
    """

    mode_means: np.ndarray = Property(default=None, doc="Mode-conditioned means x_j, shape (r, n)")
    mode_covars: np.ndarray = Property(default=None, doc="Mode-conditioned covariances P_j, shape (r, n, n)")
    mode_probabilities: np.ndarray = Property(
        default=None, doc="Mode probabilities (r,): posterior mu_j on an update, predicted c_j on a prediction")
    existence_probability: float = Property(
        default=None, doc="IPDA probability that the target exists (IMM-IPDA); None for a plain IMM")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if self.mode_means is None:
            self.mode_means = np.asarray(self.state_vector, dtype=float).T.copy()
            self.mode_covars = np.asarray(self.covar, dtype=float)[None].copy()
            self.mode_probabilities = np.ones(1)
        x, P = np.asarray(self.mode_means, float), np.asarray(self.mode_covars, float)
        mu = np.asarray(self.mode_probabilities, float)
        r = len(mu)
        require(x.shape == (r, self.ndim) and P.shape == (r, self.ndim, self.ndim),
                f"IMMState needs mode_means ({r}, {self.ndim}) and mode_covars ({r}, {self.ndim}, {self.ndim}); "
                f"got {x.shape} and {P.shape}")
        require(bool(np.all(mu >= 0)) and abs(mu.sum() - 1.0) < 1e-9, "mode_probabilities must sum to 1")
        self.mode_means, self.mode_covars, self.mode_probabilities = x, P, mu

    @classmethod
    def from_modes(cls, mode_means, mode_covars, mode_probabilities, **kwargs):
        """The state of these modes, its combined estimate by filters/imm.py's ``imm_combine``.

        Parameters
        ----------
        mode_means : array_like, shape (r, n)
            Mode-conditioned means x_j.
        mode_covars : array_like, shape (r, n, n)
            Mode-conditioned covariances P_j.
        mode_probabilities : array_like, shape (r,)
            Mode probabilities mu_j (sum 1).
        **kwargs
            Further properties of the state (``timestamp``, ``hypothesis``, ``existence_probability`` ...).

        Returns
        -------
        IMMState (or the subclass it is called on)
            Combined estimate x = sum_j mu_j x_j, P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T) with the modes attached;
            one mode is taken as given.
        """
        x, P, mu = (np.asarray(a, dtype=float) for a in (mode_means, mode_covars, mode_probabilities))
        # one mode is its own combination (as given: a one-mode IMM is exactly the mode filter, round-off included)
        xc, Pc = (x[0], P[0]) if len(mu) == 1 else imm_combine(mu, x, P)
        return cls(StateVector(xc), CovarianceMatrix(Pc), mode_means=x, mode_covars=P, mode_probabilities=mu,
                   **kwargs)

    @property
    def n_modes(self) -> int:
        """The number of modes r."""
        return len(self.mode_probabilities)

    @property
    def mode_states(self) -> list[GaussianState]:
        """The mode-conditioned estimates as Stone Soup GaussianStates."""
        return [GaussianState(StateVector(x), CovarianceMatrix(P), timestamp=self.timestamp)
                for x, P in zip(self.mode_means, self.mode_covars, strict=True)]


class IMMStatePrediction(Prediction, IMMState):
    """An IMM prediction: the mode-matched predictions and the predicted mode probabilities c_j."""


class IMMStateUpdate(Update, IMMState):
    """An IMM update: the mode-matched updates and the posterior mode probabilities mu_j."""

    log_likelihood: float = Property(
        default=None, doc="log sum_j c_j Lambda_j: the IMM likelihood of the measurement (IMMUpdater), or the "
                          "IPDA likelihood ratio log Lambda = log(1 - delta) (IMMIPDAUpdater)")


def current_state(track_or_state) -> State:
    """The latest state of a Track (any StateMutableSequence), or the state itself.

    Parameters
    ----------
    track_or_state : Track, StateMutableSequence or State
        A track or a single state.

    Returns
    -------
    State
        The track's last state, or ``track_or_state`` unchanged when it is a state.
    """
    if isinstance(track_or_state, StateMutableSequence) and not isinstance(track_or_state, State):
        return track_or_state.state
    return track_or_state


def as_imm_state(state, n_modes: int, mode_probabilities=None) -> IMMState:
    """``state`` as an r-mode IMMState: an IMMState is checked, a plain GaussianState is given to every mode
    with ``mode_probabilities`` (default equal, as P4's 1/r initial mode probabilities).

    Parameters
    ----------
    state : GaussianState or IMMState
        The state to convert.
    n_modes : int
        The number of modes r the IMM expects (an IMMState with another count is refused).
    mode_probabilities : array_like, shape (r,), optional
        Mode probabilities of a plain GaussianState; default 1/r each.

    Returns
    -------
    IMMState
        ``state`` itself when already an IMMState, else r copies of its mean and covariance.
    """
    if isinstance(state, IMMState):
        require(state.n_modes == n_modes, f"state has {state.n_modes} modes, the IMM {n_modes}")
        return state
    mu = np.full(n_modes, 1.0 / n_modes) if mode_probabilities is None else np.asarray(mode_probabilities, float)
    x = np.repeat(np.asarray(state.state_vector, dtype=float).T, n_modes, axis=0)
    P = np.repeat(np.asarray(state.covar, dtype=float)[None], n_modes, axis=0)
    return IMMState.from_modes(x, P, mu, timestamp=state.timestamp)


class IMMPredictor(Predictor):
    """IMM interaction (filters/imm.py) followed by each mode's own Stone Soup predictor (module doc).

    ``predictors[j]`` predicts mode j, e.g. ``KalmanPredictor(CombinedLinearGaussianTransitionModel(
    [ConstantVelocity(q_j)] * 2))``; keyword arguments of :meth:`predict` (``control_input`` ...) go to every
    mode's predictor. When every mode predictor is a plain ``KalmanPredictor`` the modes are predicted
    together on arrays with the same equations (x- = F x0 + B u, P- = F P0 F^T + Q + B Gamma B^T).
    """

    transition_model: TransitionModel = Property(default=None, doc="Not used: each mode predictor has its own")
    predictors: Sequence[Predictor] = Property(doc="One Stone Soup predictor per mode")
    transition_probabilities: np.ndarray = Property(
        doc="Markov matrix Pi (r, r), Pi[i, j] = P(mode j at k | mode i at k-1); rows sum to 1")
    initial_mode_probabilities: np.ndarray = Property(
        default=None, doc="Mode probabilities given to a plain GaussianState prior (default: equal)")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.transition_probabilities = validate_transition_matrix(self.transition_probabilities)
        r = len(self.predictors)
        require(r >= 1 and self.transition_probabilities.shape == (r, r),
                f"{r} mode predictors need a {r} x {r} transition matrix, got {self.transition_probabilities.shape}")

    def predict(self, prior, timestamp=None, **kwargs) -> IMMStatePrediction:
        """Interaction, then every mode's prediction to ``timestamp``; returns the mode predictions with c_j.

        Parameters
        ----------
        prior : Track or State
            The prior (a Track's last state is used); a plain GaussianState becomes an IMMState with
            ``initial_mode_probabilities``.
        timestamp : datetime.datetime, optional
            Time to predict to.
        **kwargs
            Passed to every mode's predictor (``control_input`` ...).

        Returns
        -------
        IMMStatePrediction
            The mode-matched predictions x-_j, P-_j, the predicted mode probabilities c_j and their combination.
        """
        prior = as_imm_state(current_state(prior), len(self.predictors), self.initial_mode_probabilities)
        c, x0, P0 = prior.mode_probabilities, prior.mode_means, prior.mode_covars  # one mode: mixing is identity
        if len(c) > 1:
            c, w = imm_mixing(c, self.transition_probabilities)
            x0, P0 = imm_mix(x0, P0, w)
        if all(type(p) is KalmanPredictor for p in self.predictors):
            x, P = self._predict_linear(x0, P0, prior, timestamp, **kwargs)
        else:
            x, P = self._predict_modes(x0, P0, prior, timestamp, **kwargs)
        return IMMStatePrediction.from_modes(x, P, c, timestamp=timestamp, prior=prior)

    def _predict_modes(self, x0, P0, prior, timestamp, **kwargs):
        """Each mode through its own predictor, as Stone Soup GaussianStates."""
        preds = [p.predict(GaussianState(StateVector(x), CovarianceMatrix(P), timestamp=prior.timestamp),
                           timestamp=timestamp, **kwargs)
                 for p, x, P in zip(self.predictors, x0, P0, strict=True)]
        return (np.stack([np.asarray(s.state_vector, float)[:, 0] for s in preds]),
                np.stack([np.asarray(s.covar, float) for s in preds]))

    def _predict_linear(self, x0, P0, prior, timestamp, control_input=None, **kwargs):
        """KalmanPredictor's equations for all modes at once: x- = F x0 + B u, P- = F P0 F^T + Q + B Gamma B^T."""
        dt = None if timestamp is None or prior.timestamp is None else timestamp - prior.timestamp
        F, Q, b = self._mode_matrices(prior, dt, control_input, kwargs)
        return np.einsum("jab,jb->ja", F, x0) + b, F @ P0 @ np.swapaxes(F, -1, -2) + Q

    def _mode_matrices(self, prior, dt, control_input, kwargs):
        """F (r, n, n), Q + B Gamma B^T (r, n, n) and B u (r, n) of every mode over ``dt``. Without a control
        input or keyword arguments they are kept per time interval (Stone Soup's models cache theirs the same
        way): scans mostly come at one period, and building Stone Soup's matrices costs more than the IMM."""
        key = dt if control_input is None and not kwargs else None
        cache = self.__dict__.setdefault("_matrices", {})
        if key is not None and key in cache:
            return cache[key]
        F, Q, b = [], [], []
        for p in self.predictors:
            F.append(p.transition_model.matrix(time_interval=dt, **kwargs))
            B = p.control_model.matrix(control_input=control_input, prior=prior, time_interval=dt, **kwargs)
            Q.append(p.transition_model.covar(time_interval=dt, **kwargs) + B @ p.control_model.control_noise @ B.T)
            bu = p.control_model.function(control_input, prior=prior, time_interval=dt, **kwargs)
            b.append(np.asarray(bu, dtype=float)[:, 0])
        out = (np.stack(F).astype(float), np.stack(Q).astype(float), np.stack(b))
        if key is not None:
            if len(cache) > 64:
                cache.clear()
            cache[key] = out
        return out


def _linear_kalman(updater, model) -> bool:
    """True when ``updater`` is a plain (E)KF updater on a linear model: its steps are then done on arrays."""
    return (type(updater) in (KalmanUpdater, ExtendedKalmanUpdater) and isinstance(model, LinearModel)
            and not updater.force_positive_definite_covariance)


def mode_measurement_moments(updater, state: IMMState, model, measurement_noise: bool = True, **kwargs):
    """Each mode's predicted measurement z_j (r, k) (typed, e.g. Bearing, where the model types it), innovation
    covariance S_j = H P_j H^T + R (r, k, k) and cross-covariance P_j H^T (r, n, k), by ``updater``.

    Parameters
    ----------
    updater : stonesoup.updater.Updater
        The mode updater whose ``predict_measurement`` gives the moments (a plain (E)KF updater on a linear model is
        done on arrays with the same equations).
    state : IMMState
        The predicted IMM state (r modes, n state entries).
    model : MeasurementModel
        The measurement model (k measured entries).
    measurement_noise : bool
        Add R to S_j (True) or not.
    **kwargs
        Passed to the model's ``matrix``/``covar`` or the updater.

    Returns
    -------
    z_hat : ndarray, shape (r, k)
        Predicted measurements per mode.
    S : ndarray, shape (r, k, k)
        Innovation covariances per mode.
    cross : ndarray, shape (r, n, k)
        Cross-covariances P_j H^T per mode.
    """
    if _linear_kalman(updater, model):
        H = np.asarray(model.matrix(**kwargs), dtype=float)
        cross = state.mode_covars @ H.T
        S = H @ cross + (np.asarray(model.covar(**kwargs), float) if measurement_noise else 0.0)
        return state.mode_means @ H.T, S, cross
    preds = [updater.predict_measurement(GaussianStatePrediction(s.state_vector, s.covar, timestamp=s.timestamp),
                                         model, measurement_noise, **kwargs) for s in state.mode_states]
    return (np.stack([np.asarray(mp.state_vector).ravel() for mp in preds]),
            np.stack([np.asarray(mp.covar, dtype=float) for mp in preds]),
            np.stack([np.asarray(mp.cross_covar, dtype=float) for mp in preds]))


def innovations(measurement, z_hat) -> np.ndarray:
    """nu = z - z_hat per mode (r, k), with angular entries wrapped by their Stone Soup types.

    Parameters
    ----------
    measurement : Detection or State
        The measurement z (its ``state_vector``, k entries).
    z_hat : array_like, shape (r, k)
        Predicted measurements per mode (typed entries keep their wrapping).

    Returns
    -------
    ndarray, shape (r, k)
        Innovations nu_j, in the measurement's units (m, rad, ...).
    """
    z = np.asarray(measurement.state_vector).ravel()
    return np.asarray(z[None, :] - z_hat, dtype=float)


class IMMUpdater(Updater):
    """IMM measurement update: ``updater`` in every mode, then mode probabilities and combination (module doc).

    ``updater`` is any Stone Soup Kalman-type updater (KalmanUpdater, ExtendedKalmanUpdater, UnscentedKalmanUpdater,
    :class:`~sonartrack.stonesoup.mgekf.MGEKFUpdater`); a plain (E)KF updater on a linear model runs on arrays with
    its own equations (``use_joseph_cov`` and ``force_symmetric_covariance`` honoured). The mode likelihood is
    Lambda_j = N(nu_j; 0, S_j) with nu_j and S_j from that mode's measurement prediction.
    """

    measurement_model: MeasurementModel = Property(
        default=None, doc="Measurement model (default: the mode updater's); a detection's own model comes first")
    updater: Updater = Property(doc="Stone Soup updater run in every mode")

    def _model(self, measurement_model=None):
        model = measurement_model or self.measurement_model or self.updater.measurement_model
        if model is None:
            raise InputError("no measurement model: give one to the detections, the IMMUpdater or its updater")
        return model

    def predict_measurement(self, predicted_state, measurement_model=None, measurement_noise=True, **kwargs):
        """The moment-matched measurement prediction of the modes: z = sum_j c_j z_j,
        S = sum_j c_j (S_j + (z_j - z)(z_j - z)^T), cross = sum_j c_j (C_j + (x_j - x)(z_j - z)^T).

        Parameters
        ----------
        predicted_state : IMMState or GaussianState
            The prediction (a plain Gaussian is taken as one mode).
        measurement_model : MeasurementModel, optional
            The model; default the updater's (``measurement_model``, else the mode updater's).
        measurement_noise : bool
            Include R in the mode covariances S_j.
        **kwargs
            Passed to the mode updater / model.

        Returns
        -------
        GaussianMeasurementPrediction
            Mean z, covariance S and ``cross_covar`` of the mode mixture (angles combined as offsets from mode 0's
            prediction, so they do not average across the wrap).
        """
        state = as_imm_state(predicted_state, getattr(predicted_state, "n_modes", 1))
        z_hat, S, cross = mode_measurement_moments(self.updater, state, self._model(measurement_model),
                                                   measurement_noise, **kwargs)
        c = state.mode_probabilities
        dz = np.asarray(z_hat - z_hat[0], dtype=float)  # offsets from mode 0's prediction (angles wrapped)
        dz_mean, S_c = imm_combine(c, dz, S)
        dx = state.mode_means - np.asarray(state.state_vector, float)[:, 0]
        cross_c = np.einsum("j,jnk->nk", c, cross) + np.einsum("j,jn,jk->nk", c, dx, dz - dz_mean)
        z = StateVector((z_hat[0] + dz_mean).reshape(-1, 1))
        return MeasurementPrediction.from_state(state, z, CovarianceMatrix(S_c), cross_covar=cross_c,
                                                target_type=GaussianMeasurementPrediction)

    def update(self, hypothesis, **kwargs) -> IMMStateUpdate:
        """Every mode's update with the hypothesis' detection, then mu_j = c_j Lambda_j / sum and combination.

        Parameters
        ----------
        hypothesis : SingleHypothesis
            The prediction (IMMState or plain Gaussian) and the detection; a missed detection keeps the modes and the
            probabilities as predicted.
        **kwargs
            Passed to the mode updater.

        Returns
        -------
        IMMStateUpdate
            The mode updates x_j, P_j, the posterior mode probabilities mu_j, their combination and
            ``log_likelihood`` = log sum_j c_j Lambda_j (not set for a missed detection).
        """
        pred = as_imm_state(hypothesis.prediction, getattr(hypothesis.prediction, "n_modes", 1))
        c = pred.mode_probabilities
        if not hypothesis:  # missed detection: no measurement, the modes and probabilities stay predicted
            return IMMStateUpdate.from_modes(pred.mode_means, pred.mode_covars, c, timestamp=pred.timestamp,
                                             hypothesis=hypothesis)
        model = self._model(hypothesis.measurement.measurement_model)
        if _linear_kalman(self.updater, model):
            x, P, nu, S = self._update_linear(pred, hypothesis.measurement, model)
        else:
            x, P, nu, S = self._update_modes(pred, hypothesis.measurement, **kwargs)
        mu, log_total = imm_mode_update(c, gaussian_loglik(nu, S, np.linalg.inv(S)))
        return IMMStateUpdate.from_modes(x, P, mu, timestamp=hypothesis.measurement.timestamp, hypothesis=hypothesis,
                                         log_likelihood=float(log_total))

    def _update_modes(self, pred: IMMState, measurement, **kwargs):
        """Each mode through ``updater.update``; returns x (r, n), P (r, n, n), nu (r, k), S (r, k, k)."""
        x, P, nu, S = [], [], [], []
        for s in pred.mode_states:
            hyp = SingleHypothesis(GaussianStatePrediction(s.state_vector, s.covar, timestamp=s.timestamp),
                                   measurement)
            post = self.updater.update(hyp, **kwargs)
            x.append(np.asarray(post.state_vector, dtype=float)[:, 0])
            P.append(np.asarray(post.covar, dtype=float))
            nu.append(innovations(measurement, np.asarray(hyp.measurement_prediction.state_vector).ravel()[None])[0])
            S.append(np.asarray(hyp.measurement_prediction.covar, dtype=float))
        return np.stack(x), np.stack(P), np.stack(nu), np.stack(S)

    def _update_linear(self, pred: IMMState, measurement, model):
        """KalmanUpdater's equations for all modes at once: K = P H^T S^-1, x+ = x- + K nu,
        P+ = P- - K S K^T (or the Joseph form with ``use_joseph_cov``)."""
        z_hat, S, cross = mode_measurement_moments(self.updater, pred, model)
        K = cross @ np.linalg.inv(S)
        nu = innovations(measurement, z_hat)
        x = pred.mode_means + np.einsum("jnk,jk->jn", K, nu)
        if self.updater.use_joseph_cov:
            H, R = np.asarray(model.matrix(), float), np.asarray(model.covar(), float)
            A = np.eye(pred.ndim) - K @ H
            P = A @ pred.mode_covars @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2)
        else:
            P = pred.mode_covars - K @ S @ np.swapaxes(K, -1, -2)
        if self.updater.force_symmetric_covariance:
            P = (P + np.swapaxes(P, -1, -2)) / 2
        return x, P, nu, S



_MOVED_TO_IMM_IPDA = ("IMMIPDAHypotheses", "IMMIPDAHypothesiser", "IMMIPDAUpdater", "IMMIPDATracker",
                      "imm_ipda_tracker", "track_existence", "track_likelihoods", "detection_moments")


def __getattr__(name: str):
    """The IMM-IPDA names, now in stonesoup/imm_ipda.py, still importable from here (lazily: imm_ipda imports us)."""
    if name in _MOVED_TO_IMM_IPDA:
        from sonartrack.stonesoup import imm_ipda

        return getattr(imm_ipda, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
