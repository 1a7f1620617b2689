"""Benchmark: false confirmed tracks per hour of the active chain on clutter it was not tuned on, and the acquisition
delay of a 15 dB target, on pings from the independent generator tests/worlds/active_pings.py (not our simulator).

Clutter models (reverberation only, no target): Rayleigh; K-distributed texture of shape 2, 1, 0.5; Rayleigh with
the direct blast of the towed source; K 1 with the blast and persistent clutter points. Each is run for ``--hours``
of pings (30 s apart, 12 s listening, 16 elements x 0.5 m, LFM 1 s x 100 Hz at 1.5 kHz, an ownship turn) and the
confirmed tracks are counted (every confirmed track of a reverberation-only recording is false) with an exact
Poisson 95 % interval (Garwood 1936). Acquisition: a target of 15 dB echo-to-background (steady, and Swerling 1) that
appears at a ping (``start_s``) within the window; the delay is the number of pings from its first echo to the first
ping at which a confirmed track lies within 500 m of it (1 = confirmed on its first ping).

The chain measured is the one on the path, with its default settings; "before" is measured by putting the code
before issue 34 first on the path (``git archive 9db87d5 src | tar -x -C /tmp/base``). Run:

    PYTHONPATH=src python benchmarks/bench_active_clutter.py [--hours 1] [--label new] [--models all]
        [--false-tracks-per-h F]   # confirmation at a stated rate (tracking/existence.py) instead of 0.99

Measured (2026-12-07, shared machine, 0.5 h per model, seeds as here; false confirmed tracks/h [95 %]):
    confirmation 0.99 (the default; h-clutter's runs): Rayleigh, K: 0 [0, 7.4]; K 1 + blast + points 28 [15, 47]
    --false-tracks-per-h 1: rayleigh+blast 0 [0, 7.4], K 0.5 0 [0, 7.4], K 1 + blast + points 34 [20, 54]
        (+ --clutter-map 8,3: 8 [2.2, 20]): the still points are real echoes, which the rule cannot call false
    --false-tracks-per-h 1 --strong-pfa 1e-6: Rayleigh, K 1, K 0.5: 0 [0, 7.4] each
Since h9-clutter the defaults are the rule at 1/h, mftd_strong_pfa 1e-6 and the clutter map with its stillness test
(clutter_map_pings 8); the measurement of those defaults together is bench_active_defaults.py (same worlds, front
ends cached).
Acquisition of a 15 dB steady target on K 1 (pings from its first echo to a confirmed track; seeds 3500..):
    0.99: 8, 8 (runs 0, 1); the MFTD's first contact comes on the target's 3rd ping, then the existence grows
    0.05, 0.15, 0.4, 0.8, 0.97, 0.99 a ping; --false-tracks-per-h 1: 6, 6 (threshold ~0.8 here, few tracks start);
    single-ping detector + rule: 5, 5 (first contact on its 1st ping); rule + --strong-pfa 1e-9: 6, 5; 1e-7: 6, 4;
    1e-6: 4, 4, 9, 4 (runs 0-3; run 2 lost its 3rd echo)
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from worlds.active_pings import Target, World, nav_rows, ping, ping_table_rows  # noqa: E402

#: the clutter models: name -> World fields (reverberation only)
SPIKY = {"patch_m": 0.0, "sectors": 40}  # a texture per scatterer, a few scatterers per beam-delay cell
MODELS = {
    "rayleigh": {},
    "K nu=2": {"texture_shape": 2.0, **SPIKY},
    "K nu=1": {"texture_shape": 1.0, **SPIKY},
    "K nu=0.5": {"texture_shape": 0.5, **SPIKY},
    "K nu=0.5 patches": {"texture_shape": 0.5},
    "rayleigh+blast": {"blast": True},
    "K nu=1+blast+points": {"texture_shape": 1.0, **SPIKY, "blast": True,
                            "clutter_xy": ((2500.0, 4000.0), (-3000.0, 2000.0), (1500.0, -4000.0), (-2000.0, 6000.0),
                                           (3500.0, 500.0), (-4000.0, -1500.0)), "clutter_ts_db": 35.0},
}


def base_world(hours: float, seed: int, **fields) -> World:
    """The measurement world: ``hours`` of 30 s pings, an ownship turn of 60 deg at 0.2 deg/s a third of the way."""
    pings = max(int(round(hours * 3600 / 30.0)), 2)
    return World(pings=pings, seed=seed, turn_start_s=pings * 30.0 / 3, turn_deg=-60.0, turn_rate_deg_s=0.2,
                 **fields)


def records(w: World):
    """The world's ping table and navigation as the chain's records."""
    from sonartrack.systems.active.records import ActiveNav, PingTable

    t = ping_table_rows(w)
    table = PingTable(np.asarray(t["ping"]), np.asarray(t["transmit_time_s"], float), np.asarray(t["file"]),
                      np.asarray(t["waveform"]), np.asarray(t["fc_hz"], float), np.asarray(t["bandwidth_hz"], float),
                      np.asarray(t["duration_s"], float), np.asarray(t["fs_hz"], float), np.asarray(t["channels"]),
                      np.asarray(t["samples"]))
    n = nav_rows(w)
    nav = ActiveNav(n["time_s"], np.stack([n["x_m"], n["y_m"]], -1), np.unwrap(np.deg2rad(n["heading_deg"])),
                    np.stack([n["source_x_m"], n["source_y_m"]], -1), np.stack([n["array_x_m"], n["array_y_m"]], -1),
                    np.unwrap(np.deg2rad(n["array_heading_deg"])))
    return table, nav


def run_world(w: World, settings):
    """The chain over the world's pings (generated on the fly); returns (result, truth rows)."""
    from sonartrack.systems.active.run import run_active

    truth: list[dict] = []

    def pings():
        for k in range(w.pings):
            x, rows = ping(w, k)
            truth.extend(rows)
            yield k + 1, k * w.interval_s, x

    table, nav = records(w)
    return run_active(pings(), table, nav, settings), truth


