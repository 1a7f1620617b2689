"""Where the active-chain study's detectable-but-not-held pings go: each one given ONE cause, per trial and overall.

Runs the scene with targets of chosen trials of study ``active-chain`` at full size, drawn exactly as
studies/active_chain.py ``run_trial`` draws it (``trial_rng(seed, i)``, two seeds, studies/active_chain_family.py
``draw_scene``, the first seed), through the study's own ``run_scene`` (the chain of ``sonartrack active``), with the
tracker's deleters instrumented (which part removed which track at which ping: existence (RateConfirmation, the
IPDA's termination threshold), duplicate merge (tracking/duplicates.py), ghost (systems/active/sides.py), still
hold). The chain's tracks are scored by the study's own ``score_tracks`` (its ``held_pings`` is checked against the
study's stored trials when ``--trials-parquet`` is given: the run must be the study's, ping for ping).

Every COUNTED ping (detectable: ebr_db >= 15 dB, in the window, clear of the blast; after the target's first 5
detectable pings, studies/active_chain_claims.py ``_held_detectable``) that no confirmed track holds is given the
first cause that applies (studies/active_chain_scoring.py ``unheld_causes``), in this order:

* ``miss``: no tracked detection (MFTD + strong single-ping, what the contacts are formed from) on the target's echo
  (within the study's hit_delay_s / hit_cone_deg of its delay and cone, studies/active_chain.py ``echo_hits``): a
  detector miss the track must coast through (the track state behind each miss is printed beside);
* ``acquiring``: before the target's first ping held by a confirmed track (acquisition latency);
* ``deleted-<deleter>``: the confirmed track that last held the target was deleted (existence / merge / ghost /
  still, from the instrumented deleters); ``off``: that track is alive but farther than ``match_m``;
* ``assigned-other``: that track, within ``match_m``, is assigned by the study's assignment to another target.

(A track keeps its confirmation for life, tracking/deleters.py, so "held by a tentative track" or "by its
mirror" is not a state of its own: beside each cause is printed what is near the target then: ``mirror`` an
undecided confirmed track within ``match_m`` of its mirror, whose row lists the target's true position as its other
hypothesis, systems/active/targets.py; else ``tentative`` a tentative track within ``match_m``; else ``none``.)

Also per trial: the tracked detections' hit rate on the counted pings, counted pings in the blanked delays (0 on
every trial measured), and the counted pings' median ebr_db.

Usage: ``python benchmarks/bench_active_held.py --trials 18 2 8 15 --trials-parquet DIR/trials.parquet``; each
trial's chain result is pickled under ``--cache`` (the same trial, seed and code are not re-run: delete it after a
change). ~2 min CPU per LFM trial, 1 min per CW (7-18 min wall at load 10-15 on 2 cores).

Measured (2026-12-07, main at e4c2ec6, seed 2017; every trial's held pings identical to the full study's stored
ones, /tmp/lead11/full_fin20): the study's 20 trials alone: LFM 518 of 1687 counted pings not held, 372 (72 %) of
them before the target was first held, 146 after; CW 118 of 752, 25 (21 %) before, 93 after. Trials 18, 2, 8, 16,
14 (LFM): 436 not held of 999: miss 204 (47 %), acquiring 152 (35 %), deleted by existence 33 (8 %), ghost 3, off
42 (10 %), assigned to another target 2; by the track state alone (the miss set aside): acquiring 308 (71 %: a
tentative track on the target 239, nothing 47, an undecided confirmed track on its mirror 22), deleted by existence
52 (12 %), off 68 (16 %), ghost 5, assigned-other 3; no merge or still-hold deletion. Of the 162 not-held pings of
trials 2, 8, 16, 14 whose echo was detected, the contacts went to the tracker on 142, the clutter map withheld them
on 20 (e.g. trial 8's approacher near its closest approach, range rate ~0). The single-ping detector found
0.47-0.77 of the counted echoes where Swerling 1 at its threshold and the expected ebr IN EXPONENTIAL NOISE gives
0.68-0.86 (not the yardstick in K clutter, which needs more EBR at the same Pfa: benchmarks/bench_keep_echoes.py,
detection/cfar.py ``k_os_pd``; trial 2 K-ideal 0.50 against 0.40 found). Trial 15
(CW): 45 not held of 152: miss 34, existence 4, off 4, assigned-other 3; by state: off 18, deleted by existence 14,
assigned-other 13, acquiring 0. No counted ping of the 20 trials is in the blanked delays or past the window.
"""

