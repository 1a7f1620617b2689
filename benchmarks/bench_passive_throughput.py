"""Benchmark: throughput of the whole passive chain (``sonartrack passive`` as its own process) on line arrays of
16, 32 and 64 channels: channel-samples per second, real-time factor and peak memory; then the share of each stage
of the chain at 16 channels x 4 kHz and 32 channels x 8 kHz with the narrowband pass on.

Each recording is 10 minutes of the default scene of ``sonartrack simulate`` (4 ships, ownship turn) on the
array given (element count, spacing, sample rate), written to a temporary folder first (not timed). Target: at
32 channels x 8 kHz (twice the channels and rate of the default scene) >= 100x real time and peak memory
< 1 GB on this 2-core machine; the chain with the narrowband pass >= 100x at 16 channels x 4 kHz. The process's
wall time includes the command line's start, the tables, figures and page. On a machine other processes load, the
wall time grows and the CPU time (user + system of the process) does not: both are printed, and the real-time
factor of the CPU time is the one an idle machine would give.

Options: ``--arrays 32x8`` runs only the arrays named (elements x kHz; default all three), ``--minutes 2`` a shorter
recording (for iterating; the targets are stated for 10 minutes).

Stage shares (at 16 x 4 kHz, and at 32 x 8 kHz, the target's size): the chain run in this process
(systems/passive/files.py ``run_passive_recording``) with a clock around each stage (CPU time): beamforming (the
front end's pass, less its LOFAR accumulation), narrowband (the LOFAR gram accumulated in the front end's pass,
then lines, line tracks, sources), tracking, tonal pass (the second pass over the recording, on the bearing-track
fragments before they are joined), TMA (sides and solutions); the rest (reading the navigation, checks) is
"other". And at 32 x 8 kHz the whole process by phase (``sonartrack passive`` in a child process with a CPU clock
around each phase): the start (interpreter and the command line's imports), reading and the chain, tables, figures,
page, the rest.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DURATION_S = 600.0
#: (elements, spacing m, sample rate Hz): the array's spacing is half a wavelength at 300, 600, 600 Hz
ARRAYS = ((16, 2.5, 4000.0), (32, 1.25, 8000.0), (64, 1.25, 8000.0))
TARGET_REALTIME = 100.0
TARGET_MB = 1024.0
#: the narrowband pass on, whatever the chain's default (the stage shares are measured with it)
NARROWBAND_TOML = "[narrowband]\nenabled = true\n"
#: and the bearing-time MFTD on as well (an option, off by default): the quiet-target front ends all at once
MFTD_TOML = NARROWBAND_TOML + "[btr_mftd]\nenabled = true\n"


def _scene_toml(elements: int, spacing_m: float, fs_hz: float, duration_s: float = DURATION_S) -> str:
    return (f"duration_s = {duration_s}\nsample_rate_hz = {fs_hz}\n[array]\nelements = {elements}\n"
            f"spacing_m = {spacing_m}\n[samples]\npair_elements = [1, 2]\n")


def run_measured(args: list[str]) -> tuple[float, float, float]:
    """(wall s, CPU s = user + system, peak RSS MB) of one child process (os.wait4: that child's own usage)."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"passive failed: {proc.stderr.read().decode()[-500:]}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def _verdict(ok_wall: bool, ok_cpu: bool) -> str:
    return f"{'met' if ok_wall else 'NOT met'} on wall time, {'met' if ok_cpu else 'NOT met'} on CPU time"


def _throughput_line(n: int, d: float, fs: float, wall: float, cpu: float, peak_mb: float,
                     duration_s: float = DURATION_S) -> str:
    samples = n * fs * duration_s
    line = (f"passive throughput, {n} ch x {fs / 1000:g} kHz ({d:g} m), {duration_s / 60:g} min: "
            f"{samples / wall / 1e6:.2f} M channel-samples/s = {duration_s / wall:.0f}x real time (wall {wall:.1f} s; "
            f"CPU {cpu:.1f} s = {samples / cpu / 1e6:.2f} M/s, {duration_s / cpu:.0f}x), peak memory {peak_mb:.0f} MB")
    if (n, fs) == (32, 8000.0):
        ok = _verdict(duration_s / wall >= TARGET_REALTIME and peak_mb < TARGET_MB,
                      duration_s / cpu >= TARGET_REALTIME and peak_mb < TARGET_MB)
        line += f" (target >= {TARGET_REALTIME:.0f}x and < {TARGET_MB:.0f} MB: {ok})"
    if (n, fs) == (16, 4000.0):
        ok = _verdict(duration_s / wall >= TARGET_REALTIME, duration_s / cpu >= TARGET_REALTIME)
        line += f" (target with the narrowband pass >= {TARGET_REALTIME:.0f}x: {ok})"
    return line


class _Clock:
    """CPU seconds spent inside wrapped functions, per stage label (a call inside another wrapped call counts
    for the inner stage only)."""

    def __init__(self):
        self.cpu: dict[str, float] = {}
        self._stack: list[list] = []

    def wrap(self, owner, name: str, label: str) -> None:
        import functools

        f = getattr(owner, name, None)
        if f is None:
            return

        @functools.wraps(f)
        def timed(*args, **kwargs):
            frame = [label, time.process_time(), 0.0]
            self._stack.append(frame)
            try:
                return f(*args, **kwargs)
            finally:
                self._stack.pop()
                spent = time.process_time() - frame[1]
                self.cpu[label] = self.cpu.get(label, 0.0) + spent - frame[2]
                if self._stack:
                    self._stack[-1][2] += spent

        setattr(owner, name, timed)


def stage_shares(scene: Path, spacing_m: float, config: Path, size: str = "16 ch x 4 kHz",
                 duration_s: float = DURATION_S) -> str:
    """One line: the chain's CPU time per stage on ``scene`` (``size``, ``duration_s`` long) with the settings of
    ``config`` (module doc)."""
    from sonartrack.acoustics import lofar
    from sonartrack.cli._settings import resolve
    from sonartrack.systems.passive import chain, narrowband
    from sonartrack.systems.passive.files import run_passive_recording
    from sonartrack.systems.passive.settings import PassiveSettings

    clock = _Clock()
    for owner, names, label in ((chain, ("bearing_time_record",), "beamforming"),
                                (lofar.LofarAccumulator, ("add", "gram"), "narrowband"),
                                (narrowband, ("narrowband_lines", "source_roles", "tonals_from_lines",
                                              "narrowband_records"), "narrowband"),
                                (chain, ("_with_mftd_peaks",), "btr mftd"),
                                (chain, ("track_peaks",), "tracking"), (chain, ("measure_tonals",), "tonal pass"),
                                (chain, ("solve_target",), "TMA")):
        for name in names:
            clock.wrap(owner, name, label)
    settings = resolve(PassiveSettings, config, spacing_m=spacing_m)  # as `sonartrack passive --config`
    c0, t0 = time.process_time(), time.perf_counter()
    run = run_passive_recording(scene / "recording.wav", scene / "nav.csv", settings)
    total, wall = time.process_time() - c0, time.perf_counter() - t0
    shares = dict(clock.cpu, other=total - sum(clock.cpu.values()))
    parts = ", ".join(f"{k} {v:.2f} s ({100 * v / total:.0f} %)" for k, v in shares.items())
    n_lines = len(getattr(run.result, "line_tracks", ()))
    mftd = ", bearing-time MFTD on" if settings.btr_mftd.enabled else ""
    return (f"passive chain stages, {size}, {duration_s / 60:g} min, narrowband on ({n_lines} line tracks){mftd}: CPU "
            f"{total:.1f} s = {duration_s / total:.0f}x real time (wall {wall:.1f} s): {parts}")


#: run in a child process: ``sonartrack passive`` as the command line runs it, with a CPU clock around its phases
_PHASES_CHILD = """
import functools, importlib, sys, time
marks = {}
def clocked(module, name, label):
    m = importlib.import_module(module)
    f = getattr(m, name)
    @functools.wraps(f)
    def timed(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            marks[label] = marks.get(label, 0.0) + time.process_time() - t
    setattr(m, name, timed)
t0 = time.process_time()
import sonartrack.cli.passive
for module, name, label in PHASES:
    clocked(module, name, label)
marks["start"] = time.process_time()
from sonartrack.cli import main
code = main(sys.argv[1:])
total = time.process_time()
marks["rest"] = total - sum(marks.values())
print(repr((code, total, marks)))
"""
#: (module, function, label) of the phases of ``sonartrack passive`` (cli/passive.py) the phase line reports
PHASES = (("sonartrack.systems.passive.files", "run_passive_recording", "reading + chain"),
          ("sonartrack.systems.passive.files", "write_passive_tables", "tables"),
          ("sonartrack.report.figures.passive", "write_passive_figures", "figures"),
          ("sonartrack.report.passive_page", "write_passive_page", "page"))


def process_phases(passive_args: list[str], size: str) -> str:
    """One line: the CPU time of ``sonartrack passive`` (a child process) by phase: the interpreter's start and
    the command line's imports ("start"), reading and the chain (with the heavy imports made on first use:
    pandas-free navigation, scipy, numba), tables, figures (with matplotlib's import), page, the rest."""
    import ast

    code = f"PHASES = {PHASES!r}\n" + _PHASES_CHILD
    out = subprocess.run([sys.executable, "-c", code, *passive_args], capture_output=True, text=True, check=True)
    status, total, marks = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    if status:
        raise SystemExit(f"passive failed: {out.stderr[-500:]}")
    parts = ", ".join(f"{k} {v:.2f} s ({100 * v / total:.0f} %)" for k, v in marks.items())
    return f"passive process phases, {size}, CPU {total:.1f} s: {parts}"


def _options() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    names = [f"{n}x{fs / 1000:g}" for n, _, fs in ARRAYS]
    parser.add_argument("--arrays", nargs="+", choices=names, default=names, help="arrays to run (elements x kHz)")
    parser.add_argument("--minutes", type=float, default=DURATION_S / 60, help="recording length (min)")
    return parser.parse_args()


def main() -> None:
    opts = _options()
    duration = 60.0 * opts.minutes
    exe = [sys.executable, "-m", "sonartrack.cli"]
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "narrowband.toml"
        config.write_text(NARROWBAND_TOML)
        for n, d, fs in ARRAYS:
            if f"{n}x{fs / 1000:g}" not in opts.arrays:
                continue
            scene, toml = Path(tmp) / f"scene{n}", Path(tmp) / f"scene{n}.toml"
            toml.write_text(_scene_toml(n, d, fs, duration))
            subprocess.run(exe + ["simulate", "--scene", str(toml), "--only", "passive", "--out", str(scene)],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            passive = ["passive", "--wav", str(scene / "recording.wav"), "--nav", str(scene / "nav.csv"),
                       "--spacing", str(d), "--config", str(config), "--out", str(Path(tmp) / f"out{n}")]
            wall, cpu, peak_mb = run_measured(exe + passive)
            print(_throughput_line(n, d, fs, wall, cpu, peak_mb, duration), flush=True)  # with the narrowband pass
            if (n, fs) == (32, 8000.0):  # where the whole process's time goes at the target's size
                print(process_phases(passive, f"{n} ch x {fs / 1000:g} kHz"), flush=True)
            if n <= 32:
                print(stage_shares(scene, d, config, f"{n} ch x {fs / 1000:g} kHz", duration), flush=True)
            if n == 16:  # every quiet-target front end on: narrowband and the bearing-time MFTD
                mftd = Path(tmp) / "mftd.toml"
                mftd.write_text(MFTD_TOML)
                wall, cpu, _ = run_measured(exe + ["passive", "--wav", str(scene / "recording.wav"), "--nav",
                                                   str(scene / "nav.csv"), "--spacing", str(d), "--config", str(mftd),
                                                   "--out", str(Path(tmp) / f"mftd{n}")])
                ok = _verdict(duration / wall >= TARGET_REALTIME, duration / cpu >= TARGET_REALTIME)
                print(f"passive with narrowband + bearing-time MFTD, {n} ch x {fs / 1000:g} kHz: "
                      f"{duration / wall:.0f}x real time (wall {wall:.1f} s; CPU {cpu:.1f} s = {duration / cpu:.0f}x; "
                      f"target >= {TARGET_REALTIME:.0f}x: {ok})", flush=True)
                print(stage_shares(scene, d, mftd, f"{n} ch x {fs / 1000:g} kHz", duration), flush=True)
            (scene / "recording.wav").unlink()


if __name__ == "__main__":
    main()
