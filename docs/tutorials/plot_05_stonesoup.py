"""
sonartrack parts inside a Stone Soup tracker
============================================

``sonartrack.stonesoup`` (``pip install sonartrack[stonesoup]``) offers our estimators as Stone Soup components:
they subclass Stone Soup's bases and take and return its types, so they drop into a Stone Soup tracker in place
of its own. Here: the exact JPDA as the data associator of a Stone Soup JPDA tracker (one changed import),
paper P4's IMM-IPDA built from Stone Soup's constant-velocity models and Kalman filters, in clutter, and a
bearings-only initiator in Stone Soup's own bearing-only example.
"""

# %%
# 1. Exact JPDA in a Stone Soup JPDA tracker
# ------------------------------------------
# Two targets crossing; Stone Soup's ``PDAHypothesiser`` and ``PDAUpdater``, and sonartrack's ``JPDA`` (a
# drop-in for Stone Soup's ``JPDA`` / ``JPDAwithEHM2``: the same hypotheses and weights, exact marginals from our
# compiled forward-backward pass).
import datetime

import matplotlib.pyplot as plt
import numpy as np
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.updater.probability import PDAUpdater

from sonartrack.stonesoup import JPDA, imm_ipda_tracker  # was: from stonesoup.dataassociator.probability import JPDA
from sonartrack.tracking.settings import PositionTrackerSettings

transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05), ConstantVelocity(0.05)])
measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
hypothesiser = PDAHypothesiser(KalmanPredictor(transition), PDAUpdater(measurement),
                               clutter_spatial_density=1e-3, prob_detect=0.9)
associator, updater = JPDA(hypothesiser), PDAUpdater(measurement)
t0 = datetime.datetime(2026, 1, 1)
tracks = [Track([GaussianState([[0], [1], [0], [1]], np.diag([1, 0.5, 1, 0.5]), timestamp=t0)]),
          Track([GaussianState([[0], [1], [20], [-1]], np.diag([1, 0.5, 1, 0.5]), timestamp=t0)])]
rng = np.random.default_rng(1)
measured = []
for k in range(1, 21):  # two targets crossing at k = 10
    when = t0 + datetime.timedelta(seconds=k)
    detections = {Detection((p + rng.normal(0, 1, 2)).reshape(-1, 1), timestamp=when, measurement_model=measurement)
                  for p in (np.array([k, k]), np.array([k, 20 - k]))}
    measured += [d.state_vector.ravel() for d in detections]
    for track, hypotheses in associator.associate(set(tracks), detections, when).items():
        track.append(updater.update(hypotheses))
for track, truth_end in zip(tracks, ([20, 20], [20, 0]), strict=True):
    print("track ends at", np.round(track.state_vector[[0, 2]].ravel(), 1), "m; its target at", truth_end, "m")

# %%
# Each track stays on its own target through the crossing.
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot(*np.array(measured).T, "k.", ms=3, label="detections")
for i, track in enumerate(tracks):
    xy = np.array([[s.state_vector[0, 0], s.state_vector[2, 0]] for s in track])
    ax.plot(xy[:, 0], xy[:, 1], "-", label=f"track {i}")
ax.set(xlabel="x (m)", ylabel="y (m)", title="Stone Soup PDA filters, sonartrack's exact JPDA")
ax.legend()

# %%
# 2. Paper P4's IMM-IPDA from Stone Soup parts
# --------------------------------------------
# ``imm_ipda_tracker`` builds a Stone Soup tracker from our IMM predictor, IPDA hypothesiser and updater around
# Stone Soup's constant-velocity models and Kalman filters, with the settings of paper P4's tracker: tracks start
# on single detections and are confirmed and deleted by their existence probability. A target at 3 m/s, a scan
# every 30 s, P_D 0.8, and 10 clutter points a scan over a 3.2 km square.
tracker = imm_ipda_tracker(PositionTrackerSettings(q=[1e-4, 0.05]),
                           LinearGaussian(4, (0, 2), np.eye(2) * 30.0**2))
rng = np.random.default_rng(1)
clutter, truth = [], []
for k in range(30):
    when = t0 + datetime.timedelta(seconds=30 * k)
    z = list(rng.uniform(-1600, 1600, (10, 2)))
    clutter += z
    truth.append([90.0 * k - 1300.0, 0.0])
    if rng.random() < 0.8:
        z.append(np.array(truth[-1]) + rng.normal(0, 30, 2))
    tracker.update_tracker(when, [Detection(np.reshape(zi, (2, 1)), timestamp=when) for zi in z])
confirmed = sorted(tracker.confirmed_tracks, key=lambda track: -track.metadata["existence_probability"])
for track in confirmed:
    print(f"confirmed track at {track.state.state_vector[[0, 2], 0].round()} m, "
          f"P(E) {track.metadata['existence_probability']:.3f}, modes {track.state.mode_probabilities.round(2)}")

# %%
# IPDA tracks are independent: a clutter point next to the target can start a second track that then follows the
# same target (paper P4 counts such tracks as confirmed false tracks; there is no track merging yet), so the
# target is the track with the highest existence probability.
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot(*np.array(clutter).T, ".", color="0.7", ms=3, label="clutter")
ax.plot(*np.array(truth).T, "g--", label="target (truth)")
for i, track in enumerate(confirmed):  # the most probable first
    xy = np.array([[s.state_vector[0, 0], s.state_vector[2, 0]] for s in track])
    label = "most probable track" if i == 0 else "other confirmed tracks" if i == 1 else None
    ax.plot(xy[:, 0], xy[:, 1], "b-" if i == 0 else "c-", lw=2.0 if i == 0 else 0.8, label=label)
