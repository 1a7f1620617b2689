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
3. constant velocity: a bank of single CV MGEKFs (q = 1e-9) on constant-velocity targets;
4. the bearing sd ``sonartrack tma`` gives the filter when none is given (tma/motion_verdict.py: the scale of a
   whole-record constant-velocity fit's residuals) on the turn scene, beside a model-free estimate (second
   differences of the bearings, robust: sd^2 = median(d2^2) / (6 x 0.455), chi2(1)'s median 0.455).

5. ``--grid``: the search of issue 30 item 4 for IMM settings whose ANEES is inside the interval before, during and
   after turns of 20 / 60 / 120 deg and speed changes of +3 / -2 m/s (0.05 m/s^2) on world 1, without losing the
   response: per setting (modes q, Markov matrix as the probability of staying in each mode per bearing, the
   filters' initial mode probabilities its stationary law) the window medians per case, ``miss`` = the largest
   |log(ANEES / nearest end of the interval)| over windows and cases (0: all inside), and the response on
   tests/tma/test_imm_respond.py's 90 deg turn (one IMM, 40 runs): the share of runs whose manoeuvre probability
   (modes with q >= ImmSettings.manoeuvre_q_min) exceeds 0.5 within 300 s, and the share of straight-leg samples
   flagged (that test asks >= 0.8 and <= 0.05). Then the frontier: the settings no other beats on both the straight
   legs (worst of before / after, from below) and the turns (worst during, from above).

Usage: ``python benchmarks/range_bank_nees.py [runs] [--grid]`` (default 30 runs per case; ~0.1 s of CPU per run and
case; the grid, 20 runs: ~15 s per setting).
"""

from __future__ import annotations

import contextlib
import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import chi2

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' generators (tests/tma)

from tests.tma import test_range_bank_consistency as own_model  # noqa: E402
from tests.tma.test_imm_respond import DT_S, SIGMA_B, T_TURN_S, _paths  # noqa: E402
from tests.tma.test_imm_respond import _monte_carlo as respond_runs  # noqa: E402

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


def turn_world(turn_deg: float, n_runs: int, model: ImmBfModel, speed_change_mps: float = 0.0, mu0=None):
    """Times, NEES (n_runs, n) and each run's closest approach (m) of the bank on the turn scene."""
    rng = np.random.default_rng(11)
    t1, own, tgt = _paths(rng, n_runs, turn_deg, speed_change_mps)
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
                                  np.array([a for a, _ in st]), np.array([b for _, b in st]), model, mu0=mu0)
        e = rel - x[:, :4]
        nees.append(_nees(e, P[:, :4, :4]))
    closest = np.hypot(*(tgt - own)[..., :2].transpose(2, 0, 1)).min(axis=1)
    return t, np.array(nees), closest


def _nees(e, P) -> np.ndarray:
    """e_k^T P_k^-1 e_k per row (inf where P_k is singular or the estimate is missing)."""
    try:
        out = np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])
    except np.linalg.LinAlgError:  # some P_k singular: row by row
        out = np.full(len(e), np.inf)
        for k in range(len(e)):
            with contextlib.suppress(np.linalg.LinAlgError):
                out[k] = e[k] @ np.linalg.solve(P[k], e[k])
    return np.where(np.isfinite(out), out, np.inf)


def face_sd_deg(turn_deg: float, n_runs: int) -> tuple[np.ndarray, np.ndarray]:
    """Per run of the turn scene: the bearing sd the face estimates (deg) and the second-difference estimate."""
    from sonartrack.tma.motion_verdict import judge_record
    from sonartrack.tma.records import BearingRecord, OwnshipTrack
    from sonartrack.tma.settings import TmaSettings

    rng = np.random.default_rng(11)
    t1, own, tgt = _paths(rng, n_runs, turn_deg)
    t = np.arange(0.0, 4200.0 + 1e-9, DT_S)
    k = np.searchsorted(t1, t)
    face, d2 = [], []
    for i in range(n_runs):
        rel = tgt[i, k] - own[i, k]
        zb = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
        nav = OwnshipTrack(time_s=t1, x_m=own[i, :, 0], y_m=own[i, :, 1])
        face.append(judge_record(BearingRecord(time_s=t, bearing_rad=zb), nav, TmaSettings()).sigma_deg(TmaSettings()))
        d2.append(np.rad2deg(np.sqrt(np.median(np.diff(np.unwrap(zb), 2) ** 2) / (6.0 * chi2.ppf(0.5, 1)))))
    return np.array(face), np.array(d2)


