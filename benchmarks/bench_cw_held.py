"""Benchmark: the active chain on CW scenes, an hour each: CPU seconds per stage, real-time factor on CPU time, and
the targets held (systems/active/targets.py ``truth_scores``) with the false targets, for the default active scene
simulated with a 1 s CW pulse and for a second CW scene (32 elements 0.3 m apart, a 2.4 kHz carrier).

Usage: ``python benchmarks/bench_cw_held.py [--seed S] [--duration-s D] [--scene default|b|both] [--profile]
[--cw NAME=VALUE ...]``
(the profile prints the 25 functions of most cumulative CPU time). Measures, not tests: no target is asserted.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import tempfile
import time
from pathlib import Path


def scene_settings(which: str, seed: int, duration_s: float):
    """The default active scene with a CW pulse ('default'), or on 32 x 0.3 m at 2.4 kHz ('b')."""
    from sonartrack.sim.active_scene import ActiveSceneSettings

    s = ActiveSceneSettings()
    sonar, wave = {}, {"kind": "cw"}
    if which == "b":
        sonar, wave["carrier_hz"] = {"elements": 32, "spacing_m": 0.3}, 2400.0
    return s.model_copy(update={"seed": seed, "duration_s": duration_s, "sonar": s.sonar.model_copy(update=sonar),
                                "waveform": s.waveform.model_copy(update=wave)})


def measure(which: str, seed: int, duration_s: float, profile: bool, dump: str | None = None,
            cw: dict | None = None) -> None:
    import pandas as pd

    from sonartrack.systems.active.files import run_active_files
    from sonartrack.systems.active.settings import ActiveSettings
    from sonartrack.systems.active.targets import mirror_targets, truth_scores
    from sonartrack.systems.simulate.active_files import write_active_scene

    scene = scene_settings(which, seed, duration_s)
    spacing = scene.sonar.spacing_m or scene.sound_speed_mps / (2.0 * scene.waveform.carrier_hz)
    with tempfile.TemporaryDirectory() as tmp:
        write_active_scene(scene, Path(tmp))
        settings = ActiveSettings(spacing_m=spacing, elements=scene.sonar.elements)
        settings = settings.model_copy(update={"cw": settings.cw.model_copy(update=cw or {})})
        prof = cProfile.Profile(time.process_time) if profile else None
        c0 = time.process_time()
        if prof:
            prof.enable()
        res = run_active_files(tmp, Path(tmp) / "nav.csv", settings)
        if prof:
            prof.disable()
        cpu = time.process_time() - c0
        truth = pd.read_csv(Path(tmp) / "truth.csv")
    truth["ebr_db"] = truth_ebr_db(scene, truth)
    if dump:
        import pickle

        Path(dump).write_bytes(pickle.dumps((res, truth)))
    targets = mirror_targets(res.tracks, res.geometry)
    scores = truth_scores(res.tracks, targets, truth, res.geometry)
    on_det = truth_scores(res.tracks, targets, detectable_rows(truth), res.geometry)["held"]
    on_snr = truth_scores(res.tracks, targets, detectable_rows(truth, column="snr_db"), res.geometry)["held"]
    stages = ", ".join(f"{k} {v:.1f}" for k, v in sorted(res.stage_seconds.items(), key=lambda kv: -kv[1]))
    nan = float("nan")
    held = " / ".join(f"{k} {100 * v:.0f}/{100 * on_det.get(k, nan):.0f}/{100 * on_snr.get(k, nan):.0f}"
                      for k, v in scores["held"].items())
    print(f"CW scene {which}, seed {seed}, {duration_s:.0f} s: CPU {cpu:.1f} s = {duration_s / cpu:.0f}x real time; "
          f"held % all/detectable by ebr/by snr {held}; false targets {scores['false_targets']} "
          f"({scores['false_targets'] * 3600 / duration_s:.1f}/h)")
    print(f"   stage wall s: {stages}")
    print("   " + detected_summary(res, truth))
    if prof:
        prof.dump_stats(f"/tmp/cw_held_{which}.prof")
        pstats.Stats(prof).sort_stats("tottime").print_stats(25)


def truth_ebr_db(scene, truth):
    """The truth rows' expected echo-to-background ratio (dB, sim/active_background.py; the study's ``ebr_db``)."""
    from sonartrack.sim.active_background import echo_background_db
    from sonartrack.sim.active_scene import ping_geometry, transmission_loss_model

    cols = {k: truth[k].to_numpy() for k in ("ping", "travel_time_s", "cone_deg", "doppler_hz", "snr_db")}
    return echo_background_db(scene, transmission_loss_model(scene), ping_geometry(scene), cols)


def detectable_rows(truth, level_db: float = 15.0, acquire_pings: int = 5, column: str | None = None):
    """The truth rows of detectable pings as the active-chain study counts them (studies/active_chain.py
    ``detectable_grid``, ``acquire_pings``): the echo's ``column`` (ebr_db, echo-to-background; snr_db,
    echo-to-noise as before the study's version 6; not given: ebr_db where the table has it (:func:`truth_ebr_db`),
    else snr_db) >= ``level_db``, in the listening window, clear of the blast, each target's first
    ``acquire_pings`` of them (its acquisition) left out."""
    column = column or ("ebr_db" if "ebr_db" in truth else "snr_db")
    ok = (truth[column] >= level_db) & truth["in_window"].astype(bool) & ~truth["in_blast"].astype(bool)
    t = truth[ok].sort_values("time_s")
    return t[t.groupby("target").cumcount() >= acquire_pings]


def detected_summary(res, truth, delay_s: float = 0.6, cone_deg: float = 8.0, rate_mps: float = 1.0) -> str:
    """Per target: the share of its pings in the listening window (after the blast) with an MFTD / a single-ping
    detection within ``delay_s``, ``cone_deg`` and ``rate_mps`` of its echo, its median echo SNR (dB, the
    simulator's echo-to-noise in one cell) and, where the truth has it, its median echo-to-background ratio."""
    import numpy as np

    out = []
    for name in dict.fromkeys(truth["target"]):
        t = truth[(truth["target"] == name) & truth["in_window"] & ~truth["in_blast"]]
        found = []
        for det in (res.mftd, res.single):
            hit = [bool(np.any(np.isclose(det.time_s, r.time_s)
                               & (np.abs(det.travel_time_s - r.travel_time_s) < delay_s)
                               & (np.abs(det.cone_deg - r.cone_deg) < cone_deg)
                               & (np.abs(det.range_rate_mps - r.range_rate_mps) < rate_mps))) for r in t.itertuples()]
            found.append(100 * np.mean(hit) if hit else float("nan"))
        ebr = f", ebr {np.nanmedian(t['ebr_db']):.1f} dB" if "ebr_db" in t else ""
        out.append(f"{name}: mftd {found[0]:.0f} %, single {found[1]:.0f} % of {len(t)} pings, snr "
                   f"{np.median(t['snr_db']):.1f} dB{ebr}")
    return "detected: " + "; ".join(out)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--duration-s", type=float, default=3600.0)
    p.add_argument("--scene", default="both", choices=["default", "b", "both"])
    p.add_argument("--profile", action="store_true")
    p.add_argument("--dump", default=None, help="pickle (result, truth) to this path + the scene's name")
    p.add_argument("--cw", action="append", default=[], metavar="NAME=VALUE",
                   help="a CwNormaliserSettings field (detection/cw_cells.py), repeatable; the value read as JSON")
    a = p.parse_args()
    cw = {k: json.loads(v) for k, v in (item.split("=", 1) for item in a.cw)}
    for which in (["default", "b"] if a.scene == "both" else [a.scene]):
        measure(which, a.seed, a.duration_s, a.profile, a.dump and f"{a.dump}.{which}", cw)


if __name__ == "__main__":
    main()
