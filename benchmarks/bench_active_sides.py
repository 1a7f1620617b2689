"""Why the active-chain study's targets end with their side undecided: per target, the reason, trial by trial.

Runs chosen trials of study ``active-chain`` with their targets at full size (the scene drawn exactly as
studies/active_chain.py ``run_trial`` draws it: ``trial_rng(seed, i)``, two seeds, studies/active_chain_family.py
``draw_scene``, the first seed), through the chain of ``sonartrack active``; keeps its contacts and its tracker's
arguments (a pickle under ``--cache``), re-runs the tracker stage on them with the code on the path (seconds, not
minutes: the front end and the detectors are not re-run), and judges each target as the study does (studies/
active_chain.py ``_side_ok`` through ``score_tracks``, the mftd_imm variant). Per judged target it prints the
holding track, its segments (``ActiveTracks.joins``) and twin with their decisions, ln LR and contacts, and one
reason:

* ``right`` the study judges it right;
* ``no turn`` the target was detectable (the study's ``detectable_grid``: expected echo-to-background >= 15 dB, in
  the window) on no two pings between which the array's heading changed by the chain's ``side_turn_deg``, and nothing
  was decided about it: the
  geometry offered no evidence the study calls visible, undecided is the honest answer (the hits printed beside,
  any tracked detection within the study's hit window of the echo, span the whole turn on almost every target:
  clutter falls in that window too, so they do not tell);
* ``late`` the holding track was confirmed after the turn and its retrodiction (sides.py) did not reach back over
  ``side_turn_deg`` of heading change (while the target's detections did);
* ``segments`` an earlier segment joined to the holding track (merge or re-join) had lived through the turn;
* ``twins`` the holding track and its twin are both decided on their side (sides.py: neither decided);
* ``ghost`` a confirmed track on the target's mirror not decided a ghost;
* ``other`` none of these.

Measured (2026-12-07, seed 2017, the 14 trials with judged targets: 0 1 2 4 5 7 8 9 10 11 14 15 18 19, the chain's
runs 37-148 s CPU each at load 8-12, re-trackings 0.2-3 s): main at e4c2ec6 24 of 33 right, exactly the study's
(trials.parquet), every wrong one at ln LR 0: evidence lost at a join 3 (trial 1 approacher: four re-joined segments
with ln LR 2.6, 4.4, 0, 0; trial 7 maneuvering: segment 30 at +43.4 merged into 53, which began at 0; trial 15
approacher: 51 at +273 re-joined by 132), tracking late 4 (the target held only after the turn, its track's
retrodiction finds no turn: trial 8 approacher and crossing-b, 15 maneuvering, 18 approacher), no detectable echo
across the turn 2 (trial 9 crossing-a, 19 maneuvering; also trials 1 and 7's above). With sides.py carrying the
merges' evidence (this branch): 24 of 33 (trial 7's holding track now decided +43.4, but an undecided track on its
mirror, the twin of an unmerged duplicate of it, keeps it wrong); with the re-joins' too (``--rejoin-carry``, the
change proposed to contact_tracker.py): 26 of 33 (trials 1 and 15's approachers right; 15's through the pair rule
of :meth:`SideTracker.decision`: its twin was re-joined onto a false track at +31.2 against its +280.6); no right
target turned wrong. Not judging an undecided target detectable on no two pings >= side_turn_deg of heading apart
(the proposed study rule): main 24 of 29, with both carries 26 of 31.

Usage: ``python benchmarks/bench_active_sides.py --trials 1 7 8``. CPU: ~1-3 min per trial's first run (the
pickle), ~5-20 s per re-tracking.
"""

from __future__ import annotations

import argparse
import pickle
import time
from pathlib import Path

import numpy as np


def trial_config(config, seed: int, index: int):
    """The study's config with trial ``index``'s scene (with targets, the first of its two seeds)."""
    from sonartrack.core.random import trial_rng
    from sonartrack.studies.active_chain import MANEUVERING
    from sonartrack.studies.active_chain_family import draw_scene

    rng = trial_rng(seed, index)
    seeds = rng.integers(0, 2**31 - 1, size=2)
    drawn, axes = draw_scene(config.scene, config.family, rng, MANEUVERING)
    return config.model_copy(update={"scene": drawn.model_copy(update={"seed": int(seeds[0])})}), axes


class _Recorder:
    args: tuple = ()
    kwargs: dict = {}


