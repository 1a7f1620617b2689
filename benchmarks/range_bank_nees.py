"""Measurement: the IMM range bank's NEES before, during and after a turn, and on truths drawn from its own model.

Why the bank's NEES sits below chi-square's interval (issue 30 item 4; tests/tma/test_range_bank_consistency.py
asserts the short version). Three worlds, all the tests' numpy generators (not the project's simulator):

1. turn: tests/tma/test_imm_respond.py's scene (ownship legs at 5 m/s, target 10 km away at 3-7 m/s turning 20 /
   60 / 120 deg at 1 deg/s at t = 2100 s, bearings every 10 s, sd 1 deg); the bank of 8 IMM-MGEKFs over 2-40 km
   with the paper's modes (tma/settings.py ImmSettings). Median over each window of the ANEES (4 states), over all
   runs and over the runs whose target never comes within 1 km of the ownship (a close pass breaks every EKF's
   linearised bearing, turn or not);
2. own model: the same bank on targets drawn from its own prior and Markov chain of modes: ANEES over the record
   and the mean NEES at the times the target has been in the quietest mode for 600 s;
3. constant velocity: a bank of single CV MGEKFs (q = 1e-9) on constant-velocity targets.

Usage: ``python benchmarks/range_bank_nees.py [runs]`` (default 30 runs per case; ~1 s of CPU per run and case).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import chi2

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' generators (tests/tma)

from tests.tma import test_range_bank_consistency as own_model  # noqa: E402
from tests.tma.test_imm_respond import DT_S, SIGMA_B, T_TURN_S, _paths  # noqa: E402

from sonartrack.models.relative_motion import observer_inputs  # noqa: E402
from sonartrack.tma.imm_mgekf import ImmBfModel, transition_matrix  # noqa: E402
from sonartrack.tma.range_bank import range_subintervals, run_range_bank  # noqa: E402
from sonartrack.tma.sequential_bf import initial_estimate  # noqa: E402
from sonartrack.tma.settings import ImmSettings  # noqa: E402

WINDOWS_S = {"before": (1200.0, T_TURN_S), "during": (T_TURN_S, T_TURN_S + 360.0), "after": (T_TURN_S + 360.0, 4201.0)}


def paper_model() -> ImmBfModel:
    imm = ImmSettings()
    return ImmBfModel(qs=np.asarray(imm.q_values), Pi=transition_matrix(len(imm.q_values), imm.transition_diagonal),
                      sigma_bearing_rad=SIGMA_B, q_f0=imm.q_f0)


def turn_world(turn_deg: float, n_runs: int, model: ImmBfModel):
    """Times, NEES (n_runs, n) and each run's closest approach (m) of the bank on the turn scene."""
    rng = np.random.default_rng(11)
    t1, own, tgt = _paths(rng, n_runs, turn_deg)
    t = np.arange(0.0, 4200.0 + 1e-9, DT_S)
    k = np.searchsorted(t1, t)
    ranges, sds = range_subintervals(2_000.0, 40_000.0, 8)
    nees = []
    for i in range(n_runs):
        o, rel = own[i, k], tgt[i, k] - own[i, k]
        zb = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
        st = [initial_estimate(float(zb[0]), None, o[0, 2:], range_m=r, sigma_range_m=s, sigma_bearing_rad=SIGMA_B,
                               sigma_target_velocity_mps=5.0) for r, s in zip(ranges, sds, strict=True)]
        x, P, *_ = run_range_bank(t, np.c_[zb, np.full(len(t), np.nan)], observer_inputs(t, o[:, :2], o[:, 2:]),
                                  np.array([a for a, _ in st]), np.array([b for _, b in st]), model)
        e = rel - x[:, :4]
        nees.append(np.einsum("ni,ni->n", e, np.linalg.solve(P[:, :4, :4], e[..., None])[..., 0]))
    closest = np.hypot(*(tgt - own)[..., :2].transpose(2, 0, 1)).min(axis=1)
    return t, np.array(nees), closest


def window_medians(t, nees) -> str:
    a = nees.mean(axis=0)
    return " / ".join(f"{np.median(a[(t >= lo) & (t < hi)]):6.2f}" for lo, hi in WINDOWS_S.values())


def main(n_runs: int) -> None:
    t0 = time.perf_counter()
    lo, hi = chi2.ppf([0.025, 0.975], 4 * n_runs) / n_runs
    print(f"ANEES (4 states) median per window before / during / after; 95 % interval for {n_runs} runs "
          f"[{lo:.2f}, {hi:.2f}]")
    model = paper_model()
    for turn in (20.0, 60.0, 120.0):
        t, nees, closest = turn_world(turn, n_runs, model)
        far = closest >= 1_000.0
        print(f"turn {turn:5.0f} deg: all runs {window_medians(t, nees)};  {far.sum()} runs never within 1 km: "
              f"{window_medians(t, nees[far])}  (closest approaches < 1 km: {np.round(closest[~far]).tolist()} m)")
    own_model.N_RUNS = n_runs
    lo, hi = own_model._interval(0.95)
    t, nees, modes = own_model._monte_carlo(model, own_model._markov_truth(model.qs, model.Pi))
    window = t >= own_model.WINDOW_S[0]
    steps = int(own_model.QUIET_S / (t[1] - t[0]))
    quiet = np.array([[np.all(m[max(0, k - steps):k + 1] == 0) for k in range(len(t))] for m in modes]) & window
    print(f"own model: ANEES median {np.median(nees.mean(axis=0)[window]):.2f} [{lo:.2f}, {hi:.2f}]; mean NEES where "
          f"the target has been quiet {own_model.QUIET_S:.0f} s: {nees[quiet].mean():.2f} ({quiet.sum()} samples)")
    cv = ImmBfModel(qs=np.array([1e-9]), Pi=None, sigma_bearing_rad=SIGMA_B, q_f0=model.q_f0)
    t, nees, _ = own_model._monte_carlo(cv, own_model._markov_truth([0.0], [[1.0]]))
    print("constant velocity bank on constant-velocity targets: ANEES median "
          f"{np.median(nees.mean(axis=0)[window]):.2f}")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 30)
