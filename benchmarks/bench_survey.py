"""Benchmark: survey throughput (hours of recording per hour of wall time) and Dask scheduling overhead.

One 120 s recording of the default passive scene (16 channels at 4 kHz) is simulated, and a manifest lists it
eight times (hard links, distinct names). The survey (systems/survey/run.py) runs it in this process (1 worker)
and on a local Dask cluster of 2 single-threaded worker processes; the cluster's wall time is given with and
without its start and teardown (measured on one recording that fails at once).
Overhead per recording on the cluster: on a warm cluster, 40 recordings that fail at once (a missing file)
submitted, returned and stored -- a task's round trip and the storing of its folder, without the chain.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

DURATION_S, COPIES = 120.0, 8


def _manifest(folder: Path, lines: list[str]) -> Path:
    path = folder / f"manifest{len(lines)}.csv"
    path.write_text("recording,navigation,spacing_m,name\n" + "\n".join(lines) + "\n")
    return path


def _timed(manifest: Path, out: Path, workers: int) -> tuple[float, object]:
    from sonartrack.systems.survey.manifest import read_manifest
    from sonartrack.systems.survey.run import run_survey

    t0 = time.perf_counter()
    summary = run_survey(read_manifest(manifest), out, workers=workers)
    return time.perf_counter() - t0, summary


def _cluster_start(d: Path) -> float:
    """Wall time of a survey of one recording that fails at once: the cluster's start and teardown."""
    return _timed(_manifest(d, ["none.wav,sim/nav.csv,2.5,none"]), d / "o1", 2)[0]


def _overhead_ms(d: Path, n: int = 40) -> float:
    """Per task on a warm 2-worker cluster: submit, run a recording that fails at once, return, store (ms)."""
    from distributed import Client, LocalCluster, as_completed

    from sonartrack.systems.survey.files import store_outcome
    from sonartrack.systems.survey.manifest import read_manifest
    from sonartrack.systems.survey.recording import run_recording

    entries = read_manifest(_manifest(d, [f"none{k}.wav,sim/nav.csv,2.5,n{k}" for k in range(n)]))
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as c:
        c.gather([c.submit(run_recording, e, pure=False) for e in entries[:2]])  # warm: imports done
        t0 = time.perf_counter()
        futures = {c.submit(run_recording, e, pure=False, key=f"t-{e.name}"): e for e in entries}
        for fut in as_completed(list(futures)):
            store_outcome(d / "overhead", futures[fut], fut.result())
        return (time.perf_counter() - t0) / n * 1e3


def main() -> None:
    from sonartrack.cli import main as cli

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        (d / "scene.toml").write_text(f"duration_s = {DURATION_S}\n")
        assert cli(["simulate", "--scene", str(d / "scene.toml"), "--only", "passive", "--out", str(d / "sim")]) == 0
        for k in range(COPIES):
            os.link(d / "sim" / "recording.wav", d / f"rec{k}.wav")
        real = _manifest(d, [f"rec{k}.wav,sim/nav.csv,2.5,r{k}" for k in range(COPIES)])
        hours = COPIES * DURATION_S / 3600.0
        start = _cluster_start(d)
        for workers in (1, 2):
            wall, summary = _timed(real, d / f"out{workers}", workers)
            assert summary.ok == COPIES, summary.rows
            net = f"; {hours / ((wall - start) / 3600.0):.0f} without the cluster's start" if workers > 1 else ""
            print(f"survey, {workers} worker(s){' (local Dask cluster)' if workers > 1 else ''}: "
                  f"{hours / (wall / 3600.0):.0f} hours of recording per hour{net} ({COPIES} x {DURATION_S:g} s of "
                  f"16 channels at 4 kHz in {wall:.1f} s)")
        print(f"survey on a local Dask cluster: {_overhead_ms(d):.0f} ms of scheduling and storing per recording "
              f"(cluster start and teardown {start:.1f} s)")

if __name__ == "__main__":
    main()
