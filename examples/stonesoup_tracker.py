"""A Stone Soup tracker with sonartrack's components: IMM-IPDA (paper P4) and exact JPDA.

Part 1 -- IMM-IPDA: two targets in uniform clutter, one running straight and one making a turn; tracks
start on single detections and are confirmed and deleted by their existence probability. Every part is a
Stone Soup component: Stone Soup's constant-velocity models, KalmanPredictor and KalmanUpdater as the mode
filters, sonartrack's IMMPredictor / IMMIPDAHypothesiser / IMMIPDAUpdater / IMMIPDATracker around them
(settings: paper P4's tracker, sonartrack.tracking.settings.PositionTrackerSettings).

Part 2 -- JPDA: two targets crossing, tracked by Stone Soup's PDAHypothesiser and PDAUpdater with sonartrack's
exact JPDA (a drop-in for Stone Soup's JPDA / JPDAwithEHM2) as the data associator.

Run: ``python examples/stonesoup_tracker.py`` (fixed seed, a few seconds); prints one line.
"""

from __future__ import annotations

import datetime
import time

import numpy as np
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Clutter, Detection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.updater.kalman import KalmanUpdater
from stonesoup.updater.probability import PDAUpdater

from sonartrack.stonesoup import JPDA
from sonartrack.stonesoup.imm import IMMIPDAHypothesiser, IMMIPDATracker, IMMIPDAUpdater, IMMPredictor
from sonartrack.tracking.settings import PositionTrackerSettings

T0 = datetime.datetime(2026, 1, 1)
SCAN_S, SIGMA_M, HALF_SIDE_M = 10.0, 30.0, 2500.0
TURN = (15, 40)  # scans of target 1's turn


def cv(q: float) -> CombinedLinearGaussianTransitionModel:
    """Stone Soup's 2-D constant velocity, state [x, vx, y, vy], intensity q (m^2/s^3)."""
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


def truths(n_scans: int) -> np.ndarray:
    """Positions (n_scans, 2 targets, 2): target 0 straight at 8.5 m/s, target 1 turning 0.5 deg/s from scan 15 to 40
    (0.075 m/s^2: the large-q mode's size of manoeuvre)."""
    out = np.zeros((n_scans, 2, 2))
    pos = np.array([[-1500.0, -1000.0], [1500.0, -1500.0]])
    vel = np.array([[8.0, 3.0], [-3.0, 8.0]])
    for k in range(n_scans):
        if TURN[0] <= k < TURN[1]:
            a = np.radians(0.5 * SCAN_S)
            vel[1] = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) @ vel[1]
        pos = pos + SCAN_S * vel
        out[k] = pos
    return out


def scans(truth: np.ndarray, pd: float, clutter_per_m2: float, rng):
    """Detections per scan: each target seen with probability pd, plus uniform clutter."""
    model = LinearGaussian(4, (0, 2), np.eye(2) * SIGMA_M**2)
    area = (2 * HALF_SIDE_M) ** 2
    for k, positions in enumerate(truth):
        when = T0 + datetime.timedelta(seconds=SCAN_S * (k + 1))
        dets = [Detection((p + rng.normal(0, SIGMA_M, 2)).reshape(2, 1), timestamp=when, measurement_model=model)
                for p in positions if rng.random() < pd]
        dets += [Clutter(rng.uniform(-HALF_SIDE_M, HALF_SIDE_M, (2, 1)), timestamp=when, measurement_model=model)
                 for _ in range(rng.poisson(clutter_per_m2 * area))]
        yield when, dets


