"""Live active chain (issue 31 items 2 and 6): the time per ping live against the file chain's on the same pings.

The default active scene (16 elements, LFM pings every 30 s, 5 targets), 600 s (20 pings), written by ``simulate
--kind active``. The file chain (``run_active`` on the ping files and nav.csv) against the live chain
(systems/live/active.py ``LiveActive``: the same per-ping core, the geometry from the ship's fixes given around
each ping as they arrive, plus the display updates: the B-scan row, the scan's tracks, the target table); both
timed in the same process (CPU time: the machine is shared) after a warm-up run (the compiled kernels loaded),
the best of two alternated runs each. Printed: ms per ping of each, their
ratio (the live chain's extra is its geometry rebuilt from the fixes and the updates), the JSON bytes a ping sends
to the console, and the live chain's time per ping against the ping interval (its share of one core at real-time
rate).

Bounded state (issue 31 item 4): 500 cheap synthetic pings (8 elements, a 3 s listening window at 1 kHz baseband,
one target's echo, every 4 s: 2000 s) through the live chain with ``history_s`` 400 s (its per-ping rows dropped
past that) and with the history unbounded: CPU per ping (median of 20 pings) at ping 50 and at ping 500, the rows
kept and the process's RSS at each.

    python benchmarks/bench_live_active.py [--bounded-only]
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from datetime import timedelta
from pathlib import Path

import numpy as np
import pandas as pd

from sonartrack.cli import main
from sonartrack.io.nmea import LocalProjection
from sonartrack.io.stream.types import NavFix, PingBlock, StreamHeader
from sonartrack.systems.active.run import run_active
from sonartrack.systems.active.scene_files import iter_pings, read_active_nav, read_ping_table
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.live.active import LiveActive
from sonartrack.systems.simulate.recording_layout import ORIGIN_DEG, START_UTC

SETTINGS = ActiveSettings(spacing_m=0.5)


def _pings(folder: Path, table) -> list[PingBlock]:
    return [PingBlock(int(n), float(t), float(table.fc_hz[i]), float(table.bandwidth_hz[i]),
                      float(table.duration_s[i]), float(table.fs_hz[i]), x)
            for i, (n, t, x) in enumerate(iter_pings(folder, table))]


def _fixes(folder: Path) -> list[NavFix]:
    nav = pd.read_csv(folder / "nav.csv")
    lat, lon = LocalProjection(*ORIGIN_DEG).latlon(nav.x_m.to_numpy(), nav.y_m.to_numpy())
    return [NavFix(START_UTC + timedelta(seconds=float(t)), float(a), float(b), float(h))
            for t, a, b, h in zip(nav.time_s, lat, lon, nav.heading_deg, strict=True)]


def _live(pings, fixes) -> tuple[float, int, list[float]]:
    """(CPU seconds, JSON bytes sent, CPU seconds per ping) of the live chain, fixes given up to each ping's
    window end."""
    header = StreamHeader(pings[0].samples.shape[0], pings[0].fs_hz, "float32", START_UTC)
    live, k, sent, per_ping = LiveActive(SETTINGS, header, source_tow_m=300.0, array_tow_m=450.0), 0, 0, []
    t0 = time.process_time()
    for p in pings:
        t1 = time.process_time()
        updates = live.push_ping(p)
        due = p.transmit_time_s + p.samples.shape[1] / p.fs_hz
        while k < len(fixes) and (fixes[k].utc - START_UTC).total_seconds() <= due:
            updates += live.push_nav(fixes[k])
            k += 1
        sent += sum(len(json.dumps(u)) for u in updates)
        per_ping.append(time.process_time() - t1)
    live.finish()
    return time.process_time() - t0, sent, per_ping


def _file(pings, table, nav) -> float:
    t0 = time.process_time()
    run_active(((p.ping, p.transmit_time_s, p.samples) for p in pings), table, nav, SETTINGS)
    return time.process_time() - t0


def run() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "scene"
        assert main(["simulate", "--kind", "active", "--duration-s", "600", "--out", str(folder)]) == 0
        table = read_ping_table(folder / "ping_table.csv")
        pings, fixes, nav = _pings(folder, table), _fixes(folder), read_active_nav(folder / "nav.csv")
        _file(pings, table, nav)  # warm-up: every kernel compiled and loaded
        file_s, live = [], []
        for _ in range(2):  # alternated, the best of two each (the machine is shared)
            file_s.append(_file(pings, table, nav))
            live.append(_live(pings, fixes))
    file_s, (live_s, sent, per_ping) = min(file_s), min(live)
    n, interval = len(pings), float(np.median(np.diff(table.transmit_time_s)))
    print(f"live active chain, {n} pings of 16 ch x {pings[0].samples.shape[1]} samples, CPU time: file chain "
          f"{1e3 * file_s / n:.0f} ms/ping, live {1e3 * live_s / n:.0f} ms/ping (ratio {live_s / file_s:.2f}; "
          f"the live one with its geometry from the fixes and the display updates)")
    print(f"live active chain: per ping median {1e3 * np.median(per_ping):.0f} ms, max {1e3 * max(per_ping):.0f} ms "
          f"(the first ping waits for the second: the interval); {sent / n / 1e3:.0f} kB of JSON a ping; "
          f"{100 * live_s / n / interval:.2f} % of one core at one ping every {interval:g} s")


def _synthetic_pings(n: int):
    """Noise and one target's echo on an 8-element array (the echo from the geometry: 1500 m abeam, closing)."""
    from sonartrack.systems.active.contacts import ActiveGeometry

    c, fc, bw, pulse_s, fs, window_s, interval_s, elements, d = 1500.0, 1500.0, 400.0, 0.1, 1000.0, 3.0, 4.0, 8, 0.5
    geometry = ActiveGeometry(np.array([-10.0, n * interval_s + 10.0]), np.array([[100.0, 0.0]] * 2),
                              np.zeros((2, 2)), np.zeros(2))
    rng, m = np.random.default_rng(7), np.arange(elements) - 0.5 * (elements - 1)
    tp = np.arange(int(pulse_s * fs)) / fs
    pulse = np.exp(1j * np.pi * (bw / pulse_s) * (tp - 0.5 * pulse_s) ** 2)

    def pings():
        for k in range(n):
            target = np.array([0.0, 1500.0 - 0.5 * k * interval_s])
            i0 = int(round((np.hypot(*(target - [100.0, 0.0])) + np.hypot(*target)) / c * fs))
            x = (rng.standard_normal((elements, int(window_s * fs))) + 1j * rng.standard_normal(
                (elements, int(window_s * fs)))) / np.sqrt(2)
            steer = np.exp(2j * np.pi * fc * m * d * target[0] / np.hypot(*target) / c)
            x[:, i0:i0 + len(pulse)] += 3.0 * steer[:, None] * pulse
            yield PingBlock(k + 1, k * interval_s, fc, bw, pulse_s, fs, x.astype(np.complex64))

    return geometry, pings(), ActiveSettings(spacing_m=d, sound_speed_mps=c)


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return float(line.split()[1]) / 1e3
    return float("nan")