def window_medians(t, nees) -> str:
    a = nees.mean(axis=0)
    return " / ".join(f"{np.median(a[(t >= lo) & (t < hi)]):6.2f}" for lo, hi in WINDOWS_S.values())


def main(n_runs: int) -> None:
    t0 = time.perf_counter()
    lo, hi = interval(n_runs)
    print(f"ANEES (4 states) median per window before / during / after; 95 % interval for {n_runs} runs "
          f"[{lo:.2f}, {hi:.2f}]")
    model = paper_model()
    for turn in (20.0, 60.0, 120.0):
        t, nees, closest = turn_world(turn, n_runs, model)
        far = closest >= 1_000.0
        lo_far, hi_far = interval(int(far.sum()))
        print(f"turn {turn:5.0f} deg: all runs {window_medians(t, nees)};  {far.sum()} runs never within 1 km: "
              f"{window_medians(t, nees[far])} in [{lo_far:.2f}, {hi_far:.2f}]\n"
              f"    (closest approaches < 1 km: {np.round(closest[~far]).tolist()} m)")
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
    for turn in (20.0, 60.0, 120.0):
        face, d2 = face_sd_deg(turn, n_runs)
        print(f"turn {turn:5.0f} deg: bearing sd (true 1 deg) the face estimates: median {np.median(face):.2f}, "
              f"range {face.min():.2f}-{face.max():.2f}; second differences: {d2.min():.2f}-{d2.max():.2f}")
    print(f"({time.perf_counter() - t0:.0f} s)")


CASES = ((20.0, 0.0), (60.0, 0.0), (120.0, 0.0), (0.0, 3.0), (0.0, -2.0))  # (turn deg, speed change m/s)


def stay_matrix(stay) -> np.ndarray:
    """Markov matrix with ``stay[i]`` on the diagonal and the rest of row i spread evenly over the other modes."""
    stay = np.asarray(stay, float)
    r = len(stay)
    if r == 1:
        return np.ones((1, 1))
    Pi = np.repeat(((1.0 - stay) / (r - 1))[:, None], r, axis=1)
    np.fill_diagonal(Pi, stay)
    return Pi


GRID = [([1e-5, 1e-3, 0.1], [0.99] * 3), ([1e-5, 1e-3, 0.3], [0.99] * 3), ([1e-5, 1e-3, 1.0], [0.99] * 3),
        ([1e-5, 1e-3, 0.1], [0.98] * 3), ([1e-5, 1e-3, 0.1], [0.97] * 3), ([1e-5, 1e-3, 0.3], [0.98] * 3),
        ([1e-7, 1e-3, 0.1], [0.99] * 3), ([1e-9, 1e-3, 0.3], [0.99] * 3), ([1e-6, 1e-4, 0.1], [0.99] * 3),
        ([1e-7, 1e-4, 0.3], [0.98] * 3), ([1e-5, 1e-3, 0.3], [0.995, 0.98, 0.95]),
        ([1e-9, 1e-3, 0.1], [0.999, 0.95, 0.95]), ([1e-9, 1e-4, 0.3], [0.999, 0.95, 0.95]),
        ([1e-5, 1.0], [0.99, 0.99]), ([1e-7, 0.3], [0.99, 0.9]),
        *(([1e-9, qm], stay) for qm in (0.1, 0.3, 1.0) for stay in ([0.99, 0.9], [0.999, 0.95], [0.9999, 0.95])),
        ([1e-9, 0.1], [0.999999, 0.95]), ([1e-9], [1.0])]
#: the response tests/tma/test_imm_respond.py asks for: share of runs above the level within 300 s, share flagged
RESPONSE_MIN, FLAGGED_MAX = 0.8, 0.05