def poisson_interval(k: int, conf: float = 0.95) -> tuple[float, float]:
    """Exact (Garwood) interval of a Poisson mean from a count k."""
    from scipy.stats import chi2

    a = 1 - conf
    lo = 0.0 if k == 0 else chi2.ppf(a / 2, 2 * k) / 2
    return float(lo), float(chi2.ppf(1 - a / 2, 2 * k + 2) / 2)


def confirmed_tracks(result) -> int:
    """Distinct confirmed tracks of a result."""
    tr = result.tracks.tracks
    return int(len(np.unique(tr.track_id[tr.confirmed])))


def acquisition_delay(result, truth: list[dict], gate_m: float = 500.0) -> int | None:
    """Pings from the target's first echo to the first ping with a confirmed track within ``gate_m`` (1: its first
    ping); None if never."""
    tr = result.tracks.tracks
    for n, row in enumerate(sorted(truth, key=lambda r: r["ping"])):
        at = (tr.time_s == row["time_s"]) & tr.confirmed
        if at.any() and np.hypot(tr.x[at, 0] - row["x_m"], tr.x[at, 1] - row["y_m"]).min() < gate_m:
            return n + 1
    return None


#: settings changed from the defaults for a run (``--false-tracks-per-h``: tracker confirmation at a stated rate)
OVERRIDES: dict = {}


def chain_settings():
    """The chain's default settings (the code measured is the one on the path: module doc), with ``OVERRIDES``."""
    from sonartrack.systems.active.settings import ActiveSettings

    return ActiveSettings(spacing_m=0.5, **OVERRIDES)


def measure_false(models, hours: float, which: str, seed0: int = 3400) -> dict:
    out = {}
    for j, name in enumerate(models):
        w = base_world(hours, seed0 + j, **MODELS[name])
        t0 = time.perf_counter()
        res, _ = run_world(w, chain_settings())
        k = confirmed_tracks(res)
        h = w.pings * w.interval_s / 3600.0
        lo, hi = poisson_interval(k)
        out[name] = (k, h, lo / h, hi / h)
        print(f"  {which:>3} {name:<22} {k:3d} confirmed in {h:.2f} h = {k / h:5.2f}/h  [{lo / h:.2f}, {hi / h:.2f}]"
              f"  ({time.perf_counter() - t0:.0f} s)", flush=True)
    return out


def measure_acquisition(which: str, runs: int, swerling: bool, seed0: int = 3500) -> list:
    delays = []
    for r in range(runs):
        rng = np.random.default_rng(seed0 + r)
        ang = rng.uniform(0, 2 * np.pi)
        rad = rng.uniform(3000.0, 6000.0)
        tgt = Target(rad * np.sin(ang), rad * np.cos(ang), *(2.0 * rng.standard_normal(2)), ebr_db=15.0,
                     start_s=90.0, swerling=swerling)
        w = replace(base_world(0.1, seed0 + r, texture_shape=1.0), pings=14, targets=(tgt,))
        res, truth = run_world(w, chain_settings())
        delays.append(acquisition_delay(res, truth))
    return delays


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--label", default="new")
    ap.add_argument("--models", default="all")
    ap.add_argument("--acq-runs", type=int, default=10)
    ap.add_argument("--false-tracks-per-h", type=float, default=None,
                    help="confirm at this stated false-track rate (tracker setting false_tracks_per_h)")
    ap.add_argument("--strong-pfa", type=float, default=None, help="mftd_strong_pfa: strong single-ping detections "
                    "join the MFTD's")
    ap.add_argument("--clutter-map", default=None, help="PINGS,HITS: the clutter map on (clutter_map_pings, _hits)")
    a = ap.parse_args()
    if a.clutter_map:
        pings, hits = map(int, a.clutter_map.split(","))
        OVERRIDES.update(clutter_map_pings=pings, clutter_map_hits=hits)
    if a.strong_pfa is not None:
        OVERRIDES["mftd_strong_pfa"] = a.strong_pfa
    if a.false_tracks_per_h is not None:
        OVERRIDES["tracker"] = {"false_tracks_per_h": a.false_tracks_per_h}
    models = list(MODELS) if a.models == "all" else a.models.split(",")
    for which in [a.label]:
        print(f"false confirmed tracks, reverberation only ({which} chain):")
        measure_false(models, a.hours, which)
        for sw in (False, True):
            d = measure_acquisition(which, a.acq_runs, sw)
            ok = [x for x in d if x is not None]
            print(f"  {which:>3} acquisition of a 15 dB {'Swerling 1' if sw else 'steady'} target: pings {d}; "
                  f"within 5: {sum(x <= 5 for x in ok)}/{len(d)}", flush=True)


if __name__ == "__main__":
    main()
