"""IMM-IPDA (paper P4) as Stone Soup components: hypothesiser, updater and tracker on stonesoup/imm.py's IMM.

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

import numpy as np
from stonesoup.base import Property
from stonesoup.hypothesiser import Hypothesiser
from stonesoup.models.base import LinearModel
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.reader import DetectionReader
from stonesoup.tracker import Tracker
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis, SingleProbabilityHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.track import Track
from stonesoup.updater.kalman import KalmanUpdater

from sonartrack.association.gating import gate_threshold
from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.association.likelihood import Likelihoods, gaussian_log_ratio, mahalanobis2
from sonartrack.association.pda import pda_mixture_update, pda_weights
from sonartrack.core.errors import InputError, require
from sonartrack.core.gaussian import inv_and_logdet
from sonartrack.filters.imm import imm_mode_update
from sonartrack.stonesoup.defaults import tracker_default
from sonartrack.stonesoup.imm import (
    IMMPredictor,
    IMMState,
    IMMStateUpdate,
    IMMUpdater,
    _linear_kalman,
    current_state,
    innovations,
    mode_measurement_moments,
)
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE, existence_of
from sonartrack.tracking.settings import PositionTrackerSettings


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
