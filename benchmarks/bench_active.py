"""Benchmark: the whole active chain (``sonartrack active``) on 10 minutes and one hour of pings (20 and 120 pings
at 30 s; the default 1 s LFM of 100 Hz at 200 Hz complex sampling on 16 channels, then the hour again with a 1 s
CW pulse and with 32 channels, issue 34's item 7): wall time, real-time factor, peak memory (the chain's process
only) and each stage's share of the time.

The scenes are the default active scene of ``sonartrack simulate --kind active`` (sim/active_scene.py), written to
a temporary folder first (not timed). The chain runs in a child process (start-up, numba loading and the MFTD
threshold calibration included, as a user's run has them), which prints its stage timings
(systems/active/run.py ``ActiveResult.stage_seconds``) and writes the output files. Target: the hour in <= 36 s
on this 2-core machine (>= 100x real time; the child's CPU time is printed too: on a shared machine the wall time
is not the chain's); peak memory under 1 GB whatever the number of pings (the two runs
should use about the same); the MFTD across pings must not dominate.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_S_PER_HOUR = 36.0

CHILD = """
import json, sys, time
t0 = time.perf_counter()
from sonartrack.systems.active.files import run_active_files, write_active_tables
from sonartrack.systems.active.settings import ActiveSettings
folder, out = sys.argv[1], sys.argv[2]
res = run_active_files(folder, folder + "/nav.csv", ActiveSettings(spacing_m=0.5, elements=int(sys.argv[3])))
t1 = time.perf_counter()
write_active_tables(res, out)
stages = dict(res.stage_seconds)
stages["start-up and files"] = (time.perf_counter() - t0) - sum(res.stage_seconds.values())
print(json.dumps({"stages": stages, "pings": len(res.ping_time_s), "tracks": int(res.tracks.tracks.confirmed.sum())}))
"""


def run_measured(args: list[str]) -> tuple[float, float, dict]:
    """(wall s, peak RSS MB, the child's JSON line with its CPU seconds added as "cpu_s") of one child process
    (os.wait4: that child's own usage)."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    out, err = proc.stdout.read().decode(), proc.stderr.read().decode()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"active failed: {err[-800:]}")
    info = json.loads(out.strip().splitlines()[-1])
    info["cpu_s"] = usage.ru_utime + usage.ru_stime
    return wall, usage.ru_maxrss / 1024.0, info


def write_scene(folder: Path, pings: int, pulse: str, elements: int) -> None:
    from sonartrack.sim.active_scene import ActiveSceneSettings
    from sonartrack.systems.simulate.active_files import write_active_scene

    scene = ActiveSceneSettings()
    sonar = scene.sonar.model_copy(update={"elements": elements, "spacing_m": 0.5})
    waveform = scene.waveform.model_copy(update={"kind": pulse})
    write_active_scene(scene.model_copy(update={"duration_s": pings * scene.ping_interval_s, "sonar": sonar,
                                                "waveform": waveform}), folder)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        for pings, pulse, elements in ((20, "lfm", 16), (120, "lfm", 16), (120, "cw", 16), (120, "lfm", 32),
                                       (120, "cw", 32)):
            name = f"{pulse}{elements}x{pings}"
            scene = Path(tmp) / name
            write_scene(scene, pings, pulse, elements)
            wall, peak_mb, info = run_measured([sys.executable, "-c", CHILD, str(scene), str(Path(tmp) / f"o{name}"),
                                                str(elements)])
            stages = info["stages"]
            total = sum(stages.values())
            shares = ", ".join(f"{k} {100 * v / total:.0f} %" for k, v in sorted(stages.items(), key=lambda kv: -kv[1]))
            hours = pings * 30.0 / 3600.0
            verdict = (f"target <= {TARGET_S_PER_HOUR:.0f} s: {'met' if wall <= TARGET_S_PER_HOUR else 'NOT met'}"
                       if pings == 120 else "start-up included; the target is for the hour")
            cpu = info["cpu_s"]
            print(f"active chain, {pulse.upper()}, {pings} pings x {elements} ch ({hours * 60:.0f} min): "
                  f"{wall:.1f} s = {hours * 3600 / wall:.0f}x real time ({verdict}), "
                  f"CPU {cpu:.1f} s = {hours * 3600 / cpu:.0f}x real time (a shared machine: the CPU time is the "
                  f"measure), peak memory {peak_mb:.0f} MB (target < 1024)")
            print(f"   stage shares: {shares}")
            for f in (scene / "pings").glob("*.npy"):
                f.unlink()


if __name__ == "__main__":
    main()