from __future__ import annotations

import argparse
import pickle
import time
from collections import Counter
from pathlib import Path

import numpy as np

CAUSES = ("miss", "acquiring", "deleted-existence", "deleted-merge", "deleted-ghost", "deleted-still",
          "deleted-unlogged", "off", "assigned-other")
DELETERS = {"RateConfirmation": "existence", "ExistenceDeleter": "existence", "DuplicateMerger": "merge",
            "GhostDeleter": "ghost", "StillHold": "still", "MinHits": "minhits"}
LOG: dict = {"t": None, "removed": {}, "last": {}, "withheld": {}}  # the instrumented deleters' record (track id ->
# (t, part)) and the contacts' gates: (scan time, detection row) -> the gates that withheld a contact of it


def _instrument() -> None:
    """Wrap every deleter part's ``manage``: the tracks a part itself removes (its inner part's output less its own)
    are recorded with the scan time (ContactTracker.step wrapped for it)."""
    import sonartrack.systems.active.contact_tracker as ct
    import sonartrack.systems.active.sides as sd
    import sonartrack.tracking.deleters as dl
    import sonartrack.tracking.duplicates as du

    for cls in (dl.RateConfirmation, dl.ExistenceDeleter, dl.StillHold, dl.MinHits, du.DuplicateMerger,
                sd.GhostDeleter):
        if getattr(cls.manage, "_held_wrapped", False):
            continue

        def wrap(orig, name):
            def manage(self, T, hit):
                ids_in = set(np.asarray(T.track_id).tolist())
                out = orig(self, T, hit)
                inner = getattr(self, "inner", None)
                base = LOG["last"].get(id(inner), ids_in) if inner is not None else ids_in
                for tid in base - set(np.asarray(out.track_id).tolist()):
                    LOG["removed"].setdefault(int(tid), (LOG["t"], DELETERS.get(name, name)))
                LOG["last"][id(self)] = set(np.asarray(out.track_id).tolist())
                return out
            manage._held_wrapped = True
            return manage

        cls.manage = wrap(cls.manage, cls.__name__)
    for name in ("_gates", "_not_clutter", "_not_images"):
        orig = getattr(ct.ContactTracker, name)
        if getattr(orig, "_held_wrapped", False):
            continue

        def gate(orig, name):
            def verdict(self, t_s, contacts, *rest):  # rest: the CW ridge echoes (contact_tracker.py)
                keep = orig(self, t_s, contacts, *rest)
                for d in np.asarray(contacts.detection)[~np.asarray(keep, bool)]:
                    LOG["withheld"].setdefault((float(t_s), int(d)), set()).add(name.strip("_"))
                return keep
            verdict._held_wrapped = True
            return verdict

        setattr(ct.ContactTracker, name, gate(orig, name))
    step = ct.ContactTracker.step
    if not getattr(step, "_held_wrapped", False):
        def stepped(self, t_s, contacts, *rest):
            LOG["t"], LOG["last"] = float(t_s), {}
            return step(self, t_s, contacts, *rest)
        stepped._held_wrapped = True
        ct.ContactTracker.step = stepped


