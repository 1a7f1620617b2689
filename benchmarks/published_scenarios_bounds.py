"""The published bearings-only scenarios' bounds and our ML against them, at a Monte Carlo size too long for a test.

Scenarios 'm' (Ristic, Arulampalam & Gordon 2004, ch. 6) and 'h' (Leong et al., IEEE SPL 2014) from
tests/worlds/bearings_only_literature.py. Prints, every 4 minutes, the PCRB position sd (tma/pcrb.py) on the nominal
track and averaged over sampled tracks (q of the paper), the q = 0 bound with the prior, the batch CRB without it
(tma/batch_ml.py), and our batch ML's RMSE on a CV target at a few steps with its efficiency RMSE / CRB and a 95 %
interval from the Monte Carlo (delta method on the mean square). Run: ``python benchmarks/published_scenarios_bounds.py
[runs]`` (default 2000 runs; ~10 s a scenario on one core).
"""

import sys
import time
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.models.motion import cv_transition
from sonartrack.tma.batch_ml import crb, fisher_information, ml_bearings_only
from sonartrack.tma.pcrb import pcrb_bearings_only, polar_prior, position_sd_m

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from worlds.bearings_only_literature import HIGH, KNOT_MPS, MODERATE  # noqa: E402


def prior(s, own):
    x0 = s.target_x0
    rel = x0[:2] - own[0]
    b = np.arctan2(rel[0], rel[1])
    return polar_prior(np.hypot(*rel), b, np.hypot(*x0[2:]), b + np.pi, s.prior_range_sd_m, s.sigma_rad,
                       s.prior_speed_sd_kn * KNOT_MPS, s.prior_course_sd_rad)[1]


def bounds_table(s):
    own, t = s.ownship(), s.time_s
    P0 = prior(s, own)
    nominal = position_sd_m(pcrb_bearings_only(s.target(), own, t, s.sigma_rad, s.q_m2_s3, P0))
    sampled = position_sd_m(pcrb_bearings_only(s.target(500, seed=1), own, t, s.sigma_rad, s.q_m2_s3, P0))
    cv = position_sd_m(pcrb_bearings_only(s.target(), own, t, s.sigma_rad, 0.0, P0))
    print(f"scenario {s.name}: bounds on the position (m) against time (min)")
    print("  min  PCRB(nominal)  PCRB(500 tracks)  q=0+prior  batch CRB")
    for k in range(0, s.steps + 1, 4):
        F = cv_transition(t[k])
        J = fisher_information(s.target_x0, t[: k + 1], own[: k + 1], s.sigma_rad)
        # a straight ownship so far: J is singular (Nardone & Aidala 1981), and its inverse rounding noise
        batch = (f"{position_sd_m(F @ np.linalg.inv(J) @ F.T):9.0f}" if np.linalg.cond(J) < 1e12 else "unobserved")
        print(f"  {t[k] / 60:3.0f}  {nominal[k]:13.0f}  {sampled[k]:16.0f}  {cv[k]:9.0f}  {batch:>10}")


def efficiency(s, steps, runs):
    own, t, truth = s.ownship(), s.time_s, s.target()
    rng = np.random.default_rng(7)
    for k in steps:
        F = cv_transition(t[k])
        bound = position_sd_m(F @ crb(s.target_x0, t[: k + 1], own[: k + 1], s.sigma_rad) @ F.T)
        z = s.bearings(np.broadcast_to(truth[: k + 1], (runs, k + 1, 4)), own[: k + 1], rng)
        t0 = time.perf_counter()
        sq = []
        for zi in z:
            try:
                sq.append(np.sum(np.square((F @ ml_bearings_only(zi, t[: k + 1], own[: k + 1], s.sigma_rad).x0)[:2]
                                           - truth[k, :2])))
            except InputError:
                sq.append(np.inf)
        sq = np.asarray(sq)
        rmse = np.sqrt(np.mean(sq))
        half = 1.96 * np.std(sq) / np.sqrt(runs) / (2 * rmse)  # sd of sqrt(mean) by the delta method
        print(f"  {s.name} step {k:2d}: CRB {bound:7.0f} m, ML RMSE {rmse:10.4g} m, efficiency {rmse / bound:.3f} "
              f"(95 % {(rmse - half) / bound:.3f}-{(rmse + half) / bound:.3f}), median error "
              f"{np.sqrt(np.median(sq)):.0f} m, {runs} runs in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    n_runs = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    for scenario, steps in ((MODERATE, (19, 22, 32)), (HIGH, (18, 21, 30))):
        bounds_table(scenario)
        efficiency(scenario, steps, n_runs)
