"""Gaussian IMM and IMM-IPDA (paper P4) as Stone Soup components.

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

**IMM-IPDA** (Musicki, Evans, Stankovic 1994; Musicki, Suvorova, Challa 2004; Park, Song, Lee 2017 =
paper P4, Fig. 3 and eqs. 7-21): a PDA in every mode with the track's existence probability P(E), kept
in the track's metadata under :data:`EXISTENCE` (and on the update as ``existence_probability``)::

    existence      P(E)- = p11 P(E) + p21 (1 - P(E))                              (association/ipda.py)
    gate           z_m validated when nu_rm^T S_rm^-1 nu_rm < gamma in any mode r
    mode ratio     Lambda_r = 1 - P_D P_G + P_D sum_m N(nu_rm; 0, S_rm) / rho
    weights        beta_r0 = (1 - P_D P_G) / Lambda_r,   beta_rm = P_D N(nu_rm; 0, S_rm) / (rho Lambda_r)
    mode PDA       x_r = x-_r + sum_m beta_rm K_rm nu_rm,
                   P_r = beta_r0 P-_r + sum_m beta_rm (P-_r - K_rm S_rm K_rm^T + dx_rm dx_rm^T) - dx_r dx_r^T
    mode update    mu_r = c_r Lambda_r / Lambda,   Lambda = sum_r c_r Lambda_r   (= 1 - delta)
    existence      P(E) = Lambda P(E)- / (1 - P(E)- + Lambda P(E)-)

The weights and the mode PDA are association/pda.py's (``pda_weights``, ``pda_mixture_update`` with each
detection's own cross-covariance P-_r H_m^T): one implementation of P4's eqs. 13-20 in sonartrack.

:class:`IMMIPDATracker` runs it with one-point initiation and existence-threshold confirmation and deletion,
the same steps as sonartrack's ``tracking.configurations.position_tracker``; :func:`imm_ipda_tracker` builds it
from that tracker's settings with Stone Soup's constant-velocity models and Kalman filters in the modes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property
from stonesoup.hypothesiser import Hypothesiser
from stonesoup.models.base import LinearModel
from stonesoup.models.measurement import MeasurementModel
from stonesoup.models.transition import TransitionModel
from stonesoup.predictor import Predictor
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.reader import DetectionReader
from stonesoup.tracker import Tracker
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis, SingleProbabilityHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import (
    GaussianMeasurementPrediction,
    GaussianStatePrediction,
    MeasurementPrediction,
    Prediction,
)
from stonesoup.types.state import GaussianState, State, StateMutableSequence
from stonesoup.types.track import Track
from stonesoup.types.update import Update
from stonesoup.updater import Updater
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater

from sonartrack.association.gating import gate_threshold
from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.association.likelihood import Likelihoods, gaussian_log_ratio, mahalanobis2
from sonartrack.association.pda import pda_mixture_update, pda_weights
from sonartrack.core.errors import InputError, require
from sonartrack.core.gaussian import inv_and_logdet
from sonartrack.filters.ekf import gaussian_loglik
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update, validate_transition_matrix
from sonartrack.stonesoup.defaults import tracker_default
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE, existence_of
from sonartrack.tracking.settings import PositionTrackerSettings


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



# ---------------------------------------------------------------------------------------------------------
# IMM-IPDA (paper P4)


def track_existence(track) -> float:
    """P(E) of a track after its last scan: its metadata's ``EXISTENCE`` entry (stonesoup/tracks.py), else its
    last state's ``existence_probability``.

    Parameters
    ----------
    track : Track or State
        The track (or a state).

    Returns
    -------
    float
        The existence probability P(E) in [0, 1].
    """
    return existence_of(track, getattr(current_state(track), "existence_probability", None))


def track_likelihoods(log_ratio, nu, S_inv, pd: float, pg: float) -> Likelihoods:
    """One track's gated detections in association/likelihood.py's layout (n = 1 track, g gated pairs), the input
    of association/pda.py's weights and mixture (P4 eqs. 13-20).

    Parameters
    ----------
    log_ratio : ndarray, shape (r, g)
        log N(nu_rm; 0, S_rm) - log rho per mode r and gated detection m.
    nu : ndarray, shape (r, g, k)
        Innovations.
    S_inv : ndarray, shape (r, g, k, k)
        Inverse innovation covariances.
    pd : float
        Probability of detection P_D.
    pg : float
        Gate probability P_G (the miss term is 1 - P_D P_G).

    Returns
    -------
    Likelihoods
        One track, g pairs, with the modes as the last axis of ``pair_log_ratio`` (g, r).
    """
    g = log_ratio.shape[1]
    return Likelihoods(pair_log_ratio=log_ratio.T, gated=np.ones((1, g), bool), pd=float(pd), miss=1.0 - pd * pg,
                       pair_track=np.zeros(g, dtype=np.intp), pair_meas=np.arange(g), nu=np.swapaxes(nu, 0, 1),
                       S_inv=np.swapaxes(S_inv, 0, 1), dense_log_ratio=log_ratio[None])


def detection_moments(imm_updater: IMMUpdater, state: IMMState, detections):
    """Innovations nu (r, m, k), their covariances S (r, m, k, k) and cross-covariances P H^T (r, m, n, k) of
    every mode against every detection, by the IMM updater's mode updater (all detections must measure k entries).

    Parameters
    ----------
    imm_updater : IMMUpdater
        Gives the mode updater and the measurement model of a detection without its own.
    state : IMMState
        The predicted IMM state (r modes, n entries).
    detections : sequence of Detection
        The scan's m detections.

    Returns
    -------
    nu : ndarray, shape (r, m, k)
        Innovations.
    S : ndarray, shape (r, m, k, k)
        Innovation covariances H P_r H^T + R.
    cross : ndarray, shape (r, m, n, k)
        Cross-covariances P_r H^T.
    """
    updater = imm_updater.updater
    models = [imm_updater._model(d.measurement_model) for d in detections]
    if all(_linear_kalman(updater, mm) for mm in models):
        H = np.stack([np.asarray(mm.matrix(), float) for mm in models])  # (m, k, n)
        R = np.stack([np.asarray(mm.covar(), float) for mm in models])
        z = np.stack([np.asarray(d.state_vector, float)[:, 0] for d in detections])
        cross = np.einsum("rab,mkb->rmak", state.mode_covars, H)
        S = np.einsum("mka,rmal->rmkl", H, cross) + R[None]
        return z[None] - np.einsum("mkn,rn->rmk", H, state.mode_means), S, cross
    per = [mode_measurement_moments(updater, state, mm) for mm in models]
    if len({p[0].shape for p in per}) > 1:
        raise InputError("IMM-IPDA needs detections that all measure the same number of entries")
    nu = np.stack([innovations(d, p[0]) for d, p in zip(detections, per, strict=True)], axis=1)
    return nu, np.stack([p[1] for p in per], axis=1), np.stack([p[2] for p in per], axis=1)


class IMMIPDAHypotheses(MultipleHypothesis):
    """IMM-IPDA hypotheses of one track: missed detection first, then the gated detections.

    Each single hypothesis' ``probability`` is its marginal over the modes, beta_m = sum_r mu_r beta_rm (mu_r the
    posterior mode probabilities); the per-mode weights and moments the update needs are kept as arrays."""

    existence_prediction: float = Property(default=None, doc="P(E)k|k-1, the predicted existence probability")
    log_mode_likelihood_ratios: np.ndarray = Property(default=None, doc="log Lambda_r (r,)")
    mode_weights: np.ndarray = Property(default=None, doc="(r, 1 + g): beta_r0, then beta_rm per gated detection")
    likelihoods: Likelihoods = Property(
        default=None, doc="The gated detections' nu_rm, S_rm^-1 and log ratios (association/likelihood.py, one track)")
    innovations: np.ndarray = Property(default=None, doc="nu_rm (r, g, k)")
    innovation_covars: np.ndarray = Property(default=None, doc="S_rm (r, g, k, k)")
    cross_covars: np.ndarray = Property(default=None, doc="P-_r H_m^T (r, g, n, k)")


class IMMIPDAHypothesiser(Hypothesiser):
    """IMM-IPDA hypotheses of a track (module doc; P4 Fig. 3): IMM prediction, existence prediction, the union
    of the modes' chi-square gates, and the PDA weights of every mode. Detections are one scan at ``timestamp``.
    Defaults are the declarations of sonartrack's tracker (tracking/settings.py: PositionTrackerSettings, paper
    P4's values; read by stonesoup/defaults.py). The weights and the mode updates are association/pda.py's."""

    predictor: IMMPredictor = Property(doc="IMM predictor")
    updater: IMMUpdater = Property(doc="IMM updater: its mode updater gives the measurement predictions")
    clutter_spatial_density: float = Property(doc="Clutter density rho (per unit measurement volume, e.g. 1/m^2)")
    prob_detect: float = Property(default=tracker_default("pd"), doc="Probability of detection P_D")
    prob_gate: float = Property(default=tracker_default("gate_probability"),
                                doc="Gate probability P_G (sets the chi-square gate gamma)")
    prob_survive: float = Property(default=tracker_default("p_survive"),
                                   doc="Existence Markov chain p11: the target survives a scan")
    prob_birth: float = Property(default=tracker_default("p_birth"),
                                 doc="Existence Markov chain p21: a non-existing target appears")

    def hypothesise(self, track, detections, timestamp, **kwargs) -> IMMIPDAHypotheses:
        """IMM-IPDA hypotheses of one track against one scan (class doc).

        Parameters
        ----------
        track : Track
            The track (its last state the prior; its existence from :func:`track_existence`).
        detections : iterable of Detection
            The scan's detections, all at ``timestamp``.
        timestamp : datetime.datetime
            Time of the scan.
        **kwargs
            Passed to the IMM predictor.

        Returns
        -------
        IMMIPDAHypotheses
            Missed detection first, then the detections inside any mode's gate, each with its marginal weight
            beta_m = sum_r mu_r beta_rm; the predicted existence, log Lambda_r, the per-mode weights and moments
            attached.
        """
        detections = list(detections)
        prediction = self.predictor.predict(track, timestamp=timestamp, **kwargs)
        e_pred = float(existence_predict(track_existence(track), self.prob_survive, self.prob_birth))
        r, n = prediction.mode_means.shape
        if detections:
            nu, S, cross = detection_moments(self.updater, prediction, detections)
            k = nu.shape[-1]
            S_inv, logdet = inv_and_logdet(S)
            d2 = mahalanobis2(nu, S_inv)
            gated = np.nonzero((d2 < gate_threshold(self.prob_gate, k)).any(axis=0))[0]
            log_ratio = gaussian_log_ratio(logdet, d2, k, np.log(self.clutter_spatial_density))[:, gated]
            nu, S, S_inv, cross = nu[:, gated], S[:, gated], S_inv[:, gated], cross[:, gated]
        else:
            gated, log_ratio = np.zeros(0, int), np.zeros((r, 0))
            nu, S, cross = np.zeros((r, 0, 0)), np.zeros((r, 0, 0, 0)), np.zeros((r, 0, n, 0))
            S_inv = S
        lik = track_likelihoods(log_ratio, nu, S_inv, self.prob_detect, self.prob_gate)
        w = pda_weights(lik)  # association/pda.py: beta0 (1, r), beta (1, r, g), log Lambda_r (1, r)
        weights, log_lam = np.concatenate([w.beta0[0, :, None], w.beta[0]], axis=1), w.log_lambda[0]
        marginal = imm_mode_update(prediction.mode_probabilities, log_lam)[0] @ weights
        hyps = [SingleProbabilityHypothesis(prediction, MissedDetection(timestamp=timestamp), Probability(marginal[0]))]
        hyps += [SingleProbabilityHypothesis(prediction, detections[m], Probability(b))
                 for m, b in zip(gated, marginal[1:], strict=True)]
        return IMMIPDAHypotheses(hyps, existence_prediction=e_pred, log_mode_likelihood_ratios=log_lam,
                                 mode_weights=weights, likelihoods=lik, innovations=nu, innovation_covars=S,
                                 cross_covars=cross)


class IMMIPDAUpdater(IMMUpdater):
    """IMM-IPDA update from :class:`IMMIPDAHypotheses` (module doc): PDA in every mode, mode probabilities
    mu_r = c_r Lambda_r / Lambda and existence P(E) = Lambda P(E)- / (1 - P(E)- + Lambda P(E)-). Any other
    hypothesis goes to :meth:`IMMUpdater.update`."""

    def update(self, hypotheses, **kwargs) -> IMMStateUpdate:
        """IMM-IPDA update of one track from its hypotheses (class doc); others go to :meth:`IMMUpdater.update`.

        Parameters
        ----------
        hypotheses : IMMIPDAHypotheses or SingleHypothesis
            From :meth:`IMMIPDAHypothesiser.hypothesise` (or a single hypothesis for the plain IMM update).
        **kwargs
            Passed to :meth:`IMMUpdater.update` for a single hypothesis.

        Returns
        -------
        IMMStateUpdate
            The mode PDA updates, mu_r = c_r Lambda_r / Lambda, their combination, ``existence_probability`` P(E) and
            ``log_likelihood`` = log Lambda.
        """
        if not isinstance(hypotheses, IMMIPDAHypotheses):
            return super().update(hypotheses, **kwargs)
        pred = hypotheses.single_hypotheses[0].prediction
        w = hypotheses.mode_weights  # association/pda.py's mixture of the mode's Kalman updates (P4 eqs. 19-20)
        x, P = pda_mixture_update(pred.mode_means[None], pred.mode_covars[None], hypotheses.likelihoods, w[None, :, 0],
                                  w[None, :, 1:], cross=np.swapaxes(hypotheses.cross_covars, 0, 1))
        x, P = x[0], P[0]
        mu, log_total = imm_mode_update(pred.mode_probabilities, hypotheses.log_mode_likelihood_ratios)
        existence = float(existence_update(hypotheses.existence_prediction, np.exp(log_total)))
        return IMMStateUpdate.from_modes(x, P, mu, timestamp=pred.timestamp, hypothesis=hypotheses,
                                         existence_probability=existence, log_likelihood=float(log_total))


class IMMIPDATracker(Tracker):
    """Multi-target IMM-IPDA tracker (paper P4) on Stone Soup detections and tracks.

    One scan, the steps of sonartrack's ``tracking.configurations.position_tracker`` (tracking/multi_target.py):
    every live track is hypothesised and updated on its own (:class:`IMMIPDAHypothesiser`,
    :class:`IMMIPDAUpdater`); a track is confirmed once P(E) > ``confirm_threshold`` and deleted when
    P(E) < ``terminate_threshold``; every detection that no track gated starts a tentative track (one-point
    initiation: the measured state entries at the detection with its covariance R, every other entry zero
    with variance ``velocity_std^2``; P(E) = ``initial_existence``; equal mode probabilities). Detections
    need a linear measurement model with a ``mapping`` (e.g. Stone Soup's LinearGaussian).
    Track metadata: :data:`EXISTENCE` (P(E)) and :data:`CONFIRMED`. Track ids count up from "1".
    """

    hypothesiser: IMMIPDAHypothesiser = Property(doc="IMM-IPDA hypothesiser")
    updater: IMMIPDAUpdater = Property(doc="IMM-IPDA updater")
    detector: DetectionReader = Property(default=None, doc="Detector to iterate over (or call update_tracker)")
    velocity_std: float = Property(default=tracker_default("init_velocity_std_mps"),
                                   doc="One-point initiation: standard deviation of the zero-mean prior of the "
                                       "unmeasured state entries (m/s for CV)")
    initial_existence: float = Property(default=tracker_default("initial_existence"),
                                        doc="P(E) of a new one-point track")
    confirm_threshold: float = Property(default=tracker_default("confirm_threshold"),
                                        doc="Confirm a track when P(E) exceeds this")
    terminate_threshold: float = Property(default=tracker_default("terminate_threshold"),
                                          doc="Delete a track when P(E) falls below this")
    max_tracks: int = Property(default=tracker_default("max_tracks"),
                               doc="Most live tracks; detections beyond it start no track")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._live: list[Track] = []
        self._detector_iter = None
        self._next_id = 1

    @property
    def tracks(self) -> set[Track]:
        """The live tracks (tentative and confirmed) as a set."""
        return set(self._live)

    @property
    def live_tracks(self) -> list[Track]:
        """The live tracks in the order they were started."""
        return list(self._live)

    @property
    def confirmed_tracks(self) -> set[Track]:
        """The live tracks confirmed so far (metadata :data:`CONFIRMED` true)."""
        return {t for t in self._live if t.metadata.get(CONFIRMED)}

    def __iter__(self):
        if self.detector is None:
            raise InputError("IMMIPDATracker has no detector: give one, or call update_tracker(time, detections)")
        self._detector_iter = iter(self.detector)
        return self

    def __next__(self):
        time, detections = next(self._detector_iter)
        return self.update_tracker(time, detections)

    def update_tracker(self, time, detections):
        """Process one scan (detections in a list keep their order for initiation); returns (time, tracks).

        Parameters
        ----------
        time : datetime.datetime
            Time of the scan.
        detections : iterable of Detection
            The scan's detections (linear measurement models with a ``mapping`` to start tracks).

        Returns
        -------
        time : datetime.datetime
            ``time`` unchanged.
        tracks : set of Track
            The live tracks after the update, confirmation, deletion and initiation.
        """
        detections = list(detections)
        used = self._update_tracks(time, detections)
        for track in self._live:
            if track.metadata[EXISTENCE] > self.confirm_threshold:
                track.metadata[CONFIRMED] = True
        self._live = [t for t in self._live if t.metadata[EXISTENCE] >= self.terminate_threshold]
        room = max(0, self.max_tracks - len(self._live))
        for detection in [d for d, u in zip(detections, used, strict=True) if not u][:room]:
            self._live.append(self._one_point_track(detection, time))
        return time, self.tracks

    def _update_tracks(self, time, detections) -> np.ndarray:
        """Hypothesise and update every live track; returns which detections some track gated."""
        index = {id(d): i for i, d in enumerate(detections)}
        used = np.zeros(len(detections), bool)
        for track in self._live:
            hypotheses = self.hypothesiser.hypothesise(track, detections, time)
            update = self.updater.update(hypotheses)
            track.append(update)
            track.metadata[EXISTENCE] = update.existence_probability
            used[[index[id(h.measurement)] for h in hypotheses if h]] = True
        return used

    def _one_point_track(self, detection, time) -> Track:
        """A tentative track at the detection (class doc)."""
        model = self.updater._model(detection.measurement_model)
        require(isinstance(model, LinearModel) and hasattr(model, "mapping"),
                "IMMIPDATracker starts tracks from detections with a linear model with a mapping (LinearGaussian)")
        idx = list(model.mapping)
        x = np.zeros(model.ndim_state)
        x[idx] = np.asarray(detection.state_vector, float)[:, 0]
        P = np.eye(model.ndim_state) * self.velocity_std**2
        P[np.ix_(idx, idx)] = np.asarray(model.covar(), float)
        r = len(self.hypothesiser.predictor.predictors)
        state = IMMStateUpdate.from_modes(np.repeat(x[None], r, 0), np.repeat(P[None], r, 0), np.full(r, 1.0 / r),
                                          timestamp=time, hypothesis=SingleHypothesis(None, detection),
                                          existence_probability=self.initial_existence)
        track = Track([state], id=str(self._next_id),
                      init_metadata={EXISTENCE: self.initial_existence, CONFIRMED: False})
        self._next_id += 1
        return track


def imm_ipda_tracker(settings: PositionTrackerSettings | None = None, measurement_model=None,
                     detector=None) -> IMMIPDATracker:
    """Paper P4's IMM-IPDA position tracker from Stone Soup parts, with the settings of sonartrack's
    ``tracking.configurations.position_tracker`` (tracking/settings.py: PositionTrackerSettings, P4's defaults).

    Mode j: ``KalmanPredictor(CombinedLinearGaussianTransitionModel([ConstantVelocity(q_j)] * 2))`` -- Stone Soup's
    state order [x, vx, y, vy]; every mode updates with ``KalmanUpdater(measurement_model)`` (None: each detection
    brings its own model, e.g. ``LinearGaussian(4, (0, 2), R)`` with its covariance R, as P4's contacts do).

    Parameters
    ----------
    settings : PositionTrackerSettings, optional
        Mode noise intensities q (m^2/s^3), transition matrix, P_D, P_G, clutter density (1/m^2), existence chain,
        thresholds, initial velocity standard deviation (m/s), most tracks; default the library defaults.
    measurement_model : MeasurementModel, optional
        Model of the Kalman updater; None: each detection's own.
    detector : DetectionReader, optional
        Scans to iterate over (else call ``update_tracker``).

    Returns
    -------
    IMMIPDATracker
        The tracker with its hypothesiser and updater.
    """
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity

    s = settings or PositionTrackerSettings()
    predictor = IMMPredictor(
        predictors=[KalmanPredictor(CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)]))
                    for q in s.q],
        transition_probabilities=s.transition_matrix())
    updater = IMMIPDAUpdater(updater=KalmanUpdater(measurement_model))
    hypothesiser = IMMIPDAHypothesiser(predictor=predictor, updater=updater,
                                       clutter_spatial_density=s.clutter_density_per_m2, prob_detect=s.pd,
                                       prob_gate=s.gate_probability, prob_survive=s.p_survive, prob_birth=s.p_birth)
    return IMMIPDATracker(hypothesiser=hypothesiser, updater=updater, detector=detector,
                          velocity_std=s.init_velocity_std_mps, initial_existence=s.initial_existence,
                          confirm_threshold=s.confirm_threshold, terminate_threshold=s.terminate_threshold,
                          max_tracks=s.max_tracks)