def trial_config(config, seed: int, index: int):
    """The trial's config (its drawn scene and seed, as ``run_trial``) and its axes."""
    from sonartrack.core.random import trial_rng
    from sonartrack.studies.active_chain import MANEUVERING
    from sonartrack.studies.active_chain_family import draw_scene

    rng = trial_rng(seed, index)
    seeds = rng.integers(0, 2**31 - 1, size=2)
    drawn, axes = draw_scene(config.scene, config.family, rng, MANEUVERING)
    return config.model_copy(update={"scene": drawn.model_copy(update={"seed": int(seeds[0])})}), axes


def run_cached(config, cache: Path, index: int):
    """(result, truth of the real targets, deletions {track id: (time s, deleter)}, withheld contacts {(time s,
    detection row): gates}, CPU s) of the trial's scene (a cache of an older version: no withheld record, {})."""
    import hashlib

    from sonartrack.studies.active_chain import _real_truth, run_scene

    key = hashlib.sha1((config.scene.model_dump_json() + config.chain.model_dump_json()).encode()).hexdigest()[:12]
    path = cache / f"trial{index}-{key}.pkl"
    if path.exists():
        with path.open("rb") as f:
            out = pickle.load(f)
        return (*out, *([{}] if len(out) == 3 else []), 0.0)
    _instrument()
    LOG["removed"], LOG["last"], LOG["withheld"] = {}, {}, {}
    t0 = time.process_time()
    result, _, truth = run_scene(config, config.scene)
    out = (result, _real_truth(truth), dict(LOG["removed"]), dict(LOG["withheld"]))
    cache.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        pickle.dump(out, f)
    return (*out, time.process_time() - t0)


def withheld_echoes(config, result, truth: dict, withheld: dict, pings) -> Counter:
    """Of the (target, ping) pairs ``pings`` whose echo has a tracked detection: how many had every contact of those
    detections withheld from the tracker, by the gates that withheld them (the instrumented ContactTracker)."""
    from sonartrack.studies.active_chain import truth_grid

    w, D, C = config.scene.waveform, result.detections, result.contacts
    delay = truth_grid(config, truth, "lfm_delay_s" if w.kind == "lfm" else "travel_time_s")
    tol = config.hit_delay_s if w.kind == "lfm" else max(config.hit_delay_s, 0.5 * w.duration_s)
    cone = truth_grid(config, truth, "cone_deg")
    out = Counter()
    for i, p in zip(*np.nonzero(pings), strict=True):
        m = np.nonzero(D.ping == p + 1)[0]
        near = m[(np.abs(D.travel_time_s[m] - delay[i, p]) < tol) & (np.abs(D.cone_deg[m] - cone[i, p])
                                                                      < config.hit_cone_deg)]
        rows = np.nonzero(np.isin(C.detection, near))[0]
        if not len(near) or not len(rows):
            continue
        if result.gated_out[rows].any():
            out["given"] += 1
            continue
        gates = set().union(*(withheld.get((float(C.time_s[r]), int(C.detection[r])), {"?"}) for r in rows))
        out["withheld by " + "+".join(sorted(gates))] += 1
    return out


