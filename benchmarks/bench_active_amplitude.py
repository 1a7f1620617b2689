"""Benchmark: amplitude-aided IPDA (tracker ``amplitude_aided``) on the active-chain study's reverberation-only twins:
false confirmed tracks with and without it on the same contacts.

Each trial's twin (bench_active_family.py ``trial_scene``: the study's scene of that index, targets removed, clutter
points kept) is run once through the chain at the defaults (front end, detectors, contacts; the chain's result and the
ContactTracker's arguments cached as a pickle under ``--cache``), then its tracker stage is re-run on the stored
contacts per setting list (``--set NAME=VALUE ...`` a tracker field; ``--variant`` repeats a list): each run's
confirmed tracks are all false (no target in the twin) and are classified as bench_active_family.py does.

Usage: ``PYTHONPATH=src python benchmarks/bench_active_amplitude.py --trials 14 15 6 [--minutes 60]
[--variant "amplitude_aided=true" --variant "amplitude_aided=true amplitude_start=true"]``. Measures, not tests.
The amplitude fields of the cached tracker settings are dropped, so the defaults on the path apply.

Measured (2026-12-07 session 12, h12-amp, main at e4c2ec6; chain 524 / 249 / 222 s per 1 h twin at load ~10, then
~8 s a re-track; false confirmed tracks in 1 h, by place as bench_active_family.py):
    trial 14 (LFM, K, 6 points)         without 4 (early 4)   amplitude 2 (early 2)
    trial 15 (CW, K, 14 points)         without 9 (points 4, mirrors 4, lobe 1)   amplitude 9 (the same)
    trial 6 (LFM, Rayleigh, 6 points)   without 0             amplitude 0
With the ratio capped at 30 instead of 5: 3/9/0 (trial 14: a track on a TS 18 dB still point confirmed before the
clutter map's verdict); with the first contact's ratio on the initial existence (``amplitude_start``): 4/9/0 (a
point and its mirror); with the target's prior mean excess 2x the clutter's (weight 2) and cap 30: trial 14 5.
"""

from __future__ import annotations

import argparse
import hashlib
import pickle
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def chain_once(config, scene, cache: Path) -> dict:
    """The chain's result on ``scene`` and its ContactTracker's arguments (cached)."""
    import sonartrack.systems.active.run as run_mod
    from sonartrack.studies.active_chain import run_scene

    key = hashlib.sha1((scene.model_dump_json() + "amp1").encode()).hexdigest()[:12]
    path = cache / f"twin-{key}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    real, seen = run_mod.ContactTracker, {}

    class Recording(real):
        def __init__(self, *args, **kwargs):
            seen["args"], seen["kwargs"] = args, kwargs
            super().__init__(*args, **kwargs)

    run_mod.ContactTracker = Recording
    t0 = time.perf_counter()
    try:
        result = run_scene(config.model_copy(update={"scene": scene}), scene)[0]
    finally:
        run_mod.ContactTracker = real
    out = {"result": result, "args": seen["args"], "kwargs": seen["kwargs"], "seconds": time.perf_counter() - t0}
    cache.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(out))
    return out


def retrack(c: dict, changes: list[str]):
    """The chain's tracker stage re-run on the cached contacts with tracker field changes (``NAME=VALUE``, JSON)."""
    import json

    import sonartrack.systems.active.contact_tracker as ct

    cached = c["args"][0]  # the chain's tracker settings; the amplitude fields the defaults on the path
    settings = type(cached)(**{k: v for k, v in cached.model_dump().items() if not k.startswith("amplitude_")})
    for item in changes:
        name, value = item.split("=", 1)
        settings = settings.model_copy(update={name: json.loads(value)})
    res = c["result"]
    kwargs = {**c["kwargs"], "clutter_map": ct.clutter_map_of(res.settings)}  # a fresh map: the cached one has run
    trk = ct.ContactTracker(settings, *c["args"][1:], **kwargs)
    con = res.contacts
    for t in res.ping_time_s:
        trk.step(float(t), con.rows(np.nonzero(np.isclose(con.time_s, t))[0]))
    return replace(res, tracks=trk.result())


def main() -> None:
    from bench_active_family import classify, trial_scene
    from bench_active_turns import use_amplitude
    from sonartrack.studies.active_chain import Config

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[14, 15, 6])
    ap.add_argument("--seed", type=int, default=2017)
    ap.add_argument("--minutes", type=float, default=None)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_amplitude"))
    ap.add_argument("--variant", action="append", default=[], help="space-separated tracker NAME=VALUE changes")
    ap.add_argument("--gate", type=float, default=1500.0)
    ap.add_argument("--early", type=float, default=3.0)
    ap.add_argument("--ridge", type=float, default=0.3)
    args = ap.parse_args()
    use_amplitude()
    config = Config()
    variants = [[]] + [v.split() for v in args.variant]
    totals = [0] * len(variants)
    hours = 0.0
    for i in args.trials:
        scene, values = trial_scene(config, args.seed, i, args.minutes)
        c = chain_once(config, scene, args.cache)
        w = scene.waveform
        args.range_tol = scene.sound_speed_mps / w.bandwidth_hz if w.kind == "lfm" else \
            0.5 * scene.sound_speed_mps * w.duration_s
        h = scene.duration_s / 3600.0
        hours += h
        print(f"trial {i}: " + " ".join(f"{k}={v}" for k, v in values.items()) + f" | {h:.2f} h, chain "
              f"{c['seconds']:.0f} s", flush=True)
        for k, v in enumerate(variants):
            rows = classify(retrack(c, v), scene, args)
            totals[k] += len(rows)
            by: dict = {}
            for r in rows:
                by[r["where"]] = by.get(r["where"], 0) + 1
            print(f"  {' '.join(v) or 'default':60s} false confirmed {len(rows)} "
                  f"({', '.join(f'{a} {b}' for a, b in sorted(by.items()))})", flush=True)
    for k, v in enumerate(variants):
        print(f"all {' '.join(v) or 'default':56s} {totals[k]} false confirmed in {hours:.2f} h")


if __name__ == "__main__":
    main()
