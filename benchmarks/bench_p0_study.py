"""Benchmark: the full jpda-amplitude study (paper P0), extrapolated linearly from two measured reproduces
(10 and 30 runs, 2 workers): per-run cost from the difference, plus the fixed cost (start-up, the
end-to-end run from sound, figures)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time


def main() -> None:
    times = {}
    for runs in (10, 30):
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "sonartrack.cli", "reproduce", "jpda-amplitude", "--runs", str(runs),
                            "--workers", "2", "--out", out], check=True, capture_output=True)
            times[runs] = time.perf_counter() - t0
    per_run = (times[30] - times[10]) / 20
    fixed = times[10] - 10 * per_run
    print(f"jpda-amplitude study, full 100 runs x 24 encounters x 2 trackers (extrapolated from 10 and 30 runs: "
          f"{times[10]:.1f} s, {times[30]:.1f} s; {per_run:.2f} s a run + {fixed:.0f} s fixed): "
          f"{fixed + 100 * per_run:.0f} s (target <= 120 s)")


if __name__ == "__main__":
    main()
