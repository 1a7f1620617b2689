"""The full P4 study (500 runs, all five trackers) on 2 local workers: wall time against 120 s.

Runs into a fresh temporary folder so nothing is reused from an earlier run.
"""

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _timing import run_timed  # noqa: E402

with tempfile.TemporaryDirectory() as out:
    res, wall, cpu = run_timed([sys.executable, "-m", "sonartrack.cli", "reproduce", "bistatic-imm-ipda", "--workers",
                                "2", "--out", out])
    last = res.stdout.strip().splitlines()[-1] if res.stdout.strip() else res.stderr.strip()[-300:]
    print(f"P4 study, 500 runs x 5 trackers, 2 workers: {wall:.1f} s (target <= 120 s); CPU {cpu:.0f} s (on 2 free "
          f"cores ~{cpu / 2:.0f} s) — {last}")
    sys.exit(res.returncode)
