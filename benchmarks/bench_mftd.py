"""Benchmarks for multi-frame track-before-detect (paper P1).

Prints one line per figure:
* one K = 6, N = 10 detection on a 64 x 64 plane: the compiled detector against the NumPy
  reference (same statistic), with and without restricted branching;
* a whole ROC curve down to Pfa = 1e-3 (10000 target-absent + 2000 target-present stacks of the
  study's plane) with 2 worker processes;
* the full mftd study (10000 runs), extrapolated linearly from two measured reproduces (500 and 1500
  runs, 2 workers): per-trial cost from the difference, plus the fixed cost (start-up, summary, figures).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of  # noqa: E402


def _roc_chunk(args):
    start, count, present = args
    from sonartrack.core.random import trial_rng
    from sonartrack.detection.mftd import MftdDetector
    from sonartrack.sim.range_doppler import simulate_frames, simulate_target
    from sonartrack.studies.mftd import Config

    cfg = Config()
    grid = cfg.grid()
    det = MftdDetector(grid, cfg.detector)
    out = []
    for i in range(start, start + count):
        rng = trial_rng(7, i)
        d = cfg.detector
        cells = simulate_target(rng, grid, d.period_s, d.sigma_a_mps2, cfg.n_frames).cells if present else None
        out.append(det.detect(simulate_frames(rng, grid, cfg.n_frames, det.snr, cells), checked=True).statistic)
    return out


def main() -> None:
    from sonartrack.detection.mftd import MftdDetector, MftdSettings
    from sonartrack.detection.mftd_reference import pruned_detect
    from sonartrack.metrics.roc import roc_curve
    from sonartrack.models.range_doppler import RangeDopplerGrid
    from sonartrack.sim.range_doppler import simulate_frames, simulate_target

    rng = np.random.default_rng(0)
    grid = RangeDopplerGrid.cw(64, 64, 0.125, 30e3, 1500.0)
    det = MftdDetector(grid, MftdSettings(snr_db=5.0, sigma_a_mps2=1.0, n_tracks=10, prior_density="smoothed"))
    track = simulate_target(rng, grid, 2.0, 1.0, 6)
    y = simulate_frames(rng, grid, 6, det.snr, track.cells)
    prior = det.prior(6)
    fast = det.detect(y, checked=True)
    ref = pruned_detect(y, grid, prior, det.snr, 10, restrict=True)
    ref_full = pruned_detect(y, grid, prior, det.snr, 10, restrict=False)
    t_fast = best_of(lambda: det.detect(y, checked=True), 50)
    t_ref = best_of(lambda: pruned_detect(y, grid, prior, det.snr, 10, restrict=True, checked=True), 10)
    t_full = best_of(lambda: pruned_detect(y, grid, prior, det.snr, 10, restrict=False, checked=True), 5)
    print(f"MFTD K=6 N=10 64x64 detection: ours (compiled, restricted) {t_fast * 1e3:.2f} ms, NumPy reference "
          f"{t_ref * 1e3:.2f} ms, ratio {t_ref / t_fast:.1f} x; unrestricted NumPy {t_full * 1e3:.2f} ms, ratio "
          f"{t_full / t_fast:.1f} x (target < 5 ms; |statistic diff| {abs(fast.statistic - ref_full.statistic):.1e} "
          f"to the unrestricted, {abs(fast.statistic - ref.statistic):.1e} to the restricted reference)")

    n0, n1, chunk = 10000, 2000, 500
    jobs = [(s, chunk, False) for s in range(0, n0, chunk)] + [(s, chunk, True) for s in range(n0, n0 + n1, chunk)]
    _roc_chunk((0, 1, True))  # compile in this process too (numba caches on disk for the workers)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(2) as pool:
        res = list(pool.map(_roc_chunk, jobs))
    t_roc = time.perf_counter() - t0
    h0 = np.concatenate(res[: n0 // chunk])
    h1 = np.concatenate(res[n0 // chunk:])
    c = roc_curve(h0, h1, [1e-3, 1e-2, 1e-1])
    print(f"MFTD ROC curve to Pfa=1e-3 ({n0} H0 + {n1} H1 stacks, 16x64 plane, 2 workers): {t_roc:.1f} s "
          f"(target <= 60 s); Pd at 1e-3/1e-2/1e-1 = {c.pd[0]:.3f}/{c.pd[1]:.3f}/{c.pd[2]:.3f}", flush=True)

    times = {}
    for runs in (500, 1500):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "sonartrack.cli", "reproduce", "mftd", "--runs", str(runs),
                            "--workers", "2", "--out", tmp], check=True, capture_output=True)
            times[runs] = time.perf_counter() - t0
    per_trial = (times[1500] - times[500]) / 1000
    fixed = times[500] - 500 * per_trial
    print(f"mftd study, full 10000 runs (extrapolated from 500 and 1500-run reproduces, {times[500]:.1f} s and "
          f"{times[1500]:.1f} s, 2 workers: {per_trial * 1e3:.1f} ms a trial + {fixed:.0f} s fixed): "
          f"{fixed + 10000 * per_trial:.0f} s (target <= 300 s)")


if __name__ == "__main__":
    main()
