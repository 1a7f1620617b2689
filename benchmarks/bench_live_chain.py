"""Live passive chain (issue 31 items 4 and 6): the CPU share of one core at real-time rate, and a soak of 24 h of data
at high speed with the resident memory printed each simulated hour.

Part 1, CPU share (item 6): 16 channels x 4 kHz streamed through LivePassive as fast as it goes, in odd blocks, with
navigation fixes each second and the targets refreshed on the live schedule (systems/live/run.py: every 10 s of
stream, or ten refresh times when a refresh takes longer), for 75 min of data with the default 1 h history (so the
last 15 min run with the history full). The share is the process CPU time spent in the chain (refreshes included,
the generator excluded) over the data's duration: what the chain takes of one core when the data come at real-time
rate (target <= 15 %), whole run and last 15 min. Also push_block's time per window (median, 99th percentile: the
chain's part of the 1 s budget from a window's last sample to the screen; bench_live_latency.py measures the whole).

Part 2, soak (item 4): 24 h of data through the same chain, as fast as it goes, with a lighter stream (8 channels x
1 kHz: the chain's state has the same structure, a quarter of the bins; at 16 x 4 kHz the day would take ~25 min of
CPU on this machine) and a 30 min history; the targets refreshed every 15 min of data. Printed each simulated hour:
the resident memory, and the refresh time (bounded: the tonal lines come from per-track accumulators,
systems/live/tonals.py; the TMA sees the history). Then the growth from the first hour after the history filled to
the end (flat: bounded state).

The data: a cheap synthetic generator (not the simulator): per window, white noise on every element plus three
broadband sources whose cone angles drift (fractional delays applied in frequency: exact plane waves of the window's
circular transform) each with a tonal line, so the tracker, the LOFAR lines and the TMA have work.

    python benchmarks/bench_live_chain.py                  # both parts (~3 + ~7 min of CPU on this machine)
    python benchmarks/bench_live_chain.py --part soak --hours 3
"""

from __future__ import annotations

import argparse
import resource
import time
from datetime import UTC, datetime, timedelta

import numpy as np

from sonartrack.io.stream.types import NavFix, SampleBlock, StreamHeader
from sonartrack.systems.live import LivePassive
from sonartrack.systems.passive import PassiveSettings

SPACING_M, C_MPS = 2.5, 1500.0
START = datetime(2026, 12, 7, tzinfo=UTC)
#: (cone angle at 0 (deg), drift (deg/h), broadband amplitude per bin, tonal (Hz), tonal amplitude)
SOURCES = [(40.0, 30.0, 1.2, 120.0, 40.0), (100.0, -20.0, 0.9, 175.0, 30.0), (150.0, 10.0, 0.8, 90.0, 30.0)]


def synthetic_window(k: int, rng: np.random.Generator, channels: int, fs_hz: float) -> np.ndarray:
    """Window k (channels, fs_hz samples: 1 s, float32): noise plus the drifting sources (module doc)."""
    m = int(fs_hz)
    f = np.fft.rfftfreq(m, 1.0 / fs_hz)
    spec = (rng.standard_normal((channels, f.size)) + 1j * rng.standard_normal((channels, f.size))) * np.sqrt(m / 2)
    offsets = (np.arange(channels) - (channels - 1) / 2.0) * SPACING_M
    hours = k / 3600.0
    for cone0, drift, amp, tone_hz, tone_amp in SOURCES:
        cone = np.deg2rad(np.clip(cone0 + drift * hours * np.sin(2 * np.pi * hours / 6.0), 1.0, 179.0))
        s = amp * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * np.sqrt(m / 2)
        s[int(round(tone_hz))] += tone_amp * m * np.exp(2j * np.pi * rng.random())
        tau = offsets * np.cos(cone) / C_MPS
        spec += s[None, :] * np.exp(-2j * np.pi * f[None, :] * tau[:, None])
    return np.fft.irfft(spec, m, axis=1).astype(np.float32) * 1e-3


def _rss_mb() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def _nav_fix(t_s: float) -> NavFix:
    """A ship on 045 deg at 3 m/s (its own tow: the array at the ship)."""
    d = 3.0 * t_s
    lat = 54.0 + d * np.cos(np.pi / 4) / 111_320.0
    lon = 11.0 + d * np.sin(np.pi / 4) / (111_320.0 * np.cos(np.deg2rad(54.0)))
    return NavFix(START + timedelta(seconds=t_s), float(lat), float(lon), 45.0, 3.0)


class Stream:
    """The synthetic stream (module doc): windows in blocks of 0.37 s (never a window's length), a fix a second."""

    def __init__(self, channels: int, fs_hz: float, seed: int = 1):
        self.channels, self.fs_hz = channels, fs_hz
        self.rng, self.index, self.block = np.random.default_rng(seed), 0, int(0.37 * fs_hz)
        self.pending = np.zeros((channels, 0), np.float32)
        self.header = StreamHeader(channels, fs_hz, "float32", START)

    def window(self, live: LivePassive, k: int) -> list[SampleBlock]:
        """Window k's fix pushed; its blocks (made here, outside the timed part)."""
        live.push_nav(_nav_fix(k + 2.0))
        self.pending = np.concatenate([self.pending, synthetic_window(k, self.rng, self.channels, self.fs_hz)], axis=1)
        out = []
        while self.pending.shape[1] >= self.block:
            out.append(SampleBlock(self.index, self.pending[:, :self.block].T))
            self.index, self.pending = self.index + self.block, self.pending[:, self.block:]
        return out


