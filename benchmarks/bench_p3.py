"""Benchmarks for propagation-aware TMA (paper P3).

Prints one line per figure:
* RAM TL for the East Sea deep case (200 m source) to 80 km, cold (pyram import and numba compile
  excluded and reported apart) and from the disk cache;
* one EM/MAP solve of 100 frames (the tma-propagation scenario, South Sea summer), and the
  bearings-only Gauss-Newton/LM ML against scipy.optimize.least_squares on the same problem;
* the full tma-propagation study is run by `sonartrack reproduce tma-propagation` (its time is printed
  by that command); here it is extrapolated from a measured 4-run reproduce with every run sweeping.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of, run_timed  # noqa: E402


def bench_tl() -> None:
    """RAM TL cold (pyram import apart) and through the disk cache."""
    from sonartrack.acoustics.environment import load_environment
    from sonartrack.io.environment import cached_tl_field

    t0 = time.perf_counter()
    import pyram.PyRAM  # noqa: F401 - compile once, outside the timing

    t_import = time.perf_counter() - t0
    env = load_environment("east-summer")
    t0 = time.perf_counter()
    cached_tl_field(env, 200.0, 200.0, rmax_m=80_000.0)
    t_cold = time.perf_counter() - t0
    t_cache = best_of(lambda: cached_tl_field(env, 200.0, 200.0, rmax_m=80_000.0), 5)
    print(f"TL East Sea summer, 200 m, 200 Hz, to 80 km: cold {t_cold:.2f} s (target <= 2.5 s; pyram import "
          f"{t_import:.1f} s apart), from cache {t_cache * 1e3:.1f} ms (target < 50 ms)")


def _scenario():
    """Bearings and SNRs of one tma-propagation run, South Sea summer: (config, t, po, z, xi, ranges, snr, sb)."""
    from sonartrack.studies.tma_propagation import Config, placement, snr_curve

    cfg = Config()
    e = "south-summer"
    ranges, snr = snr_curve(cfg, e)
    r0, _ = placement(cfg, e)
    t = cfg.times_s()
    po, _, _ = cfg.observer().state(t)
    pt, _, _ = cfg.target(r0).state(t)
    d = pt - po
    rng = np.random.default_rng(1)
    sb = np.deg2rad(0.5)
    z = np.arctan2(d[:, 0], d[:, 1]) + rng.normal(0, sb, len(t))
    xi = np.interp(np.linalg.norm(d, axis=1), ranges, snr) + rng.normal(0, 1.0, len(t))
    return cfg, t, po, z, xi, ranges, snr, sb


def bench_solvers() -> None:
    """One EM/MAP solve; bearings-only ML against scipy's least_squares on the same problem."""
    from scipy.optimize import least_squares

    from sonartrack.core.angles import wrap_angle
    from sonartrack.tma.batch_ml import bearing_model, ml_bearings_only
    from sonartrack.tma.em_map import make_problem, solve_em_map

    cfg, t, po, z, xi, ranges, snr, sb = _scenario()

    def em():
        prob = make_problem(z, xi, t, po, sb, 1.0, lambda r: np.interp(r, ranges, snr), cfg.em_map.r_min_m,
                            cfg.em_map.r_max_m)
        return solve_em_map(prob)

    t_em = best_of(em, 3, repeat=3)
    print(f"EM/MAP solve, 100 frames (grid start + accelerated EM + covariance): {t_em * 1e3:.0f} ms (target < 500 ms)")

    ours = ml_bearings_only(z, t, po, sb)
    x_init = ours.x0 + np.array([800.0, -600.0, 0.5, -0.5])

    def peer():
        return least_squares(lambda x: wrap_angle(z - bearing_model(x, t, po)[0]) / sb,
                             x_init, jac=lambda x: -bearing_model(x, t, po)[1] / sb, method="lm", xtol=1e-12)

    t_ours = best_of(lambda: ml_bearings_only(z, t, po, sb, x_init=x_init), 20)
    t_peer = best_of(peer, 20)
    diff = np.max(np.abs(ml_bearings_only(z, t, po, sb, x_init=x_init).x0 - peer().x))
    print(f"bearings-only ML (Gauss-Newton/LM), 100 bearings: ours {t_ours * 1e3:.2f} ms, peer {t_peer * 1e3:.2f} ms "
          f"(scipy least_squares 'lm', same start), ratio {t_peer / t_ours:.1f} x; max |X0 diff| {diff:.1e}")


def bench_study() -> None:
    """The full study's time, extrapolated from a 4-run reproduce in which every run sweeps."""
    from sonartrack.studies.tma_propagation import Config

    with tempfile.TemporaryDirectory() as out:
        cfgfile = Path(out) / "c.toml"
        cfgfile.write_text("sweep_fraction = 1.0\n")
        res, t4, cpu4 = run_timed([sys.executable, "-m", "sonartrack.cli", "reproduce", "tma-propagation", "--runs",
                                   "4", "--config", str(cfgfile), "--workers", "2", "--out", out])
        res.check_returncode()
    # a run without the sweep costs about 2/17 of a sweeping one (measured: 0.29 s against 2.5 s of CPU)
    share = Config().sweep_fraction + (1 - Config().sweep_fraction) * 2 / 17
    full, cpu = t4 / 4 * 100 * share, cpu4 / 4 * 100 * share
    print(f"tma-propagation study, full (100 runs, 30 % sweeping 15 SL values): ~{full:.0f} s extrapolated from 4 "
          f"sweeping runs in {t4:.1f} s, 2 workers (target <= 300 s); CPU ~{cpu:.0f} s (on 2 free cores "
          f"~{cpu / 2:.0f} s)")


def main() -> None:
    os.environ["SONARTRACK_CACHE_DIR"] = tempfile.mkdtemp()
    bench_tl()
    bench_solvers()
    bench_study()


if __name__ == "__main__":
    main()
