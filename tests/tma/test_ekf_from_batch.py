"""The sequential EKF started from a batch estimate (paper P3) keeps the batch accuracy and is consistent."""

import numpy as np

from sonartrack.core.units import KNOT_MPS as KN
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.batch import ekf_from_batch
from sonartrack.tma.batch_ml import BatchEstimate, bearing_model, ml_bearings_only
from sonartrack.tma.records import BearingRecord, OwnshipTrack


def test_ekf_from_ml_is_accurate_and_consistent():
    t = np.arange(0.0, 1800.0 + 1.0, 20.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KN, 0.0, ((600.0, 660.0, np.deg2rad(1.5)), (1200.0, 1260.0, np.deg2rad(-1.5))))
    po, _, _ = obs.state(t)
    c = np.deg2rad(250.0)
    x0 = np.array([3000.0, 5200.0, 4 * KN * np.sin(c), 4 * KN * np.cos(c)])
    h, _, _ = bearing_model(x0, t, po)
    own = OwnshipTrack(time_s=t, x_m=po[:, 0], y_m=po[:, 1])
    rng = np.random.default_rng(8)
    nees, err_b, err_e = [], [], []
    for _ in range(40):
        z = h + rng.normal(0, np.deg2rad(1.0), len(t))
        est_all = ml_bearings_only(z, t, po, np.deg2rad(1.0))
        first = t <= 1300.0  # batch on the first 1300 s (both maneuvers), the EKF takes over after
        est = ml_bearings_only(z[first], t[first], po[first], np.deg2rad(1.0))
        sol = ekf_from_batch(BearingRecord(time_s=t, bearing_rad=z), own, est, start_s=t[first][-1],
                             sigma_bearing_rad=np.deg2rad(1.0), q_m2_s3=1e-8)
        truth_end = x0 + np.array([x0[2], x0[3], 0, 0]) * t[-1]
        e = sol.state[-1] - truth_end
        nees.append(e @ np.linalg.solve(sol.covariance[-1], e))
        err_e.append(np.hypot(*e[:2]))
        xb, _ = est_all.state_at(t[-1:])
        err_b.append(np.hypot(*(xb[0, :2] - truth_end[:2])))
    assert np.mean(nees) < 1.5 * 4  # consistent: the chi-square(4) mean is 4 (40 runs, EKF linearisation)
    # batch-then-EKF is about as accurate as one batch solve over everything
    assert np.sqrt(np.mean(np.square(err_e))) < 1.3 * np.sqrt(np.mean(np.square(err_b)))
    # and a start from a wrong state with a small covariance is worse: the batch start matters
    bad = BatchEstimate(x0=x0 + np.array([3000.0, 3000.0, 2.0, 0.0]), covariance=np.eye(4) * [1e4, 1e4, 0.1, 0.1],
                        t0_s=0.0, iterations=0, converged=True, objective=0.0, method="x")
    sol_bad = ekf_from_batch(BearingRecord(time_s=t, bearing_rad=z), own, bad, start_s=0.0,
                             sigma_bearing_rad=np.deg2rad(1.0), q_m2_s3=1e-8)
    assert np.hypot(*(sol_bad.state[-1, :2] - truth_end[:2])) > 2 * err_e[-1]
