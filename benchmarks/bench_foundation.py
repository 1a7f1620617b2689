"""Foundation speed against the peers, on identical inputs.

* PDA update of one track with 40 measurements: ours (compiled and NumPy) vs Stone Soup's
  PDAHypothesiser + PDA + PDAUpdater. Target: >= 100x faster (compiled), same estimates.
* IMM step with 2 CV modes: ours (compiled and NumPy) vs FilterPy's IMMEstimator. Target: >= 10x.
* The IPDA / IMM-IPDA tracker (tracking/configurations.py position_tracker; its pre-gate, IMM mixing and
  PDA mixture sums compiled) in the P4 scenario: ms per scan. Target: <= 0.6 ms with 3 modes.

Timings are medians of repeated runs after a warm-up (numba compiled beforehand).
"""

import datetime
import time

import numpy as np


def median_time(fn, repeat=7, number=50):
    fn()
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        out.append((time.perf_counter() - t0) / number)
    return float(np.median(out))


def _stone_soup_pda(x0, P0, z, R, q, dt, pd, pg, rho):
    """Stone Soup's PDAHypothesiser + PDA + PDAUpdater on our inputs (its state order is [x, vx, y, vy])."""
    from stonesoup.dataassociator.probability import PDA
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.types.detection import Detection
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track
    from stonesoup.updater.kalman import KalmanUpdater
    from stonesoup.updater.probability import PDAUpdater

    perm = [0, 2, 1, 3]
    t0 = datetime.datetime(2020, 1, 1)
    t1 = t0 + datetime.timedelta(seconds=dt)
    trans = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
    meas = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=R)
    track = Track([GaussianState(x0[perm].reshape(-1, 1), P0[np.ix_(perm, perm)], timestamp=t0)])
    dets = {Detection(zz.reshape(-1, 1), timestamp=t1, measurement_model=meas) for zz in z}
    assoc = PDA(PDAHypothesiser(KalmanPredictor(trans), KalmanUpdater(meas), clutter_spatial_density=rho,
                                prob_detect=pd, prob_gate=pg))
    updater = PDAUpdater(meas)

    def ss():
        return updater.update(assoc.associate({track}, dets, t1)[track])

    return ss, lambda post: np.asarray(post.state_vector, float).ravel()[np.argsort(perm)]


def bench_pda():
    from sonartrack.association.gating import gate_threshold
    from sonartrack.association.pda import pda_update
    from sonartrack.association.pda_kernel import pda_update_fast
    from sonartrack.filters.kalman import kf_predict
    from sonartrack.models.motion import cv_process_noise, cv_transition

    rng = np.random.default_rng(0)
    q, dt, pd, pg, rho = 0.5, 2.0, 0.85, 0.99, 1e-4
    x0 = np.array([0.0, 0.0, 3.0, 1.0])
    P0 = np.diag([400.0, 400.0, 4.0, 4.0])
    R = np.array([[90.0, 20.0], [20.0, 60.0]])
    x_pred, P_pred = kf_predict(x0, P0, cv_transition(dt), cv_process_noise(dt, q))
    z = x_pred[:2] + rng.uniform(-300, 300, (40, 2))
    z[:3] = x_pred[:2] + rng.normal(0, 15, (3, 2))
    ss, ss_state = _stone_soup_pda(x0, P0, z, R, q, dt, pd, pg, rho)
    gamma = gate_threshold(pg)

    def ours_numpy():
        xp, Pp = kf_predict(x0, P0, cv_transition(dt), cv_process_noise(dt, q))
        return pda_update(xp, Pp, z, R, pd=pd, pg=pg, gamma=gamma, clutter_density=rho)

    F, Q = cv_transition(dt), cv_process_noise(dt, q)

    def ours_fast():
        xp, Pp = F @ x0, F @ P0 @ F.T + Q
        return pda_update_fast(xp, Pp, z, R, pd=pd, pg=pg, gamma=gamma, clutter_density=rho)

    diff = np.abs(ss_state(ss()) - ours_fast()[0]).max()
    t_ss = median_time(ss, repeat=5, number=20)
    t_np = median_time(ours_numpy, number=300)
    t_fast = median_time(ours_fast, number=2000)
    print(f"PDA predict+update, 1 track, 40 measurements: ours {t_fast * 1e6:.1f} us (compiled), "
          f"{t_np * 1e6:.0f} us (NumPy); Stone Soup {t_ss * 1e3:.2f} ms; ratio {t_ss / t_fast:.0f} x compiled, "
          f"{t_ss / t_np:.0f} x NumPy (target >= 100 x compiled); max |x diff| {diff:.1e}")


def bench_imm():
    from filterpy.kalman import IMMEstimator, KalmanFilter

    from sonartrack.filters.imm_kf import imm_kf_step
    from sonartrack.filters.imm_kf_kernel import imm_kf_step_fast
    from sonartrack.models.motion import H_POSITION, cv_process_noise_stack, cv_transition

    F, H = cv_transition(1.0), H_POSITION
    Q = cv_process_noise_stack(1.0, [0.01, 1.0])
    R = np.eye(2) * 25.0
    Pi = np.array([[0.97, 0.03], [0.03, 0.97]])
    x = np.zeros((2, 4))
    P = np.stack([np.eye(4) * 100.0] * 2)
    mu = np.array([0.5, 0.5])
    z = np.array([1.0, 2.0])
    filters = []
    for j in range(2):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x, kf.P, kf.F, kf.Q, kf.H, kf.R = x[j].copy(), P[j].copy(), F, Q[j], H, R
        filters.append(kf)
    imm = IMMEstimator(filters, mu.copy(), Pi)

    def fp():
        imm.predict()
        imm.update(z)

    t_fp = median_time(fp, number=200)
    t_np = median_time(lambda: imm_kf_step(x, P, mu, z, F, Q, H, R, Pi), number=300)
    t_fast = median_time(lambda: imm_kf_step_fast(x, P, mu, z, F, Q, H, R, Pi), number=3000)
    print(f"IMM step, 2 CV modes: ours {t_fast * 1e6:.1f} us (compiled), {t_np * 1e6:.0f} us (NumPy); "
          f"FilterPy IMMEstimator {t_fp * 1e6:.0f} us; ratio {t_fp / t_fast:.0f} x compiled, {t_fp / t_np:.1f} x NumPy "
          f"(target >= 10 x)")


def bench_tracker():
    from sonartrack.sim.bistatic_sonar import simulate_scan
    from sonartrack.studies.bistatic_imm_ipda import Config
    from sonartrack.tracking.configurations import position_tracker

    cfg = Config()
    rng = np.random.default_rng(1)
    ship, sonar, truth = cfg.ownship(), cfg.sonar(), cfg.target_states()
    scans = [simulate_scan(rng, sonar, ship, float(t), truth[k, :2]) for k, t in enumerate(cfg.times_s())]
    cases = cfg.cases()
    for name, q in (("IPDA (1 mode)", cases["ipda_small"]), ("IMM-IPDA (2 modes)", cases["imm2"]),
                    ("IMM-IPDA (3 modes)", cases["imm3"])):
        def run(q=q):
            trk = position_tracker(cfg.tracker_settings(q))
            for s in scans:
                trk.step(s.time_s, s.z, s.R)
        t = median_time(run, repeat=5, number=1)
        print(f"tracker, P4 scenario (~40 contacts/scan), {name}: {t / len(scans) * 1e3:.2f} ms per scan"
              + (" (target <= 0.6 ms)" if len(q) == 3 else ""))


if __name__ == "__main__":
    bench_pda()
    bench_imm()
    bench_tracker()