ax.set(xlabel="x (m)", ylabel="y (m)", title="IMM-IPDA (paper P4) from Stone Soup parts")
ax.legend()

# %%
# 3. A bearings-only initiator in Stone Soup's bearing-only example
# -----------------------------------------------------------------
# Stone Soup's bearing-only example (docs/examples/filters/bearing_only_example.py) says Stone Soup has no
# bearings-only initiator and starts its EKF tracker from the target's true initial state. Here is its scene
# (sensor from (0, 0) m at (-5, -7) m/s, target from (50, 50) m at rest with q = 1 m^2/s^3, bearings
# +/- 0.025 deg every second for 100 s) and its tracker, with ``RangeParameterisedInitiator`` in place of the
# truth: Peach's bank of range-parameterised EKFs (10 m to 2 km) is held inside the initiator until the range
# sd is at most 20 % of the range, then handed to Stone Soup's EKF as one Gaussian.
from stonesoup.dataassociator.neighbour import NearestNeighbour  # noqa: E402
from stonesoup.deleter.time import UpdateTimeStepsDeleter  # noqa: E402
from stonesoup.hypothesiser.distance import DistanceHypothesiser  # noqa: E402
from stonesoup.measures import Mahalanobis  # noqa: E402
from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing  # noqa: E402
from stonesoup.predictor.kalman import ExtendedKalmanPredictor  # noqa: E402
from stonesoup.tracker.simple import SingleTargetTracker  # noqa: E402
from stonesoup.updater.kalman import ExtendedKalmanUpdater  # noqa: E402

from sonartrack.stonesoup import RANGE_MIXTURE, RangeParameterisedInitiator  # noqa: E402

transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(1.0), ConstantVelocity(1.0)])
sigma = np.deg2rad(0.025)
rng = np.random.default_rng(2001)
F, Q = transition.matrix(time_interval=datetime.timedelta(seconds=1)), transition.covar(
    time_interval=datetime.timedelta(seconds=1))
target, sensor, truth, sensor_track, scans = np.array([50.0, 0, 50, 0]), np.zeros(2), [], [], []
for k in range(101):
    if k:
        target = F @ target + rng.multivariate_normal(np.zeros(4), Q)
        sensor = sensor + np.array([-5.0, -7.0])
    when = t0 + datetime.timedelta(seconds=k)
    bearing = np.arctan2(target[2] - sensor[1], target[0] - sensor[0]) + rng.normal(0, sigma)
    model = Cartesian2DToBearing(4, (0, 2), np.array([[sigma**2]]), translation_offset=sensor.reshape(2, 1).copy())
    truth.append(target[[0, 2]].copy())
    sensor_track.append(sensor.copy())
    scans.append((when, {Detection(np.array([[bearing]]), timestamp=when, measurement_model=model)}))

initiator = RangeParameterisedInitiator(transition_model=transition, min_range=10.0, max_range=2000.0,
                                        target_speed=2.0)
predictor, updater = ExtendedKalmanPredictor(transition), ExtendedKalmanUpdater(measurement_model=None)
tracker = SingleTargetTracker(initiator=initiator, deleter=UpdateTimeStepsDeleter(3), detector=scans,
                              updater=updater, data_associator=NearestNeighbour(
                                  DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=5)))
track, released_at = None, None
for when, tracks in tracker:
    if tracks and track is None:
        track, released_at = next(iter(tracks)), when
k_release = int((released_at - t0).total_seconds())
for k, label in ((k_release, "at release"), (100, "at the end")):
    state = next(s for s in track if s.timestamp == t0 + datetime.timedelta(seconds=k))
    error = np.hypot(*(state.state_vector[[0, 2], 0] - truth[k]))
    sd = np.sqrt(np.trace(state.covar[np.ix_([0, 2], [0, 2])]))
    print(f"{label} (t = {k} s): position error {error:.1f} m, position sd {sd:.1f} m, "
          f"range {np.hypot(*(truth[k] - sensor_track[k])):.0f} m")
print(f"{initiator.n_filters} range filters held {k_release + 1} bearings; the track's states start at "
      f"t = {(track.states[0].timestamp - t0).seconds} s")

# %%
# The track's first states are the collapsed mixture after each held bearing (from the first, where the mean is the
# prior's, half way out along the bearing), then Stone Soup's EKF carries it on. The circles are the range filters at
# release, their area the filter's weight: the bearings have ruled out all ranges but a few. The range stays the
# weakly known quantity of this scene (the sensor moves almost straight away from the target), but no truth went into
# the tracker.
mixture = track.metadata[RANGE_MIXTURE]
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot(*np.array(truth).T, "g--", label="target (truth)")
ax.plot(*np.array(sensor_track).T, "k:", label="sensor")
xy = np.array([s.state_vector[[0, 2], 0] for s in track])
ax.plot(*xy[:k_release + 1].T, ".", color="c", ms=4, label="held (collapsed mixture)")
ax.plot(*xy[k_release:].T, "b-", label="track (Stone Soup EKF)")
ax.scatter([c.state_vector[0, 0] for c in mixture], [c.state_vector[2, 0] for c in mixture],
           s=[400 * float(c.weight) for c in mixture], facecolors="none", edgecolors="r", label="range filters")
ax.set(xlabel="x (m)", ylabel="y (m)", title="Stone Soup's bearing-only example, started by sonartrack",
       aspect="equal")
ax.legend()
