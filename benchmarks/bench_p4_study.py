"""The full P4 study (500 runs, all five trackers) on 2 local workers: wall time against 120 s.

Runs into a fresh temporary folder so nothing is reused from an earlier run.
"""

import subprocess
import sys
import tempfile
import time

with tempfile.TemporaryDirectory() as out:
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "sonartrack.cli", "reproduce", "bistatic-imm-ipda", "--workers", "2",
                          "--out", out], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    last = res.stdout.strip().splitlines()[-1] if res.stdout.strip() else res.stderr.strip()[-300:]
    print(f"P4 study, 500 runs x 5 trackers, 2 workers: {wall:.1f} s (target <= 120 s) — {last}")
    sys.exit(res.returncode)
