"""Benchmark: the whole passive chain (``sonartrack passive``) on 10 and 60 minutes of 16-channel 4 kHz
recording: wall time, real-time factor and peak memory (the chain's process only).

The recordings are the default scene of ``sonartrack simulate`` (4 ships, ownship turn), written to a
temporary folder first (not timed). Target: one hour through the whole chain (beamforming, tracking,
tonal pass, side decision and TMA) in <= 36 s on this 2-core machine (>= 100x real time), and peak
memory under 1 GB whatever the recording's length (the two lengths should use about the same).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_S_PER_HOUR = 36.0


def run_measured(args: list[str]) -> tuple[float, float]:
    """(wall s, peak RSS MB) of one child process: os.wait4 gives that child's own resource usage."""
    import os

    t0 = time.perf_counter()
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"passive failed: {proc.stderr.read().decode()[-500:]}")
    return wall, usage.ru_maxrss / 1024.0


def main() -> None:
    exe = [sys.executable, "-m", "sonartrack.cli"]
    with tempfile.TemporaryDirectory() as tmp:
        for minutes in (10, 60):
            scene = Path(tmp) / f"scene{minutes}"
            subprocess.run(exe + ["simulate", "--duration-s", str(minutes * 60), "--only", "passive", "--out",
                                  str(scene)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall, peak_mb = run_measured(exe + ["passive", "--wav", str(scene / "recording.wav"), "--nav",
                                                str(scene / "nav.csv"), "--spacing", "2.5", "--out",
                                                str(Path(tmp) / f"out{minutes}")])
            verdict = (f"target <= {TARGET_S_PER_HOUR:.0f} s: {'met' if wall <= TARGET_S_PER_HOUR else 'NOT met'}"
                       if minutes == 60 else "start-up of a few seconds included; the target is for the hour")
            print(f"passive chain, {minutes} min of 16 ch x 4 kHz: {wall:.1f} s = {minutes * 60 / wall:.0f}x real time "
                  f"({verdict}), peak memory {peak_mb:.0f} MB (target < 1024)")
            (scene / "recording.wav").unlink()


if __name__ == "__main__":
    main()