def attribute(config, result, truth: dict, removed: dict, withheld: dict | None = None) -> dict:
    """Per target, the causes of its counted, not-held pings (module doc) and the counts beside them."""
    from sonartrack.studies.active_chain import (
        _mirror,
        detectable_grid,
        echo_hits,
        score_tracks,
        truth_grid,
    )
    from sonartrack.studies.active_chain_scoring import undecided_at, unheld_causes

    score = score_tracks(config, result.tracks, result, truth)
    held = score["held_pings"] > 0.5
    det = detectable_grid(config, truth) > 0.5
    counted = det & (np.cumsum(det, axis=1) > config.acquire_pings)
    hits = echo_hits(config, result.detections, truth)
    t = truth_grid(config, truth, "time_s")
    xy = np.stack([truth_grid(config, truth, "x_m"), truth_grid(config, truth, "y_m")], -1)
    ok = np.isfinite(t)
    xy_m = np.full_like(xy, np.nan)
    xy_m[ok] = _mirror(result.geometry, t[ok], xy[ok])
    sides = result.tracks.sides

    held_by = np.where(held, _holders(config, result, truth), -1)
    cause, state, near = unheld_causes(counted, held_by, hits, t, xy, xy_m, result.tracks.tracks, config.match_m,
                                       lambda tid, t_s: undecided_at(sides, tid, t_s))
    cause, state = (_deleter(c, held_by, removed) for c in (cause, state))
    m = cause != ""
    causes = Counter(cause[m].tolist())
    sub = Counter(f"{'miss, ' if c == 'miss' else ''}{s}, near {n}" for c, s, n in zip(cause[m], state[m], near[m],
                                                                                      strict=True))
    if withheld:
        sub.update({f"hit, {k}": v for k, v in withheld_echoes(config, result, truth, withheld,
                                                              (cause != "") & hits).items()})
    ebr = truth_grid(config, truth, "ebr_db")
    # Swerling 1 at the single-ping threshold on s = y / mu: Pd = exp(-T / (1 + EBR)), the expected EBR taken as known
    pd_sw1 = np.exp(-result.thresholds["single"] / (1.0 + 10.0 ** (ebr / 10.0)))
    single = echo_hits(config, result.single, truth)
    tt = truth_grid(config, truth, "travel_time_s")
    blank = config.chain_settings().front_end.blank_s
    return {"counted": int(counted.sum()), "held": int((held & counted).sum()), "causes": causes, "miss_sub": sub,
            "held_pings": held,
            "hit_rate": float(hits[counted].mean()) if counted.any() else np.nan,
            "single_rate": float(single[counted].mean()) if counted.any() else np.nan,
            "pd_sw1": float(pd_sw1[counted].mean()) if counted.any() else np.nan,
            "blanked": int((counted & (tt < blank)).sum()), "ebr_median": float(np.median(ebr[counted]))
            if counted.any() else np.nan, "per_target": [(int(counted[i].sum()), int((held & counted)[i].sum()))
                                                         for i in range(len(held))]}


def _deleter(cause: np.ndarray, held_by: np.ndarray, removed: dict) -> np.ndarray:
    """"deleted" causes named by the deleter that removed the last holding track (the instrumented log)."""
    out = cause.copy()
    for i, p in zip(*np.nonzero(cause == "deleted"), strict=True):
        before = np.nonzero(held_by[i, :p] >= 0)[0]
        out[i, p] = "deleted-" + removed.get(int(held_by[i, before[-1]]), (None, "unlogged"))[1]
    return out


def _holders(config, result, truth) -> np.ndarray:
    """(targets, pings) the confirmed track holding each target (-1: none) by the study's assignment."""
    from sonartrack.metrics.track_quality import associate_tracks
    from sonartrack.studies.active_chain import _by_ping, _truth_arrays
    from sonartrack.studies.active_chain_family import target_names

    t_truth, ids, xy = _truth_arrays(truth, target_names(config.scene))
    tr = result.tracks.tracks
    assoc = associate_tracks(t_truth, ids, xy, tr.time_s, tr.track_id, tr.x[:, :2], config.match_m,
                             confirmed=tr.confirmed)
    return _by_ping(config, truth, assoc.time_s, assoc.track_of, -1)


def _stored_held(path: Path | None, index: int):
    if path is None or not path.exists():
        return None
    import pandas as pd

    df = pd.read_parquet(path)
    row = df[df["trial"] == index]
    return None if not len(row) else np.asarray(row.iloc[0]["held_pings"], float)