def run_trial_chain(config, cache: Path, index: int) -> tuple[dict, float]:
    """The chain's result on the trial's scene, its truth and its tracker's arguments (cached pickle)."""
    import sonartrack.systems.active.run as run_mod
    from sonartrack.studies.active_chain import _real_truth, run_scene

    key = f"trial-{index}-{config.scene.seed}.pkl"
    path = cache / key
    if path.exists():
        return pickle.loads(path.read_bytes()), 0.0
    real = run_mod.ContactTracker

    class Recording(real):
        def __init__(self, *args, **kwargs):
            _Recorder.args, _Recorder.kwargs = args, kwargs
            super().__init__(*args, **kwargs)

    t0 = time.process_time()
    run_mod.ContactTracker = Recording
    try:
        result, _, truth = run_scene(config, config.scene)
    finally:
        run_mod.ContactTracker = real
    out = {"result": result, "truth": _real_truth(truth), "args": _Recorder.args[2:], "kwargs": _Recorder.kwargs,
           "settings": _Recorder.args[0]}
    cache.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(out))
    return out, time.process_time() - t0


def retrack(c: dict):
    """The chain's tracker stage re-run on the cached contacts with the code on the path: (ActiveTracks, the
    ContactTracker, for its side tracker's internals)."""
    from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of

    r = c["result"]
    kw = {**c["kwargs"], "clutter_map": clutter_map_of(r.settings)}  # a fresh map: the recorded one has run
    trk = ContactTracker(c["settings"], r.geometry, *c["args"], **kw)
    con = r.contacts
    bounds = np.searchsorted(con.time_s, np.append(r.ping_time_s, np.inf), side="left")
    for k, t in enumerate(r.ping_time_s):
        trk.step(float(t), con.rows(slice(bounds[k], bounds[k + 1])))
    return trk.result(), trk


def carry_rejoins() -> None:
    """``--rejoin-carry``: ContactTracker._rejoin (systems/active/contact_tracker.py, not this helper's file) wrapped
    so that each new re-join also carries the lost segment's side evidence to the new track (sides.py
    :meth:`~sonartrack.systems.active.sides.SideTracker.carry`): the one-line change proposed to its owner."""
    import sonartrack.systems.active.contact_tracker as ct

    inner = ct.ContactTracker._rejoin

    def rejoin(self, t_s, snap):
        before = dict(self.joins)
        inner(self, t_s, snap)
        for new in self.joins.keys() - before.keys():
            self.sides.carry(new, self.joins[new])

    ct.ContactTracker._rejoin = rejoin


def _heading_span_deg(geometry, times) -> float:
    """The largest change of the array's heading between any two of ``times`` (deg)."""
    if not len(times):
        return 0.0
    h = np.asarray(geometry.heading_at(np.asarray(times, float)), float)
    return float(np.rad2deg(h.max() - h.min()))


def _segments(joins, tid: int) -> list[int]:
    """``tid`` and every track joined to it, earlier or later (the join links' connected set)."""
    links: dict[int, set] = {}
    for a, b in joins or ():
        links.setdefault(int(a), set()).add(int(b))
        links.setdefault(int(b), set()).add(int(a))
    seen, todo = {tid}, [tid]
    while todo:
        for b in links.get(todo.pop(), ()):
            if b not in seen:
                seen.add(b)
                todo.append(b)
    return sorted(seen)


def describe(config, c: dict, tracks, trk) -> list[dict]:
    """One row per judged target (module doc)."""
    from sonartrack.metrics.track_quality import associate_tracks
    from sonartrack.studies.active_chain import _mirror, _truth_arrays, detectable_grid, echo_hits, score_tracks
    from sonartrack.studies.active_chain_family import target_names

    r, truth = c["result"], c["truth"]
    names = target_names(config.scene)
    sc = score_tracks(config, tracks, r, truth)
    t_truth, ids, xy = _truth_arrays(truth, names)
    tr, d, g = tracks.tracks, tracks.sides, r.geometry
    assoc = associate_tracks(t_truth, ids, xy, tr.time_s, tr.track_id, tr.x[:, :2], config.match_m,
                             confirmed=tr.confirmed)
    hits = echo_hits(config, r.detections, truth)
    det = detectable_grid(config, truth) > 0.5
    ping_t = np.asarray(r.ping_time_s, float)
    min_turn = float(config.chain.side_turn_deg)
    last = tr.time_s == assoc.time_s[-1]
    mirror_xy = _mirror(g, t_truth, xy)
    out = []
    for i, name in enumerate(names):
        if not np.isfinite(sc["side_ok"][i]):
            continue
        span = _heading_span_deg(g, ping_t[hits[i]])
        det_span = _heading_span_deg(g, ping_t[det[i]])
        hold = int(assoc.track_of[-1, i])
        at = np.isclose(t_truth, assoc.time_s[-1]) & (ids == assoc.truth_ids[i])
        rows = last & tr.confirmed & ~np.isin(tr.track_id, assoc.track_of[-1])
        ghosts = tr.track_id[rows][np.hypot(*(tr.x[rows, :2] - mirror_xy[at][0]).T) < config.match_m].tolist()
        segs = _segments(tracks.joins, hold) if hold >= 0 else []
        info = []
        for s in segs:
            k = d.of(s)
            conf = tr.time_s[(tr.track_id == s) & tr.confirmed]
            st = trk.sides
            live = sum(st._sums[s][0].live) if s in st._sums else 0
            n = st._sums[s][0].n if s in st._sums else 0
            turn = np.rad2deg(abs(g.heading_at(conf[-1]) - st._h0[s])) if s in st._h0 and len(conf) else np.nan
            info.append({"track": s, "from": conf[0] if len(conf) else np.nan, "to": conf[-1] if len(conf) else np.nan,
                         "decision": d.decision[k] if k is not None else "-", "lr": d.log_lr[k] if k is not None else
                         np.nan, "twin": int(d.twin[k]) if k is not None else -1, "n": n, "retro": n - live,
                         "turn_deg": turn})
        gh = [(gid, d.decision[d.of(gid)] if d.of(gid) is not None else "-") for gid in ghosts]
        out.append({"target": name, "ok": sc["side_ok"][i], "lr": sc["side_log_lr"][i], "hold": hold,
                    "span_deg": span, "hits": int(hits[i].sum()), "segments": info, "ghosts": gh,
                    "det_span_deg": det_span, "detectable": int(det[i].sum()),
                    "decided": (decided := any(s["decision"] != "undecided" for s in info if s["track"] == hold) or
                                any(x[1] != "undecided" for x in gh)),
                    "reason": _reason(sc["side_ok"][i], hold, info, gh, det_span if not decided else 360.0,
                                      min_turn)})
    return out


