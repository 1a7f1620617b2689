"""Benchmark: CPU time a trial of one study at its full-size config (issue 32 item 5), optionally profiled.

    python benchmarks/profile_study_trial.py jpda-amplitude 2 [--profile]   (not run by `make bench`: it needs a study)

Runs ``prepare`` (if the study has one), one warm-up trial (numba compiles or loads its kernels), then N trials
(seeds 1..N of master seed 2017) and prints the CPU time a trial and that times the study's full ``runs``; CPU
time, not wall time, because the machine is shared. Measured 2026-12-07 (load 13-18 on 2 cores, so a little high):
P0 jpda-amplitude 1.52 s a trial (152 s for 100), P1 mftd 0.006 s (63 s for 10 000), P2 bftma-imm 0.019 s (2 s for
100, plus 11 s compiling), P3 tma-propagation 0.315 s (31 s for 100, plus 7.6 s prepare), P4 bistatic-imm-ipda
0.226 s (113 s for 500): ~370 s CPU, ~185 s on 2 free cores before start-up and figures.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from sonartrack import studies
from sonartrack.core.random import trial_rng


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study")
    ap.add_argument("trials", type=int)
    ap.add_argument("--profile", action="store_true", help="cProfile the N trials (top 35 by cumulative time)")
    args = ap.parse_args(argv)
    mod = studies.load(args.study)
    config = mod.Config()
    t0 = time.process_time()
    if hasattr(mod, "prepare"):
        mod.prepare(config)
    t1 = time.process_time()
    mod.run_trial(config, trial_rng(2017, 0))  # warm-up: kernels compiled or loaded
    t2 = time.process_time()
    print(f"{args.study}: runs {config.runs}, prepare {t1 - t0:.1f} s CPU, first trial {t2 - t1:.2f} s", flush=True)
    prof = cProfile.Profile() if args.profile else None
    start = time.process_time()
    for i in range(1, args.trials + 1):
        if prof:
            prof.enable()
        mod.run_trial(config, trial_rng(2017, i))
        if prof:
            prof.disable()
    per = (time.process_time() - start) / args.trials
    print(f"{args.study}: {per:.3f} s CPU a trial -> {per * config.runs:.0f} s CPU for {config.runs} runs", flush=True)
    if prof:
        pstats.Stats(prof).sort_stats("cumulative").print_stats(35)


if __name__ == "__main__":
    main()