def study_split(path: Path, acquire: int = 5) -> None:
    """From the study's stored trials alone (no run): per pulse, the counted not-held pings before the target is
    first held (acquisition) and after (drops and gaps)."""
    import pandas as pd

    df = pd.read_parquet(path)
    tot = {}
    for k in range(len(df)):
        r = df.iloc[k]
        n_t = len(r["ttc_s"]) // 4
        det = np.asarray(r["detectable"]).reshape(n_t, -1) > 0.5
        counted = det & (np.cumsum(det, axis=1) > acquire)
        held = np.asarray(r["held_pings"]).reshape(4, n_t, -1)[0] > 0.5
        lost = counted & ~held
        ever = np.cumsum(held, axis=1) > 0
        v = np.array([counted.sum(), (held & counted).sum(), (lost & ~ever).sum(), (lost & ever).sum()])
        pulse = "LFM" if int(np.asarray(r["axes"])[0]) == 0 else "CW"
        tot[pulse] = tot.get(pulse, 0) + v
    for pulse, (n, h, before, after) in tot.items():
        print(f"study {pulse}: counted {n}, held {h} ({h / max(n, 1):.2f}); not held {n - h}: before first held "
              f"{before} ({before / max(n - h, 1):.0%}), after {after} ({after / max(n - h, 1):.0%})")


def main() -> None:
    from sonartrack.studies.active_chain import Config
    from sonartrack.studies.active_chain_family import target_names

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[18, 2, 8, 16])
    ap.add_argument("--seed", type=int, default=2017, help="the study's master seed (sonartrack reproduce's default)")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_held"))
    ap.add_argument("--trials-parquet", type=Path, default=None, help="the study's trials.parquet: its held_pings "
                                                                      "checked against this run's")
    args = ap.parse_args()
    if args.trials_parquet is not None and args.trials_parquet.exists():
        study_split(args.trials_parquet)
    total = {"LFM": Counter(), "CW": Counter()}
    sub_total = {"LFM": Counter(), "CW": Counter()}
    sums = {"LFM": [0, 0], "CW": [0, 0]}
    print("trial pulse counted held frac hit|counted blanked ebr_med  " + " ".join(CAUSES))
    for i in args.trials:
        config, axes = trial_config(Config(), args.seed, i)
        result, truth, removed, withheld, cpu = run_cached(config, args.cache, i)
        a = attribute(config, result, truth, removed, withheld)
        pulse = config.scene.waveform.kind.upper()
        stored = _stored_held(args.trials_parquet, i)
        same = "" if stored is None else (" same as study" if np.array_equal(
            stored.reshape(4, *a["held_pings"].shape)[0] > 0.5, a["held_pings"]) else " DIFFERS from study")
        print(f"{i:5d} {pulse:5s} {a['counted']:7d} {a['held']:4d} {a['held'] / max(a['counted'], 1):.2f} "
              f"{a['hit_rate']:.2f} {a['blanked']:3d} {a['ebr_median']:5.1f}  "
              + " ".join(f"{a['causes'].get(c, 0):3d}" for c in CAUSES) + f"  cpu {cpu:.0f} s{same}")
        print("      by state, near: " + ", ".join(f"{k} {v}" for k, v in sorted(a["miss_sub"].items())))
        print(f"      single-ping detector on the counted pings: hit {a['single_rate']:.2f}, Swerling 1 at its "
              f"threshold in exponential noise and the expected ebr {a['pd_sw1']:.2f} (not the yardstick in K "
              f"clutter: benchmarks/bench_keep_echoes.py, detection/cfar.py k_os_pd)")
        print("      per target (counted/held): " + ", ".join(
            f"{n} {c}/{h}" for n, (c, h) in zip(target_names(config.scene), a["per_target"], strict=True)))
        total[pulse].update(a["causes"])
        sub_total[pulse].update(a["miss_sub"])
        sums[pulse][0] += a["counted"]
        sums[pulse][1] += a["held"]
    for pulse in total:
        n, h = sums[pulse]
        if not n:
            continue
        lost = n - h
        print(f"{pulse}: counted {n}, held {h} ({h / n:.2f}), not held {lost}: " + ", ".join(
            f"{c} {total[pulse][c]} ({total[pulse][c] / max(lost, 1):.0%})" for c in CAUSES if total[pulse][c]))
        print(f"{pulse}: by state, near: " + ", ".join(f"{k} {v}" for k, v in sorted(sub_total[pulse].items())))


if __name__ == "__main__":
    main()
