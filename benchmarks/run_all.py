"""Run every benchmarks/bench_*.py in turn and print their lines (`make bench`).

Each benchmark is a plain script that prints one line per figure, with ratios against the peer
implementation where there is one. They run one after another so that they do not compete for the
two cores. The command line's start (bench_cli_start.py: ``sonartrack studies`` as a whole process
against Stone Soup's import) runs first, before the others have warmed or loaded the machine.
"""

import subprocess
import sys
import time
from pathlib import Path

here = Path(__file__).parent
failed = []
FIRST = "bench_cli_start.py"
for script in sorted(here.glob("bench_*.py"), key=lambda p: (p.name != FIRST, p.name)):
    print(f"== {script.stem}", flush=True)
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, str(script)], cwd=here.parent)
    print(f"   ({time.perf_counter() - t0:.0f} s)", flush=True)
    if res.returncode:
        failed.append(script.name)
if failed:
    print("benchmarks that failed: " + ", ".join(failed))
    sys.exit(1)
