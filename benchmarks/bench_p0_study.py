"""Benchmark: the full jpda-amplitude study (paper P0), extrapolated linearly from two measured reproduces
(10 and 30 runs, 2 workers): per-run cost from the difference, plus the fixed cost (start-up, the
end-to-end run from sound, figures)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _timing import run_timed  # noqa: E402


def main() -> None:
    times, cpus = {}, {}
    for runs in (10, 30):
        with tempfile.TemporaryDirectory() as out:
            res, times[runs], cpus[runs] = run_timed([sys.executable, "-m", "sonartrack.cli", "reproduce",
                                                      "jpda-amplitude", "--runs", str(runs), "--workers", "2",
                                                      "--out", out])
            res.check_returncode()
    per_run = (times[30] - times[10]) / 20
    fixed = times[10] - 10 * per_run
    cpu = cpus[10] + 90 * (cpus[30] - cpus[10]) / 20  # CPU of all processes, extrapolated the same way
    print(f"jpda-amplitude study, full 100 runs x 24 encounters x 2 trackers (extrapolated from 10 and 30 runs: "
          f"{times[10]:.1f} s, {times[30]:.1f} s; {per_run:.2f} s a run + {fixed:.0f} s fixed): "
          f"{fixed + 100 * per_run:.0f} s (target <= 120 s); CPU {cpu:.0f} s (on 2 free cores ~{cpu / 2:.0f} s)")


if __name__ == "__main__":
    main()
