"""Benchmark: one IMM predict + update cycle inside Stone Soup (3 constant-velocity modes, position measurement).

Three implementations of the same cycle on the same inputs:

* ours -- sonartrack.stonesoup.imm: IMMPredictor / IMMUpdater around Stone Soup's KalmanPredictor and
  KalmanUpdater (the modes predicted and updated together on arrays, filters/imm.py for mixing and combination);
* Stone Soup loop -- what a Stone Soup user writes without it: per mode a mixed GaussianState, KalmanPredictor.predict,
  KalmanUpdater.update, the mode likelihood from the measurement prediction, then gm_reduce_single;
* FilterPy -- IMMEstimator.predict() + update(z).

Prints the time per cycle, the ratios, and the largest difference of the combined estimate between ours and the
Stone Soup loop (they compute the same thing).
"""

from __future__ import annotations

import datetime
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of  # noqa: E402

QS = (0.01, 0.3, 3.0)
T0, DT = datetime.datetime(2026, 1, 1), datetime.timedelta(seconds=2)


def setup():
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.types.detection import Detection
    from stonesoup.updater.kalman import KalmanUpdater

    Pi = np.full((3, 3), 0.025)
    np.fill_diagonal(Pi, 0.95)
    mm = LinearGaussian(4, (0, 2), np.diag([25.0, 25.0]))
    predictors = [KalmanPredictor(CombinedLinearGaussianTransitionModel([ConstantVelocity(q)] * 2)) for q in QS]
    rng = np.random.default_rng(0)
    x = rng.normal(0, 5, (3, 4))
    P = np.stack([np.diag([100.0, 9.0, 100.0, 9.0])] * 3)
    mu = np.array([0.5, 0.3, 0.2])
    det = Detection(np.array([[12.0], [-7.0]]), timestamp=T0 + DT, measurement_model=mm)
    return predictors, KalmanUpdater(mm), Pi, x, P, mu, det


def stonesoup_loop_step(predictors, updater, Pi, x, P, mu, det):
    """The IMM cycle written with Stone Soup objects only (module doc)."""
    from scipy.stats import multivariate_normal
    from stonesoup.functions import gm_reduce_single
    from stonesoup.types.array import StateVectors
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.state import GaussianState

    c = mu @ Pi
    w = mu[:, None] * Pi / c[None, :]
    posts, lik = [], []
    for j, predictor in enumerate(predictors):
        x0 = w[:, j] @ x
        P0 = sum(w[i, j] * (P[i] + np.outer(x[i] - x0, x[i] - x0)) for i in range(len(predictors)))
        prediction = predictor.predict(GaussianState(x0.reshape(-1, 1), P0, timestamp=T0), timestamp=det.timestamp)
        hyp = SingleHypothesis(prediction, det)
        posts.append(updater.update(hyp))
        mp = hyp.measurement_prediction
        lik.append(multivariate_normal.pdf(np.ravel(det.state_vector - mp.state_vector), cov=mp.covar))
    mu_new = c * np.array(lik)
    mu_new /= mu_new.sum()
    means = StateVectors([p.state_vector for p in posts])
    return gm_reduce_single(means, np.stack([p.covar for p in posts], axis=2), mu_new)


def main():
    from filterpy.kalman import IMMEstimator, KalmanFilter
    from stonesoup.types.hypothesis import SingleHypothesis

    from sonartrack.stonesoup.imm import IMMPredictor, IMMState, IMMUpdater

    predictors, updater, Pi, x, P, mu, det = setup()
    imm_p, imm_u = IMMPredictor(predictors=predictors, transition_probabilities=Pi), IMMUpdater(updater=updater)
    state = IMMState.from_modes(x, P, mu, timestamp=T0)

    def ours():
        return imm_u.update(SingleHypothesis(imm_p.predict(state, timestamp=det.timestamp), det))

    def loop():
        return stonesoup_loop_step(predictors, updater, Pi, x, P, mu, det)

    filters = []
    for j, p in enumerate(predictors):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.F, kf.Q = p.transition_model.matrix(time_interval=DT), p.transition_model.covar(time_interval=DT)
        kf.H, kf.R, kf.x, kf.P = updater.measurement_model.matrix(), updater.measurement_model.covar(), x[j], P[j]
        filters.append(kf)
    fp = IMMEstimator(filters, mu, Pi)
    z = np.asarray(det.state_vector, float)[:, 0]

    def filterpy():
        fp.predict()
        fp.update(z)

    mean_loop, covar_loop = loop()
    out = ours()
    diff = max(np.abs(np.asarray(out.state_vector, float) - np.asarray(mean_loop, float)).max(),
               np.abs(np.asarray(out.covar) - np.asarray(covar_loop)).max())
    t_ours, t_loop, t_fp = best_of(ours, 200), best_of(loop, 100), best_of(filterpy, 500)
    print(f"IMM cycle, 3 CV modes, in Stone Soup: ours {t_ours * 1e6:.0f} us, Stone Soup per-mode loop "
          f"{t_loop * 1e6:.0f} us (ratio {t_loop / t_ours:.1f}x), FilterPy IMMEstimator {t_fp * 1e6:.0f} us "
          f"(ratio {t_fp / t_ours:.1f}x); max |ours - loop| = {diff:.1e}")


if __name__ == "__main__":
    main()
