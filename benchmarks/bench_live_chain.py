"""Live passive chain soak (issue 31 items 4 and 6): a day of 16 channels x 4 kHz streamed through LivePassive as fast
as it goes, in odd blocks, with navigation fixes each second and the targets refreshed on the live schedule.

Prints the latency of push_block per window (median, 99th percentile: the chain's share of the 1 s budget from a
window's last sample to the screen), the refresh time, the CPU share of one core at real-time rate (processing time
/ data time, refreshes included, against the issue's 15 % target), and the resident memory when the history has
filled, at the end, and its growth in between (flat: bounded state).

The data: a cheap synthetic generator (not the simulator): per window, white noise on every element plus three
broadband sources whose cone angles drift (fractional delays applied in frequency: exact plane waves of the window's
circular transform) each with a tonal line, so the tracker, the LOFAR lines and the TMA have work.

    python benchmarks/bench_live_chain.py                  # 24 h of data (about 20 min on one core)
    python benchmarks/bench_live_chain.py --hours 3 --history-s 1800
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

CHANNELS, FS_HZ, SPACING_M, C_MPS = 16, 4000.0, 2.5, 1500.0
START = datetime(2026, 12, 7, tzinfo=UTC)
#: (cone angle at 0 (deg), drift (deg/h), broadband amplitude per bin, tonal (Hz), tonal amplitude)
SOURCES = [(40.0, 30.0, 1.2, 120.0, 40.0), (100.0, -20.0, 0.9, 175.0, 30.0), (150.0, 10.0, 0.8, 90.0, 30.0)]


def synthetic_window(k: int, rng: np.random.Generator) -> np.ndarray:
    """Window k (CHANNELS, FS_HZ samples, float32): noise plus the drifting sources (module doc)."""
    m = int(FS_HZ)
    f = np.fft.rfftfreq(m, 1.0 / FS_HZ)
    spec = (rng.standard_normal((CHANNELS, f.size)) + 1j * rng.standard_normal((CHANNELS, f.size))) * np.sqrt(m / 2)
    offsets = (np.arange(CHANNELS) - (CHANNELS - 1) / 2.0) * SPACING_M
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


def soak(hours: float, history_s: float, refresh_s: float, seed: int = 1) -> dict:
    """Stream ``hours`` of data through the chain (module doc); the measurements."""
    rng = np.random.default_rng(seed)
    live = LivePassive(PassiveSettings(spacing_m=SPACING_M), StreamHeader(CHANNELS, FS_HZ, "float32", START),
                       history_s=history_s)
    n_windows, block = int(hours * 3600), int(0.37 * FS_HZ)  # blocks of 0.37 s: never a window's length
    pending, index, next_refresh, refresh, rss = np.zeros((CHANNELS, 0), np.float32), 0, refresh_s, [], {}
    cpu0, busy = time.process_time(), 0.0
    for k in range(n_windows):
        live.push_nav(_nav_fix(k + 2.0))
        pending = np.concatenate([pending, synthetic_window(k, rng)], axis=1)
        t0 = time.process_time()
        while pending.shape[1] >= block:
            live.push_block(SampleBlock(index, pending[:, :block].T))
            index, pending = index + block, pending[:, block:]
        if k + 1 >= next_refresh:  # the live schedule on data time: refresh_s, or ten refresh times
            r0 = time.perf_counter()
            live.refresh()
            refresh.append(time.perf_counter() - r0)
            next_refresh = k + 1 + max(refresh_s, refresh[-1] / 0.1)
        busy += time.process_time() - t0
        if k + 1 == int(history_s) + 600:
            rss["history"] = _rss_mb()
    rss["end"], rss["peak"] = _rss_mb(), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    lat = np.array(live.latency_s)
    targets = len(live.last_targets["rows"]) if live.last_targets else 0
    live.close()
    return {"targets": targets, "windows": n_windows, "latency_ms": 1e3 * lat, "refresh_s": np.array(refresh),
            "busy_s": busy,
            "total_cpu_s": time.process_time() - cpu0, "rss": rss}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hours", type=float, default=24.0)
    ap.add_argument("--history-s", type=float, default=3600.0)
    ap.add_argument("--refresh-s", type=float, default=10.0)
    a = ap.parse_args()
    m = soak(a.hours, a.history_s, a.refresh_s)
    data_s = m["windows"] * 1.0
    lat = m["latency_ms"]
    print(f"live chain soak: {a.hours:g} h of {CHANNELS} ch x {FS_HZ:g} Hz, history {a.history_s:g} s, "
          f"{len(m['refresh_s'])} refreshes, {m['targets']} targets at the end")
    print(f"  push_block per window (last {lat.size}): median {np.median(lat):.1f} ms, 99th percentile "
          f"{np.quantile(lat, 0.99):.1f} ms (budget 1000 ms to the screen)")
    if m["refresh_s"].size:
        print(f"  refresh: median {np.median(m['refresh_s']):.2f} s, max {m['refresh_s'].max():.2f} s")
    share = m["busy_s"] / data_s
    print(f"  CPU share of one core at real-time rate: {100 * share:.1f} % (target <= 15 %: ratio "
          f"{share / 0.15:.2f}); the generator excluded")
    rss = m["rss"]
    if "history" in rss:
        print(f"  resident memory: {rss['history']:.0f} MB once the history filled, {rss['end']:.0f} MB at the end "
              f"(growth {rss['end'] - rss['history']:+.0f} MB), peak {rss['peak']:.0f} MB")
    else:
        print(f"  resident memory: {rss['end']:.0f} MB at the end (the run is shorter than the history + 600 s)")


if __name__ == "__main__":
    main()
