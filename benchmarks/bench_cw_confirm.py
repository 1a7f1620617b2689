"""Why a CW false track is confirmed on two contacts and then listed for 10-20 pings: the tracker stage replayed.

Runs the reverberation-only twin of chosen trials of study ``active-chain`` (benchmarks/bench_active_family.py
``trial_scene``) once through the chain, recording the tracker stage's inputs (systems/active/run.py builds a
``ContactTracker``; every ``step``'s contacts and ridge contacts are kept, a pickle per trial under ``--cache``), then
replays the tracker stage on them with the tracker code on the path (seconds, not minutes) and prints per confirmed
track: its pings from birth to confirmation, existence per ping (. no contact in its gate, * one or more), the
confirmation threshold then, and how many pings it stayed listed with no contact; and the false confirmed tracks
(bench_active_family.py ``classify``, every one of them false on a reverberation-only twin).

Usage: ``PYTHONPATH=src python benchmarks/bench_cw_confirm.py --trials 11 1 [--cache /tmp/cw_confirm]
[--set FIELD=VALUE ...]`` (``--set``: tracker settings, e.g. ``confirm_min_hits=3``). Measures, asserts nothing. The
replay gives the chain's own tracks bit for bit (checked: trials 11 and 1, every row's id, flag, existence and state).

Measured (2026-12-08, h12-cwconf on h12-lead 25a932b; chain 103 s / 44 s a trial at load ~4, replay ~1 s):
trial 11 (CW, spiky K): 4 false tracks, 2 rows; trial 1 (CW, Rayleigh): 4 tracks, 1 row. Why confirmed: the CW
tracker's clutter density is its own contacts' mean over the listening disc, 8e-10 /m^2 (1.3 contacts a ping) on
trial 11 and 2-5e-10 on trial 1, so one contact in a young track's gate has a position likelihood ratio
N(z; z_pred, S) / lambda = e^6.5-e^8.6 (the range-rate term adds only e^-0.3..e^0.9: the new track's 5 m/s prior
predicts any range rate near a still point's), Lambda = 0.6 + 0.4 x 0.99 x that ~ 300-2000, while the rate rule's
threshold at 1 false track/h with 0.6-1.1 tracks started a scan is odds 3.8-7 (existence 0.78-0.88) against the start's
0.053: one contact after the first confirms (51/52 and 27/28: existence 0.03 -> 0.94 and 0.05 -> 0.98 on their second
contact, none after). Ville's bound holds only where the clutter is as dense as assumed; a still point's skirt recurs
in one place (~1e-6 /m^2 there, ~1000 x lambda). Why listed on: with p11 0.98 the predicted odds are at most 49 and
each missed scan multiplies them by 0.98 x (1 - 0.4 x 0.99) ~ 0.59, so from ~1 to the deletion level 0.01 takes
14 scans (12-14 listed after their last contact). Settings (tracker), false rows (tracks) on 11 + 1:
    as is                       2 + 1 (8)
    confirm_min_hits 3          1 + 1 (4)   (the pairs confirmed on one contact after their first: gone)
    confirm_min_hits 4          0 + 1 (1)
    listed_existence 0.5 (rows) 2 + 1 (8), listed 12-14 -> 5 pings after the last contact (needs the
                                contact_tracker.py diff of tracking/deleters.py listed_tracks; as the deleter's
                                confirmation flag instead: 2 + 2, a re-confirmation made a row)
Default scene (bench_active_rows.py on /tmp/lead11/rows11's contacts; rows, false, extra; held % mean): as is LFM 4,0,0
83 / 4,0,0 87; CW 6,1,1 90 / 4,0,0 88. min hits 3: LFM same; CW 5,0,1 90 / 5,1,0 89. min hits 4: CW 5,0,1 88 /
6,2,0 83. listed 0.5: rows same, held LFM 81 / 87, CW 85 / 82; 0.2: 82 / 87, 88 / 86; 0.1: 82 / 87, 89 / 87.
min hits 3 + listed 0.5: LFM 4,0,0 81 / 4,0,0 87; CW 5,0,1 85 / 5,1,0 83. bench_active_turns.py (the 60 deg at 0.6
deg/s scenes of /tmp/active_turns' contacts): min hits 3 false tracks 4 -> 2, acquisition CW seed 2 5 -> 6 pings, its
held 74 -> 56 %; LFM the same. bench_active_family.py --trials 11 1 --minutes 60 (the chain run, h12-lead -> this
branch with the proposed min hits 3 and listing 0.5): false tracks 8 -> 4, rows 3 -> 2; the pairs left listed 12 and
17 pings (were 22 and 27). With listing 0.5, tests/systems/active/test_turns_tracker.py's "held at every ping from
confirmation" fails (a target's row unlisted over 3-4 missed pings); with min hits 3 alone it passes (and
tests/systems/active, live, studies' active-chain, cli active, report active page: 145 passed). LFM twin trial 18
(Rayleigh; 25a932b + min hits 3): 4 tracks, 2 rows, as at 25a932b (its LFM tracks hit every ping).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import pickle
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))


def record(config, scene, cache: Path) -> dict:
    """The tracker stage's inputs of the chain on ``scene`` (cached by the scene's JSON)."""
    import hashlib

    from _active_cache import run_recorded

    key = hashlib.sha1((scene.model_dump_json() + config.chain.model_dump_json()).encode()).hexdigest()[:12]
    path = cache / f"steps-{key}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    rec = run_recorded(config, scene)
    cache.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(rec))
    return rec


def wire_listed() -> None:
    """The proposed wiring (systems/active/contact_tracker.py, not this branch's file): ``_rate_confirmation`` passes
    the tracker settings' ``listed_existence`` to tracking/deleters.py ``RateConfirmation`` (off: as before)."""
    import sonartrack.systems.active.contact_tracker as ct
    from sonartrack.tracking.deleters import MinHits, RateConfirmation

    def rate_confirmation(settings, scan_interval_s):
        deleter = RateConfirmation(settings.false_tracks_per_h, scan_interval_s, settings.initial_existence,
                                   settings.terminate_threshold, listed_threshold=settings.listed_existence)
        return MinHits(deleter, settings.confirm_min_hits) if settings.confirm_min_hits > 1 else deleter

    ct._rate_confirmation = rate_confirmation


def replay(rec: dict, changes: dict):
    """The tracker stage on the recorded inputs, the tracker settings updated with ``changes``; returns the
    ContactTracker and a per-scan log of (time, track ids, existence, hit, confirm threshold)."""
    from sonartrack.systems.active.contact_tracker import ContactTracker

    args, kwargs = copy.deepcopy(list(rec["args"])), copy.deepcopy(rec["kwargs"])
    args[0] = type(args[0]).model_validate({**args[0].model_dump(), **changes})
    trk = ContactTracker(*args, **kwargs)
    log = []
    inner = trk.tracker.deleter
    while getattr(inner, "inner", None) is not None and not hasattr(inner, "confirm_threshold"):
        inner = inner.inner
    real_update = trk.tracker._update

    def spy(T, scan, dt, turn=0.0):
        out = real_update(T, scan, dt, turn)
        log.append((scan.time_s, out[0].track_id.copy(), out[0].existence.copy(), out[1].copy(),
                    float(getattr(inner, "confirm_threshold", np.nan))))
        return out

    trk.tracker._update = spy
    for t, contacts, ridge in rec["steps"]:
        trk.step(t, contacts, ridge)
    return trk, log


def track_story(tid: int, tracks, log, times) -> str:
    """One confirmed track's life: existence per ping from birth, * where its gate held a contact."""
    ping = {round(float(t), 3): k + 1 for k, t in enumerate(times)}
    rows = np.nonzero(tracks.track_id == tid)[0]
    first_c = rows[tracks.confirmed[rows]][0]
    last_hit, parts, thr = None, [], np.nan
    for t, ids, ex, hit, th in log:
        j = np.nonzero(ids == tid)[0]
        if len(j):
            parts.append(f"{ex[j[0]]:.3g}{'*' if hit[j[0]] else '.'}")
            last_hit = ping[round(t, 3)] if hit[j[0]] else last_hit
            if t == tracks.time_s[first_c]:
                thr = th
    p0, pc, pe = (ping[round(float(tracks.time_s[r]), 3)] for r in (rows[0], first_c, rows[-1]))
    listed = int(tracks.confirmed[rows].sum())
    return (f"  track {tid}: born ping {p0}, confirmed ping {pc} (threshold {thr:.4f}), last ping {pe}, last contact "
            f"ping {last_hit}, listed {listed} pings, {pe - (last_hit or pe)} after its last contact\n    "
            + " ".join(parts))


def main() -> None:
    from bench_active_family import classify, trial_scene
    from sonartrack.studies.active_chain import Config, _rows_and_tracks

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[11, 1])
    ap.add_argument("--seed", type=int, default=2017)
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/cw_confirm"))
    ap.add_argument("--set", nargs="*", default=[], help="tracker settings FIELD=VALUE (JSON values)")
    ap.add_argument("--wire-deleter", action="store_true", help="listed_existence in the deleter (wire_listed)")
    ap.add_argument("--stories", action="store_true", help="print each confirmed track's existence per ping")
    args = ap.parse_args()
    import json

    changes = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    if args.wire_deleter:
        wire_listed()
    args.gate, args.early, args.ridge = 1500.0, 3.0, 0.3
    config, total, total_rows = Config(), 0, 0
    for i in args.trials:
        scene, values = trial_scene(config, args.seed, i, args.minutes)
        rec = record(config, scene, args.cache)
        t0 = time.perf_counter()
        trk, log = replay(rec, changes)
        result = rec["result"]
        result = dataclasses.replace(result, tracks=trk.result())
        w = scene.waveform
        args.range_tol = scene.sound_speed_mps / w.bandwidth_hz if w.kind == "lfm" else 0.5 * scene.sound_speed_mps \
            * w.duration_s
        rows = classify(result, scene, args)
        listed, _ = _rows_and_tracks(result.tracks, result.geometry)
        total, total_rows = total + len(rows), total_rows + listed
        print(f"trial {i} ({values['pulse']}, {values['model']}): {len(rows)} false confirmed tracks, {listed} rows; "
              f"replay "
              f"{time.perf_counter() - t0:.1f} s (chain {rec['seconds']:.0f} s)")
        for r in rows:
            print("   ", {k: (round(v, 2) if isinstance(v, float) else v) for k, v in r.items()})
        if args.stories:
            tr = result.tracks.tracks
            for tid in np.unique(tr.track_id[tr.confirmed]):
                print(track_story(int(tid), tr, log, result.ping_time_s))
    print(f"total {total} false confirmed tracks, {total_rows} false rows")


if __name__ == "__main__":
    main()
