"""Benchmark of zig detection (tma/zig.py): the sequential GLR over a 2 h record of 360 bearings.

Prints one line per figure:
* the sequential test alone (a GLR profile over every candidate change time at each of the 360 bearings) on a
  constant-velocity target seen from an ownship on 15-min legs (target: well under 1 s);
* the whole of :func:`~sonartrack.tma.zig.detect_zigs` on a target with two zigs (test, locate, fit the legs).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of  # noqa: E402

KN = 1852.0 / 3600.0


def _legs(t, p0, change_times, velocities):
    edges = np.r_[t[0], change_times, np.inf]
    a = np.clip(t[:, None] - edges[:-1], 0.0, edges[1:] - edges[:-1])
    return np.asarray(p0, float) + a @ np.asarray(velocities, float)


def _vel(course_deg, speed_kn):
    c = np.radians(course_deg)
    return speed_kn * KN * np.array([np.sin(c), np.cos(c)])


def record(zig_times, courses, speeds):
    """360 bearings over 2 h (sigma 1 deg); ownship at 6 kn on 15-min legs; target ~10 km away."""
    rng = np.random.default_rng(7)
    t = np.arange(360) * 20.0
    own = _legs(t, [0.0, 0.0], 900.0 * np.arange(1, 8), [_vel(c, 6) for c in [0, 70, 0, 70, 0, 70, 0, 70]])
    tgt = _legs(t, [8000.0, 6000.0], zig_times, [_vel(c, s) for c, s in zip(courses, speeds, strict=True)])
    sigma = np.radians(1.0)
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1]) + rng.normal(0, sigma, len(t))
    return t, z, own, sigma


def main() -> None:
    from sonartrack.tma.zig import detect_zigs, glr_threshold, sequential_glr

    t, z, own, sigma = record([], [250], [10])
    h = glr_threshold(0.1, 20.0)
    seq = best_of(lambda: sequential_glr(t, z, own, sigma, h), 1, repeat=3)
    print(f"sequential GLR, 360 bearings over 2 h (CV target): {seq * 1e3:.0f} ms (target: well under 1000 ms)")
    t, z, own, sigma = record([2405.0, 4810.0], [250, 190, 280], [10, 10, 7])
    rep = detect_zigs(t, z, own, sigma)
    full = best_of(lambda: detect_zigs(t, z, own, sigma), 1, repeat=3)
    print(f"detect_zigs with leg fit, 360 bearings, 2 zigs: {full * 1e3:.0f} ms; zigs at "
          f"{', '.join(f'{zg.time_s:.0f} s (detected {zg.detected_s:.0f} s)' for zg in rep.zigs)}; true 2405, 4810 s")


if __name__ == "__main__":
    main()