def _reason(ok: float, hold: int, segs: list[dict], ghosts: list, span: float, min_turn: float) -> str:
    """The module doc's reason of one judged target."""
    if ok == 1.0:
        return "right"
    if span < min_turn:
        return "no turn"
    own = next((s for s in segs if s["track"] == hold), None)
    if own is not None and own["decision"] == "track" and ghosts and any(x[1] != "mirror" for x in ghosts):
        return "ghost"
    if own is not None and own["decision"] == "undecided" and abs(own["lr"]) >= np.log(100.0):
        return "twins"
    if any(s["track"] != hold and np.isfinite(s["turn_deg"]) and s["turn_deg"] >= min_turn for s in segs):
        return "segments"
    if own is not None and not (own["turn_deg"] >= min_turn):
        return "late"
    return "other"


def main() -> None:
    from sonartrack.studies.active_chain import Config

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[1, 7, 8])
    ap.add_argument("--seed", type=int, default=2017, help="the study's master seed (sonartrack reproduce's default)")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_sides"))
    ap.add_argument("--quiet", action="store_true", help="only the per-target lines")
    ap.add_argument("--rejoin-carry", action="store_true", help="carry a lost segment's side evidence to the track "
                    "re-joined to it (the proposed contact_tracker.py change, by wrapping)")
    args = ap.parse_args()
    if args.rejoin_carry:
        carry_rejoins()
    base = Config()
    tally: dict[str, int] = {}
    for i in args.trials:
        config, axes = trial_config(base, args.seed, i)
        c, sec = run_trial_chain(config, args.cache, i)
        t0 = time.process_time()
        tracks, trk = retrack(c)
        sec_t = time.process_time() - t0
        w = config.scene.waveform
        print(f"trial {i}: {w.kind} {config.scene.sonar.elements} elements, chain {sec:.0f} s CPU (0: cached), "
              f"tracker {sec_t:.1f} s CPU")
        for row in describe(config, c, tracks, trk):
            tally[row["reason"]] = tally.get(row["reason"], 0) + 1
            print(f"  {row['target']:12s} ok {row['ok']:.0f} lnLR {row['lr']:8.1f} hold {row['hold']:4d} "
                  f"hits {row['hits']:3d} over {row['span_deg']:5.1f} deg, detectable {row['detectable']:3d} over "
                  f"{row['det_span_deg']:5.1f} deg, {'decided' if row['decided'] else 'undecided'} "
                  f"-> {row['reason']}")
            if args.quiet:
                continue
            for s in row["segments"]:
                print(f"      seg {s['track']:4d} {s['from']:6.0f}-{s['to']:6.0f} s {s['decision']:9s} "
                      f"lnLR {s['lr']:8.1f} contacts {s['n']:3d} (retro {s['retro']:2d}) turn {s['turn_deg']:5.1f} deg "
                      f"twin {s['twin']}")
            if row["ghosts"]:
                print(f"      on its mirror: {row['ghosts']}")
    print("reasons: " + ", ".join(f"{k} {v}" for k, v in sorted(tally.items())))


if __name__ == "__main__":
    main()
