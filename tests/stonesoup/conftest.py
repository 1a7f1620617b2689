"""Scenes for the Stone Soup component tests (Stone Soup is imported inside the fixtures, so that without the
extra the test modules skip with their own reason instead of this file failing to import).

``tutorial_scene`` rebuilds the scene of Stone Soup's JPDA tutorial (docs/tutorials/08_JPDATutorial.py, Stone
Soup 1.9.1) from its parameters: two constant-velocity targets (q = 0.005 m^2/s^3 per axis) from [0, 1, 0, 1]
and [0, 1, 20, -1] ([x, vx, y, vy]) that cross near t = 10 s, 1 s steps, position measurements with
R = 0.75 I, P_D = 0.9, and per target and scan up to 9 clutter points uniform in a 20 m x 20 m square around
it; the tracker's hypothesiser has clutter density 0.125, P_D = 0.9 and Stone Soup's default P_G = 0.95.
Randomness comes from one seeded ``numpy.random.Generator`` (the tutorial's seed, 1991) instead of the
global state the tutorial uses.
"""

from __future__ import annotations

import datetime

import numpy as np
import pytest

START = datetime.datetime(2026, 1, 1)


def _truths(rng, transition_model, starts, n_steps):
    from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState

    dt = datetime.timedelta(seconds=1)
    F, Q = transition_model.matrix(time_interval=dt), transition_model.covar(time_interval=dt)
    truths = []
    for x0 in starts:
        x = np.array(x0, float)
        path = GroundTruthPath([GroundTruthState(x.reshape(-1, 1), timestamp=START)])
        for k in range(1, n_steps + 1):
            x = F @ x + rng.multivariate_normal(np.zeros(4), Q)
            path.append(GroundTruthState(x.reshape(-1, 1), timestamp=START + k * dt))
        truths.append(path)
    return truths


def _scans(rng, truths, measurement_model, prob_detect, n_scans, max_clutter=10, half_width=10.0):
    from stonesoup.types.detection import Clutter, TrueDetection

    R = measurement_model.covar()
    scans = []
    for k in range(n_scans):
        detections = set()
        for path in truths:
            state = path[k]
            if rng.random() <= prob_detect:
                z = measurement_model.matrix() @ state.state_vector + rng.multivariate_normal(np.zeros(2), R)[:, None]
                detections.add(TrueDetection(z, groundtruth_path=path, timestamp=state.timestamp,
                                             measurement_model=measurement_model))
            centre = np.array([state.state_vector[0, 0], state.state_vector[2, 0]])
            for _ in range(rng.integers(max_clutter)):
                z = centre - half_width + 2 * half_width * rng.random(2)
                detections.add(Clutter(z.reshape(-1, 1), timestamp=state.timestamp,
                                       measurement_model=measurement_model))
        scans.append((START + datetime.timedelta(seconds=k), detections))
    return scans


def build_scene(seed=1991, starts=((0, 1, 0, 1), (0, 1, 20, -1)), n_scans=20, max_clutter=10):
    """The tutorial scene (module doc) for ``starts``: a dict of its models, truths, scans and priors."""
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
    from stonesoup.types.state import GaussianState

    rng = np.random.default_rng(seed)
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.005), ConstantVelocity(0.005)])
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([0.75, 0.75]))
    truths = _truths(rng, transition, starts, n_scans)
    scans = _scans(rng, truths, measurement, 0.9, n_scans, max_clutter)
    priors = [GaussianState(np.array(x0, float).reshape(-1, 1), np.diag([1.5, 0.5, 1.5, 0.5]), timestamp=START)
              for x0 in starts]
    return {"transition": transition, "measurement": measurement, "truths": truths, "scans": scans,
            "priors": priors, "prob_detect": 0.9, "clutter_density": 0.125}


@pytest.fixture(scope="module")
def tutorial_scene():
    """Stone Soup's JPDA tutorial scene (module doc)."""
    return build_scene()


@pytest.fixture(scope="module")
def crowded_scene():
    """Five targets converging on the origin in the tutorial's clutter: clusters of up to five tracks."""
    angles = np.arange(5) * 2 * np.pi / 5
    starts = [(-10 * np.cos(a), np.cos(a), -10 * np.sin(a), np.sin(a)) for a in angles]
    return build_scene(seed=7, starts=starts, n_scans=20, max_clutter=6)


def pda_hypothesiser(scene, cls=None, **options):
    """The tutorial's hypothesiser (``cls`` PDAHypothesiser by default) on ``scene``'s models."""
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.updater.kalman import KalmanUpdater

    cls = cls or PDAHypothesiser
    return cls(predictor=KalmanPredictor(scene["transition"]), updater=KalmanUpdater(scene["measurement"]),
               clutter_spatial_density=scene["clutter_density"], prob_detect=scene["prob_detect"], **options)


@pytest.fixture(scope="module")
def scene_tools():
    """Helpers for the test modules (importing conftest by name is not possible under importlib mode)."""
    return {"build_scene": build_scene, "pda_hypothesiser": pda_hypothesiser}