def interval(n_runs: int, level: float = 0.95) -> np.ndarray:
    """chi2(4 N) / N's two-sided interval: the ANEES (4 states) of a consistent filter over N runs at one time."""
    return chi2.ppf([(1.0 - level) / 2.0, (1.0 + level) / 2.0], 4 * n_runs) / n_runs


def grid_row(qs, stay, n_runs: int) -> dict:
    """One setting of the grid: window medians per case, ``miss`` and the response (module doc, item 5); each case's
    interval for the runs it averages (those never within 1 km of the ownship)."""
    Pi = stay_matrix(stay)
    model = ImmBfModel(qs=np.asarray(qs, float), Pi=Pi, sigma_bearing_rad=SIGMA_B, q_f0=ImmSettings().q_f0)
    mu0 = np.linalg.matrix_power(Pi, 1 << 20)[0]
    windows, miss = [], 0.0
    for turn, dv in CASES:
        t, nees, closest = turn_world(turn, n_runs, model, dv, mu0)
        far = closest >= 1_000.0
        a = nees[far].mean(axis=0)
        windows.append([float(np.median(a[(t >= w0) & (t < w1)])) for w0, w1 in WINDOWS_S.values()])
        lo, hi = interval(int(far.sum()))
        miss = max(miss, float(np.max(np.abs(np.log(np.array(windows[-1]) / np.clip(windows[-1], lo, hi))))))
    w = np.array(windows)
    t, man, _, level = respond_runs(40, 90.0, model=model)
    after = t >= T_TURN_S
    first = np.array([t[after][np.argmax(m[after] > level)] - T_TURN_S if np.any(m[after] > level) else np.inf
                      for m in man])
    straight = (t > 600) & (t < T_TURN_S)
    return {"qs": qs, "stay": stay, "windows": w, "miss": miss, "quiet": float(w[:, [0, 2]].min()),
            "turn": float(w[:, 1].max()), "within300": float(np.mean(first <= 300.0)),
            "flagged": float(np.mean(man[:, straight] > level))}


def _frontier(rows: list[dict]) -> list[dict]:
    """The rows no other row beats on both the straight legs (higher worst) and the turns (lower worst)."""
    return [r for r in rows if not any(o["quiet"] >= r["quiet"] and o["turn"] <= r["turn"]
                                       and (o["quiet"], o["turn"]) != (r["quiet"], r["turn"]) for o in rows)]


def grid(n_runs: int) -> None:
    """Item 5 of the module doc: print the grid and its frontier."""
    t0, c0 = time.perf_counter(), time.process_time()
    lo, hi = interval(n_runs)
    print(f"grid, {n_runs} runs per case, interval [{lo:.2f}, {hi:.2f}]; per case before/during/after: "
          + ", ".join(f"turn {a:.0f} dv {b:+.0f}" for a, b in CASES))
    rows = []
    for qs, stay in GRID:
        r = grid_row(qs, stay, n_runs)
        rows.append(r)
        print(f"q {qs} stay {stay}: " + "  ".join("/".join(f"{v:.2f}" for v in c) for c in r["windows"])
              + f"  miss {r['miss']:.2f}  straight >= {r['quiet']:.2f}  turn <= {r['turn']:.2f}  response "
              f"{r['within300']:.2f} within 300 s, flagged {r['flagged']:.2f}", flush=True)
    responsive = [r for r in rows if r["within300"] >= RESPONSE_MIN and r["flagged"] <= FLAGGED_MAX]
    for name, some in (("all settings", rows), ("settings with test_imm_respond's response", responsive)):
        print(f"frontier of the {name} (worst straight-leg ANEES, worst during-turn ANEES, miss, response):")
        for r in sorted(_frontier(some), key=lambda r: r["quiet"]):
            print(f"  q {r['qs']} stay {r['stay']}: {r['quiet']:.2f}, {r['turn']:.2f}, {r['miss']:.2f}, "
                  f"{r['within300']:.2f} / {r['flagged']:.2f}")
    print(f"({time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} s CPU)")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--grid"]
    runs = int(args[0]) if args else 30
    grid(runs) if "--grid" in sys.argv else main(runs)