def cpu_share(minutes: float, history_s: float, refresh_s: float) -> None:
    """Part 1 (module doc)."""
    stream = Stream(16, 4000.0)
    live = LivePassive(PassiveSettings(spacing_m=SPACING_M), stream.header, history_s=history_s)
    n, next_refresh, refresh, busy = int(minutes * 60), refresh_s, [], np.zeros(int(minutes * 60))
    for k in range(n):
        blocks = stream.window(live, k)
        t0 = time.process_time()
        for b in blocks:
            live.push_block(b)
        if k + 1 >= next_refresh:  # the live schedule on data time: refresh_s, or ten refresh times
            r0 = time.process_time()
            live.refresh()
            refresh.append(time.process_time() - r0)
            next_refresh = k + 1 + max(refresh_s, refresh[-1] / 0.1)
        busy[k] = time.process_time() - t0
    lat = 1e3 * np.array(live.latency_s)
    live.close()
    last = busy[int(history_s):] if n > history_s + 60 else busy
    print(f"live chain CPU, 16 ch x 4 kHz, {minutes:g} min of data, history {history_s:g} s, {len(refresh)} "
          f"refreshes (median {np.median(refresh):.2f} s CPU, max {max(refresh):.2f} s)")
    print(f"  push_block per window: median {np.median(lat):.1f} ms, 99th percentile {np.quantile(lat, 0.99):.1f} ms "
          "(wall; budget 1000 ms to the screen)")
    share, share_last = busy.sum() / n, last.sum() / last.size
    print(f"  CPU share of one core at real-time rate: {100 * share:.1f} % whole run, {100 * share_last:.1f} % with "
          f"the history full (target <= 15 %: ratio {max(share, share_last) / 0.15:.2f}); the generator excluded")


def soak(hours: float, history_s: float, refresh_every_s: float, channels: int, fs_hz: float) -> None:
    """Part 2 (module doc)."""
    stream = Stream(channels, fs_hz)
    live = LivePassive(PassiveSettings(spacing_m=SPACING_M), stream.header, history_s=history_s)
    n, refresh, rss, wall0, cpu0 = int(hours * 3600), [], [], time.perf_counter(), time.process_time()
    print(f"live chain soak: {hours:g} h of {channels} ch x {fs_hz:g} Hz as fast as it goes, history {history_s:g} s, "
          f"targets refreshed every {refresh_every_s:g} s of data")
    for k in range(n):
        for b in stream.window(live, k):
            live.push_block(b)
        if (k + 1) % int(refresh_every_s) == 0:
            r0 = time.process_time()
            live.refresh()
            refresh.append(time.process_time() - r0)
        if (k + 1) % 3600 == 0:
            rss.append(_rss_mb())
            hour = refresh[-int(3600 // refresh_every_s):]
            print(f"  hour {(k + 1) // 3600:2d}: resident {rss[-1]:6.0f} MB, refresh max {max(hour):.2f} s CPU, "
                  f"{len(live.last_targets['rows']) if live.last_targets else 0} targets, "
                  f"{time.perf_counter() - wall0:.0f} s wall, {time.process_time() - cpu0:.0f} s CPU so far",
                  flush=True)
    live.close()
    full = int(np.ceil((history_s + 600) / 3600))  # the first hour with the history (and the tonal ring) full
    if len(rss) > full:
        print(f"  resident memory from hour {full} to hour {len(rss)}: {rss[full - 1]:.0f} -> {rss[-1]:.0f} MB "
              f"(growth {rss[-1] - rss[full - 1]:+.0f} MB over {len(rss) - full} h; peak "
              f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0:.0f} MB); refresh CPU median "
              f"{np.median(refresh):.2f} s, max {max(refresh):.2f} s; {time.perf_counter() - wall0:.0f} s wall, "
              f"{time.process_time() - cpu0:.0f} s CPU (target <= 600 s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", choices=["cpu", "soak", "both"], default="both")
    ap.add_argument("--cpu-minutes", type=float, default=75.0)
    ap.add_argument("--hours", type=float, default=24.0)
    ap.add_argument("--soak-history-s", type=float, default=1800.0)
    ap.add_argument("--soak-channels", type=int, default=8)
    ap.add_argument("--soak-rate", type=float, default=1000.0)
    a = ap.parse_args()
    if a.part in ("cpu", "both"):
        cpu_share(a.cpu_minutes, 3600.0, 10.0)
    if a.part in ("soak", "both"):
        soak(a.hours, a.soak_history_s, 900.0, a.soak_channels, a.soak_rate)


if __name__ == "__main__":
    main()
