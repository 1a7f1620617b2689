"""Benchmark: throughput of the whole passive chain (``sonartrack passive`` as its own process) on line arrays of
16, 32 and 64 channels: channel-samples per second, real-time factor and peak memory.

Each recording is 10 minutes of the default scene of ``sonartrack simulate`` (4 ships, ownship turn) on the
array given (element count, spacing, sample rate), written to a temporary folder first (not timed). Target: at
32 channels x 8 kHz (twice the channels and rate of the default scene) >= 100x real time and peak memory
< 1 GB on this 2-core machine. The process's wall time includes the command line's start (a few seconds).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from bench_passive import run_measured

DURATION_S = 600.0
#: (elements, spacing m, sample rate Hz): the array's spacing is half a wavelength at 300, 600, 600 Hz
ARRAYS = ((16, 2.5, 4000.0), (32, 1.25, 8000.0), (64, 1.25, 8000.0))
TARGET_REALTIME = 100.0
TARGET_MB = 1024.0


def _scene_toml(elements: int, spacing_m: float, fs_hz: float) -> str:
    return (f"duration_s = {DURATION_S}\nsample_rate_hz = {fs_hz}\n[array]\nelements = {elements}\n"
            f"spacing_m = {spacing_m}\n[samples]\npair_elements = [1, 2]\n")


def main() -> None:
    exe = [sys.executable, "-m", "sonartrack.cli"]
    with tempfile.TemporaryDirectory() as tmp:
        for n, d, fs in ARRAYS:
            scene, toml = Path(tmp) / f"scene{n}", Path(tmp) / f"scene{n}.toml"
            toml.write_text(_scene_toml(n, d, fs))
            subprocess.run(exe + ["simulate", "--scene", str(toml), "--only", "passive", "--out", str(scene)],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall, peak_mb = run_measured(exe + ["passive", "--wav", str(scene / "recording.wav"), "--nav",
                                                str(scene / "nav.csv"), "--spacing", str(d), "--out",
                                                str(Path(tmp) / f"out{n}")])
            rate = n * fs * DURATION_S / wall
            line = (f"passive throughput, {n} ch x {fs / 1000:g} kHz ({d:g} m), 10 min: {rate / 1e6:.2f} M "
                    f"channel-samples/s, {DURATION_S / wall:.0f}x real time, peak memory {peak_mb:.0f} MB")
            if (n, fs) == (32, 8000.0):
                ok = DURATION_S / wall >= TARGET_REALTIME and peak_mb < TARGET_MB
                line += f" (target >= {TARGET_REALTIME:.0f}x and < {TARGET_MB:.0f} MB: {'met' if ok else 'NOT met'})"
            print(line, flush=True)
            (scene / "recording.wav").unlink()


if __name__ == "__main__":
    main()