def bounded(n: int = 500, history_s: float = 400.0) -> None:
    """Per-ping CPU and RSS at ping 50 and ping ``n``, bounded against unbounded (module doc)."""
    for label, h in ((f"history_s {history_s:g} s", history_s), ("unbounded", 1e12)):
        geometry, pings, settings = _synthetic_pings(n)
        live, cpu, at = None, [], {}
        for p in pings:
            if live is None:
                live = LiveActive(settings, StreamHeader(p.samples.shape[0], p.fs_hz, "float32", START_UTC),
                                  nav=geometry, history_s=h)
            t0 = time.process_time()
            live.push_ping(p)
            cpu.append(time.process_time() - t0)
            if p.ping in (50, n):
                rows = len(live.chain.tracker._rows["time_s"])
                at[p.ping] = (1e3 * float(np.median(cpu[-20:])), rows, len(live.chain.contacts), _rss_mb())
        (a_ms, a_rows, a_c, a_rss), (b_ms, b_rows, b_c, b_rss) = at[50], at[n]
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            size = live.checkpoint(Path(tmp) / "active.ckpt").stat().st_size
            write_s = time.perf_counter() - t0
        print(f"live active bounded state, {label}: per ping {a_ms:.0f} ms at ping 50, {b_ms:.0f} ms at ping {n} "
              f"(ratio {b_ms / a_ms:.2f}); tracker scans kept {a_rows} -> {b_rows}, contact pings {a_c} -> {b_c}; "
              f"RSS {a_rss:.0f} -> {b_rss:.0f} MB; a checkpoint at ping {n}: {size / 1e6:.1f} MB in "
              f"{1e3 * write_s:.0f} ms")


if __name__ == "__main__":
    if "--bounded-only" not in sys.argv[1:]:
        run()
    bounded()
