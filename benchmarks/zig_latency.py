"""Zig latency and false zigs of the sequential test alone on the manoeuvring-target study's scenes (tma/zig.py).

Draws each trial's scene, bearing sd and noise exactly as studies/manoeuvring_target.py :func:`run_trial` does
(``trial_rng(seed, i)``), runs the sequential GLR (:func:`~sonartrack.tma.zig.sequential_glr`) at the threshold
:func:`~sonartrack.tma.zig.glr_threshold` gives for the stated rate, and scores it as the study does: a true zig is
detected within 120 s when the first crossing in (c_k, c_k+1] is at most 120 s after it; it counts when it is
*detectable* (a test at the known change time would cross h with probability >= 0.9); every unmatched crossing on
a constant-velocity scene is a false zig. The legs are not fitted (the study's latency is the sequential test's).
Usage: ``python benchmarks/zig_latency.py [rate_per_h] [first:last trial] [seed]`` (default 0.05, 0:100, 2017;
about 1-2 min of CPU for the 100 scenes). Prints one line per late or missed detectable zig and per false zig, then
the shares with their 95 % intervals.
"""

from __future__ import annotations

import sys

import numpy as np


def trial_zigs(config, seed: int, i: int, rate: float):
    """(rows of (k, c_k, latency, noncentrality linearised and not, h, turn, range), false zigs, hours, cv scene)
    of trial ``i``."""
    from sonartrack.core.random import trial_rng
    from sonartrack.sim.manoeuvre_scene import draw_manoeuvre_scene
    from sonartrack.studies.manoeuvring_target import (
        DETECT_WITHIN_S,
        bearing_sigma,
        noise_free_glr,
        noisy_bearings,
        noncentrality,
    )
    from sonartrack.tma.zig import glr_threshold, sequential_glr

    rng = trial_rng(seed, i)
    scene = draw_manoeuvre_scene(config.scene, rng)
    sigma = bearing_sigma(scene.cone_rad, float(np.radians(rng.uniform(*config.sigma_base_deg))))
    z = noisy_bearings(scene.bearing_rad, sigma, rng)
    t, own, c = scene.time_s, scene.own_xy_m, scene.change_times_s
    h = glr_threshold(rate, float(np.median(np.diff(t))))
    _, zigs = sequential_glr(t, z, own, sigma, h, window_s=config.window_s)
    ends, used, rows = np.r_[c[1:], t[-1] + 1.0], set(), []
    for k in range(len(c)):
        hits = [j for j, zg in enumerate(zigs) if c[k] < zg.detected_s <= ends[k]]
        used.update(hits[:1])
        lat = zigs[hits[0]].detected_s - c[k] if hits else np.inf
        nc = noncentrality(t, own, sigma, scene.params, c, k, c[k] + DETECT_WITHIN_S, config.window_s)
        nl = noise_free_glr(scene, sigma, k, c[k] + DETECT_WITHIN_S, config.window_s)
        xy, o = scene.target_xy_m(c[k:k + 1])[0], [np.interp(c[k], t, own[:, 0]), np.interp(c[k], t, own[:, 1])]
        rows.append((k, c[k], lat, nc, nl, h, abs(scene.turn_deg[k]), float(np.hypot(*(xy - o)))))
    return rows, len(zigs) - len(used), (t[-1] - t[0]) / 3600.0, len(c) == 0


def main() -> None:
    from scipy.stats import ncx2

    from sonartrack.studies.manoeuvring_target import Config, _poisson_rate, _share

    rate = float(sys.argv[1]) if len(sys.argv) > 1 else 0.05
    lo, hi = (int(v) for v in (sys.argv[2] if len(sys.argv) > 2 else "0:100").split(":"))
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 2017
    config = Config()
    fast, fast_nl, false, hours = [], [], 0, 0.0
    for i in range(lo, hi):
        rows, n_false, h_rec, cv = trial_zigs(config, seed, i, rate)
        for k, c, lat, nc, nl, h, turn, rng_m in rows:
            lin, nonlin = (ncx2.sf(h, 2, max(v, 1e-12)) >= 0.9 for v in (nc, nl))
            if lin:
                fast.append(float(lat <= 120.0))
            if nonlin:
                fast_nl.append(float(lat <= 120.0))
            if (lin or nonlin) and lat > 120.0:
                print(f"trial {i} zig {k} at {c:.0f} s: latency {lat:.0f} s, noncentrality {nc:.1f} linearised, "
                      f"{nl:.1f} not, h {h:.1f}, turn {turn:.0f} deg, range {rng_m / 1e3:.1f} km", flush=True)
        if cv:
            false, hours = false + n_false, hours + h_rec
            if n_false:
                print(f"trial {i}: {n_false} false zig(s)", flush=True)
    n = _share(np.array(fast_nl))
    print(f"rate {rate:g}/h, detectable by the noise-free GLR: within 120 s {n['k']}/{n['n']} = {n['share']:.3f} "
          f"[{n['low']:.2f}, {n['high']:.2f}]")
    s, f = _share(np.array(fast)), _poisson_rate(false, hours)
    print(f"rate {rate:g}/h, detectable by the linearised noncentrality: within 120 s {s['k']}/{s['n']} = "
          f"{s['share']:.3f} [{s['low']:.2f}, {s['high']:.2f}]")
    print(f"false zigs {f['k']} in {f['hours']:.1f} h = {f['rate']:.3f}/h [{f['low']:.3f}, {f['high']:.3f}]")


if __name__ == "__main__":
    main()