def imm_ipda_tracker(s: PositionTrackerSettings) -> IMMIPDATracker:
    """Paper P4's IMM-IPDA as Stone Soup components (one Stone Soup KalmanPredictor per mode)."""
    predictor = IMMPredictor(predictors=[KalmanPredictor(cv(q)) for q in s.q],
                             transition_probabilities=s.transition_matrix())
    updater = IMMIPDAUpdater(updater=KalmanUpdater(None))  # the detections carry their measurement model
    hypothesiser = IMMIPDAHypothesiser(predictor=predictor, updater=updater,
                                       clutter_spatial_density=s.clutter_density_per_m2, prob_detect=s.pd,
                                       prob_gate=s.gate_probability, prob_survive=s.p_survive, prob_birth=s.p_birth)
    return IMMIPDATracker(hypothesiser=hypothesiser, updater=updater, velocity_std=s.init_velocity_std_mps,
                          initial_existence=s.initial_existence, confirm_threshold=s.confirm_threshold,
                          terminate_threshold=s.terminate_threshold)


def run_imm_ipda(rng) -> str:
    s = PositionTrackerSettings(pd=0.9, init_velocity_std_mps=10.0)
    truth = truths(50)
    tracker = imm_ipda_tracker(s)
    large_q = {"before": [], "in": []}  # large-q mode probability of confirmed tracks on the turning target
    for k, (when, dets) in enumerate(scans(truth, s.pd, s.clutter_density_per_m2, rng)):
        tracker.update_tracker(when, dets)
        phase = "before" if k < TURN[0] else "in" if TURN[0] + 5 <= k < TURN[1] else None
        if phase:
            large_q[phase] += [t.state.mode_probabilities[1] for t in tracker.confirmed_tracks
                               if _distance(t, truth[k, 1]) < 150.0]
    on_target = [t for t in tracker.confirmed_tracks if min(_distance(t, p) for p in truth[-1]) < 150.0]
    held = sum(any(_distance(t, p) < 150.0 for t in on_target) for p in truth[-1])
    false = len(tracker.confirmed_tracks) - len(on_target)
    return (f"IMM-IPDA: {held}/2 targets held ({len(on_target)} confirmed tracks on them, {false} false), "
            f"large-q mode {np.mean(large_q['before']):.2f} before / {np.mean(large_q['in']):.2f} in the turn")


def _distance(track, position) -> float:
    return float(np.hypot(*(np.asarray(track.state.state_vector, float)[[0, 2], 0] - position)))


def run_jpda(rng) -> str:
    """Two targets crossing at the origin, tracks started on the truth (as Stone Soup's JPDA tutorial)."""
    trans, model = cv(0.05), LinearGaussian(4, (0, 2), np.eye(2) * 10.0**2)
    starts = [np.array([-400.0, 10.0, -300.0, 7.5]), np.array([-400.0, 10.0, 300.0, -7.5])]
    tracks = [Track([GaussianState(x.reshape(-1, 1), np.diag([100.0, 4.0, 100.0, 4.0]), timestamp=T0)]) for x in starts]
    hypothesiser = PDAHypothesiser(KalmanPredictor(trans), KalmanUpdater(model), clutter_spatial_density=1e-5,
                                   prob_detect=0.9, prob_gate=0.99)
    associator, updater = JPDA(hypothesiser=hypothesiser), PDAUpdater(model)
    for k in range(1, 81):
        when = T0 + datetime.timedelta(seconds=k)
        dets = {Detection((x[[0, 2]] + k * x[[1, 3]] + rng.normal(0, 10.0, 2)).reshape(2, 1), timestamp=when,
                          measurement_model=model) for x in starts if rng.random() < 0.9}
        dets |= {Clutter(rng.uniform(-500, 500, (2, 1)), timestamp=when, measurement_model=model)
                 for _ in range(rng.poisson(5))}
        for track, multihypothesis in associator.associate(tracks, dets, when).items():
            track.append(updater.update(multihypothesis))
    ends = [x[[0, 2]] + 80 * x[[1, 3]] for x in starts]
    errors = [_distance(t, p) for t, p in zip(tracks, ends, strict=True)]
    return f"JPDA: {sum(e < 50.0 for e in errors)}/2 crossing targets held, final error {max(errors):.0f} m"


if __name__ == "__main__":
    start = time.perf_counter()
    rng = np.random.default_rng(2026)
    line = f"{run_imm_ipda(rng)}; {run_jpda(rng)}"
    print(f"{line} ({time.perf_counter() - start:.1f} s)")
