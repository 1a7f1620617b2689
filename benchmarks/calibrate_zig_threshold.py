"""Calibration of the zig test's threshold (tma/zig.py): false zigs per hour of constant-velocity records, by
bearing interval and threshold, against the tail form the threshold is set from.

Records: the manoeuvring-target study's scene family (sim/manoeuvre_scene.py) with every target at constant
velocity (5-20 km, 4-15 kn, ownship on leg-turn-leg, zig-zag or constant-turn patterns), 60-90 min, bearings every
``dt`` s exactly, each bearing's sd the line array's law sigma_base / max(|sin cone|, 0.05) with sigma_base drawn
in 0.5-1 deg (the study's). The sequential test (:func:`~sonartrack.tma.zig.sequential_glr`, window 1800 s) is
run at each threshold h; every detection is a false zig. Printed per (dt, h): false zigs, hours and the rate per
hour; per dt, the Poisson ML of the tail form's scale over the thresholds (tma/zig.py module doc),

    K = false zigs / (hours x sum_h (h / 2)^2 exp(-h / 2))   (with the Garwood 95 % interval of the count),

beside the table's K (tma/zig.py :func:`~sonartrack.tma.zig.tail_scale_per_hour`), which was made from this output.
Usage: ``python benchmarks/calibrate_zig_threshold.py [hours_per_dt] [dt,dt,...]`` (default 12 h per interval, the
intervals 2, 5, 10, 30, 60 s; about 2.5 min of CPU per 10 h at dt = 2 s with the four thresholds, less at longer
intervals). Each interval's records depend on dt and the hours only, so intervals run apart give the same
numbers.
"""

from __future__ import annotations

import sys

import numpy as np

INTERVALS_S = (2.0, 5.0, 10.0, 30.0, 60.0)
THRESHOLDS = (9.0, 12.0, 15.0, 18.0)


def cv_records(dt: float, hours: float, seed: int):
    """(t, z, own, sigma) constant-velocity records of the study's family at bearing interval dt, ``hours`` long."""
    from sonartrack.sim.manoeuvre_scene import ManoeuvreSceneSettings, draw_manoeuvre_scene
    from sonartrack.studies.manoeuvring_target import bearing_sigma, noisy_bearings

    rng = np.random.default_rng(seed)
    fam = ManoeuvreSceneSettings(cv_share=1.0, bearing_interval_s=[dt, dt])
    total = 0.0
    while total < hours * 3600.0:
        scene = draw_manoeuvre_scene(fam, rng)
        sigma = bearing_sigma(scene.cone_rad, float(np.radians(rng.uniform(0.5, 1.0))))
        z = noisy_bearings(scene.bearing_rad, sigma, rng)
        total += scene.time_s[-1] - scene.time_s[0]
        yield scene.time_s, z, scene.own_xy_m, sigma


def garwood(k: int) -> tuple[float, float]:
    """The exact 95 % interval of a Poisson mean from a count k (Garwood 1936, Biometrika 28)."""
    from scipy.stats import chi2

    return (float(chi2.ppf(0.025, 2 * k) / 2.0) if k else 0.0), float(chi2.ppf(0.975, 2 * (k + 1)) / 2.0)


def main() -> None:
    from sonartrack.tma.zig import sequential_glr, tail_scale_per_hour

    hours = float(sys.argv[1]) if len(sys.argv) > 1 else 12.0
    intervals = [float(v) for v in sys.argv[2].split(",")] if len(sys.argv) > 2 else INTERVALS_S
    form = np.array([(h / 2) ** 2 * np.exp(-h / 2) for h in THRESHOLDS])
    for dt in intervals:
        counts, total_s = np.zeros(len(THRESHOLDS)), 0.0
        for t, z, own, sigma in cv_records(dt, hours, seed=int(dt * 10)):
            total_s += t[-1] - t[0]
            for j, h in enumerate(THRESHOLDS):
                counts[j] += len(sequential_glr(t, z, own, sigma, h)[1])
        for j, h in enumerate(THRESHOLDS):
            print(f"dt {dt:4.0f} s  h {h:4.1f}: {counts[j]:3.0f} false zigs in {total_s / 3600:5.1f} h = "
                  f"{counts[j] / (total_s / 3600.0):6.3f} per h", flush=True)
        k_lo, k_hi = (v / (total_s / 3600.0 * form.sum()) for v in garwood(int(counts.sum())))
        print(f"dt {dt:4.0f} s: K = {counts.sum() / (total_s / 3600.0 * form.sum()):.2f} [{k_lo:.2f}, {k_hi:.2f}] "
              f"per h (table: {tail_scale_per_hour(dt):.2f})", flush=True)


if __name__ == "__main__":
    main()
