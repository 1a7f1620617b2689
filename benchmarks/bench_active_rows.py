"""Benchmark: the rows a user reads from ``sonartrack active`` on the default scene, both pulses, against the truth.

For the default active scene (sim/active_scene.py) simulated with its LFM and with a 1 s CW, seeds 1 and 2, the
chain is run once (front end, detectors, contacts: cached under ``--cache``, a pickle per scene) and its tracker stage
is re-run on the stored contacts with the settings on the path. Each listed target row (systems/active/targets.py
``mirror_targets``) and each confirmed track is associated with the truth: a track belongs to the true target that
lies within ``--gate-m`` of its confirmed rows, or whose mirror about the array's axis does, on most of them (a
ghost counts for its target). Printed per pulse and seed:

* rows, rows per true target (1 wanted), rows of no true target (false), rows listing only a ghost;
* per true target, its confirmed track segments with their ping spans and pings to confirm;
* the held % of each target's detectable pings (bench_cw_held.py ``detectable_rows``; truth_scores' rule);
* why each track ended: coasted out (existence fell below the termination threshold), merged (a duplicate of a
  confirmed track), ghost (its side decided the mirror), held (StillHold), or alive at the end;
* the confirmed tracks confirmed on 1-2 pings of contacts (pings from birth to confirmation).

Usage: ``PYTHONPATH=src python benchmarks/bench_active_rows.py [--cache /tmp/active_rows] [--kinds lfm cw]
[--seeds 1 2] [--set NAME=VALUE ...]``. Measures, not tests: nothing is asserted. A row counts for the target of its
latest track (1 km gate); "before" is measured with the code before (``git archive 7fec702 src``) first on the path.

Measured (2026-12-07, h10-acthold; the chain once per scene, ~2-6 min each on the shared machine, then ~10 s of
tracking per run of this script; per pulse/seed: rows for the 4 detectable targets, false rows, duplicate rows,
ghost-only rows, rows of <= 2 pings; held % of detectable pings approacher / crossing-a / crossing-b / maneuvering):
    before   LFM 1: 9, 2, 3, 3, 3; 74/70/80/99     after  4, 0, 0, 0, 0; 74/70/90/99
             LFM 2: 7, 1, 2, 0, 1; 78/82/89/98            4, 0, 0, 0, 0; 78/82/89/98
             CW 1: 22, 2, 16, 4, 10; 90/72/76/70          6, 1, 1, 0, 1; 90/72/76/79
             CW 2: 23, 2, 17, 3, 9; 74/82/76/79           8, 1, 3, 1, 0; 78/85/76/79
The changes, each measured here: a ghost with no live twin reflected onto its target's side (sides.py GhostDeleter:
LFM 1 crossing-b 3 rows -> 1, held 80 -> 90 %); merged duplicates and re-confirmed lost tracks listed as one target
(contact_tracker.py ``rejoin_s`` 600 s, targets.py: CW 22/23 -> 8/9 rows); confirmed targets' lobe images withheld
(contact_tracker.py ``_not_images``: LFM's one false row a seed, 16 pings at the fore endfire at crossing-b's range,
-> 0); twins from one shared ping (sides.py MIN_TWIN_PINGS 1: CW 1 7 -> 6). Tried and left off: confirmation after
3 scans in the gate (tracking confirm_min_hits 3: CW 1 6 rows, CW 2 10); rejoin_s 1200 s (CW 1 4 rows, but CW 2
chains three targets' fragments into one row through merges at crossings).

Measured (2026-12-07, h10-acthold2, same caches; ~80 s a run of all four at load ~13): the tracker's pd on CW pings
(tracking ``pd_cw``, contact_tracker.py ``_cw_pd``; LFM unchanged, 4 clean rows each):
    pd_cw (0.7 = pd)  CW 1: 6, 1, 1, 0, 1; 90/72/76/79     CW 2: 8, 1, 3, 1, 0; 78/85/76/79
          0.5               5, 1, 1, 0, 1                        5, 0, 2, 0, 1
          0.45              6, 1, 2, 0, 0; 93/74/78/77           5, 0, 2, 0, 0; 89/79/79/84
          0.4 (default)     4, 1, 0, 0, 0; 93/73/78/86           5, 0, 2, 0, 0; 86/82/79/86
          0.3               4, 1, 0, 0, 0; 95/72/78/93           4, 0, 1, 0, 0; 86/67/79/46
Tried and left off (tracking ``merge_confirmed_scans`` 2, 3: two confirmed tracks merged only after 2-3 scans in a row
passing the test): LFM 2 4 -> 3 rows (a ghost of crossing-b merged into maneuvering's ghost 2 scans later), CW 1 4, CW 2
5-6; a merge of confirmed tracks recorded as one target only when they passed the test since (within 4-10 scans of)
the younger's confirmation, else the better-informed kept: CW 1 5-8 rows, CW 2 7-9. What is left on CW: a track
coasting through crossing-b's missed pings ~93-101 takes the approacher's contacts 1.4 km off (its gate ~400 m sd) on
both seeds, and the merger then records the approacher's track as its duplicate: one row for two targets. Two seeds
only: the rows are not monotone in pd_cw (0.45 gives 6 on CW 1), so 0.4 rests on the measured Pd as much as on them.

Measured (2026-12-07, h10-acthold3; ~10-40 s a run of all four): the counts above hid rows that list two or more
true targets (a merge or re-join of two targets' tracks; the row then counts for its latest track's target): now
printed as "rows holding 2+ true targets" (a ghost's label left out: near a crossing the mirrors of two targets
are close). Changes: a coasting confirmed track (existence < 0.5, tracking/duplicates.py DuplicateMerger) ranks
below the track holding its target and is recorded as that target only if the pair passed the test at its last
held scan; a decided track and its twin put on one side of a row by joins name the row (targets.py; was a
ghost-only row). Per pulse/seed: rows, false, extra, ghost-only, <= 2-ping rows, rows holding 2+ targets; held %:
    ACTHOLD2's caches (before ACTCW)  main                             h10-acthold3
        CW 1                        4, 1, 0, 0, 0, 1 (appr.+cr-b)    5, 1, 0, 0, 0, 0; held 95/73/78/86 (was 93)
        CW 2                        5, 0, 2, 0, 0, 1 (appr.+cr-b)    6, 0, 2, 0, 0, 0; held 86/82/79/86 (same)
    the lead's caches on main (/tmp/lead/rows10: ACTCW's CW sigma_time, delay_guard 0)
        LFM 1                       4, 0, 0, 0, 0, 0                 same; held 74/70/90/99
        LFM 2                       4, 0, 0, 0, 0, 1 (cr-b+man.)     same; held 77/76/88/98 (main with ACTFAM)
        CW 1                        5, 1, 0, 1, 1, 2                 same; held 95/78/100/90
        CW 2                        5, 0, 1, 0, 0, 1 (appr.+man.)    6, 0, 2, 0, 0, 1 (appr.+cr-b); held 90/80/100/85
Reverberation-only false confirmed tracks (bench_active_defaults.py --parts reverb, cached, 6 h): 0, as main.
What is left: on the lead's caches the CW tracker confirms 26-29 tracks for 4 targets (LFM 7-8); the merger and the
re-join glue them into 5-6 rows, and the glue cannot tell a young fragment from another target's new track: their
test T = P_i + P_j is dominated by the young track's covariance (position sd 200-900 m at its first scans), and the
merges' d^2 do not separate the right from the wrong (same target 1.6-12.9, two targets 3.7-13.2, gate 13.3).
Without any recorded merge or re-join: CW 1 22 rows, CW 2 20, none holding two targets. Tried and left off: the
record also requiring the test on each of the last 5 or 10 common scans (tracking merge_history_scans): CW 1 17
rows, still 2 holding two targets (through re-joins); the CW contacts' R scaled by 1.5 and 2 (a stand-in for the
CW cone error measured 2.0 deg vs 0.87 stated, ACTCW): 25-26 and 19 confirmed tracks, 5-7 rows, 1-2 holding two.
A re-join (contact_tracker.py) tested against the lost track's last state with existence >= 0.9 instead of its
last (coasted) one: lead's CW 1 a row holding three targets, CW 2 0 mixed (was 1); ACTHOLD2's CW 1 7 rows, 1 mixed.

Measured (2026-12-07 session 11, h11-cwfrag; the lead's caches /tmp/lead/rows10b copied; ~1-2 min a run of all
four at load ~12). Per pulse/seed: rows, false, extra, rows holding 2+ targets, confirmed tracks; held % (mean):
                              LFM 1        LFM 2          CW 1                          CW 2
    main (0e2e8dd)            4,0,0,0, 8   4,0,0,1, 8     4,1,0,2, 29; 95/78/100/90     6,0,2,1, 26; 90/80/100/85
    + join links as pairs     same         same           3,1,0,2, 29 (a row of 3)      3,0,0,1, 26
    + contacts shared by rank 4,0,0,0, 8   4,0,0,0, 6     3,1,0,1, 21 (a row of all 4)  4,0,0,1, 21; held 91/90
    + told-apart pairs kept   4,0,0,0, 8   4,0,0,0, 6     7,1,2,0, 13; 95/73/100/90     7,1,2,0, 17; 92/83/100/85
      (the defaults now: contact_claims 'all', merge_keep_apart)
Tried and left off: the CW peak contacts (ActiveSettings cw_peak_contacts, ACTCW's run.py change; contacts rebuilt):
with the shared contacts CW 1 5,2,0,1, 12 tracks, held 85; CW 2 4,0,0,1, 19, held 88 (approacher 95 -> 81 on CW 1);
with the told-apart pairs too 5,2,0,1 / 7,2,1,0. On the peak contacts: claims 'confirmed' (confirmed tracks claim
from tentative ones only) with the told-apart pairs 8 and 11 CW rows; 'lm' (LMIPDA's symmetric odds) 5 and 4 rows
with 1 and 2 holding two targets, 13/11 with the told-apart pairs. Told-apart pairs merged after 5 or 10 scans
together (not listed as one): 8,1,3,1 / 7,2,1,1 and 8,1,3,0 / 6,1,1,1. Told-apart pairs' merges not recorded (but
deleted): 7,1,2,1 / 9,0,5,1.
A scene no one tuned on (``--kinds cwb``: bench_cw_held.py's scene b, 32 x 0.3 m, 2.4 kHz, 5 detectable targets;
chain ~10 min a seed here, then ~1 min): rows, false, extra, holding 2+, confirmed tracks; held % (mean)
    main                       seed 3: 6,0,1,1, 30; 82     seed 4: 6,0,1,2 (a row of 4), 36; 86
    shared contacts            5,1,0,2, 27; 85             6,0,1,1 (a row of 3), 27; 90
    + told-apart pairs kept    9,0,4,0, 20; 84             9,1,3,1, 19; 89
(telling a pair apart only after 3 or 6 held scans failing the test: 10,0,5,0 / 9,1,3,1 and 10,1,4,0 / 9,1,3,1.)
So the told-apart rule trades rows joining targets (main 6 in these 4 CW runs, shared contacts alone 5, both 1) for
extra rows (4, 1, 11): two confirmed tracks on one target that were apart once (a track that swapped targets at a
crossing, or a second track started off its target) are kept, and listed, both.
What is left on CW: 2 extra rows a seed (seed 2: three confirmed tracks on crossing-b to the end, one of them the
approacher's until the crossing at ping ~52; seed 1: crossing-b's and maneuvering's second tracks) and one false
row (seed 1: pings 101-119 at the fore endfire, as on main; seed 2: a track of pings 60-76).

Measured (2026-12-07 session 11, h11-cwfrag2; same caches, plus LFM seeds 3-4 and cwb seeds 1-2 simulated here;
~35 s for CW 1-2, ~1 min a cwb seed): the false row of CW seed 1 was crossing-b's grating-lobe alias: crossing-b at
cone 160-195 deg (aft endfire), held by track 27, was heard on the fore endfire beam at the same travel time (r_B 2-97 m
apart, the CW's delay known to ~430 m) at 0.8-2.9 times its statistic, so the image test (weaker, within 15 m) passed
it; it started track 84 at ping 97, confirmed at 101, fed to ping 108, coasting to 119. Now a contact in the alias
lobe (|u - u_held -+ lambda/d| <= lambda/(N d), u = cos cone) of a held contact, within c/(B sqrt 12) in r_B, goes to
no unconfirmed track (contact_tracker.py EndfireAlias, setting ``endfire_alias``). rows, false, extra, holding 2+,
confirmed tracks; held % (mean):
                      CW 1             CW 2             LFM 1-4            cwb 1 / 2 / 3 / 4
    endfire_alias off 7,1,2,0, 13; 89  7,1,2,0, 17; 90  4/4/5/4 rows, 0 f  11,1,5,1 / 10,0,5,0 / 9,0,4,0 / 9,1,3,1
    endfire_alias on  6,0,2,0, 12; 89  7,1,2,0, 16; 90  same               same
CW seed 2's false row is the approacher's mirror during the ownship's turn (heading -5 -> -24 deg, pings 55-66): the
approacher's own track 43 was 0.9-1.7 km off at pings 58-64, its twin 44 (a ghost, 54-65) and a second mirror track
50 (confirmed at 60, no twin: sides.py pairs each track with one twin, and 43's is 44) coasted away (2-2.5 km from
anything by ping 66) and is listed as a row of its own.

Measured (2026-12-07 session 11, h11-dup2; the lead's caches /tmp/lead11/rows11 plus CW seed 5 built here (~3 min),
cwfrag2's cwb 3-4 caches; ~1-2 min a run): a told-apart pair merged after all when it passes the test on the whole
state and on the velocity and shares its nearest contact on k scans in a row (tracking/duplicates.py
``reunite_scans``, ``--reunite k``; the lead's user check, CW seed 5: tracks 19 and 40 both alive to the end on one
target). Rows for the detectable targets, rows holding 2+ targets; held % per target:
    k   CW 1          CW 2          CW 5                    cwb 3           cwb 4
    0   7, 0          5, 0          6, 0; 100/67/100/88     9, 0            8, 2
    3   6, 0          4, 0          6, 1 (appr.+cr-b)       8, 2            7, 2
    5   6, 0          4, 0          5, 0; 100/75/100/88     10, 1           7, 2
    8   6, 0          4, 0          5, 0 (19+40 at ping     7, 0            8, 2 (a side twin's, not a
                                    107); 100/75/100/88                     reunion: all 3 same-target)
Held % at k = 8 equal to k = 0 or higher on every target (CW 1 95/75/100/91, CW 2 90/76/100/85); LFM 1-2 unchanged
(4 clean rows each). Default 8 (ActiveSettings merge_reunite_scans). The lead's user check (``sonartrack active`` on
/tmp/lead11/user/sc_cw, ~25 s): 6 -> 5 rows (track 40 merged into 19 at 3210 s); left: target 1 (track 23) still
decided starboard, but at 2370 s with ln LR 7.4 (mirror 24) instead of 1950 s with 226.5 (mirror 32): track 32, ~900 m
off 23 until 2700 s, jumped onto 23's contacts at 2730 s and was reunited with it at ping 94, so its side evidence is
no longer the row's. Tried and left off: no reunion of pairs sides.py counted as mirrors (the user check unchanged).
"""

from __future__ import annotations

import argparse
import pickle
import tempfile
from pathlib import Path

import numpy as np


def scene(kind: str, seed: int):
    """The default active scene with pulse ``kind`` (lfm | cw, the other waveform fields the default's); ``cwb``:
    bench_cw_held.py's second CW scene (32 elements 0.3 m apart, 2.4 kHz, an hour), a scene no one tuned on."""
    from sonartrack.sim.active_scene import ActiveSceneSettings

    if kind == "cwb":
        from bench_cw_held import scene_settings

        return scene_settings("b", seed, 3600.0)

    s = ActiveSceneSettings()
    return s.model_copy(update={"seed": seed, "waveform": s.waveform.model_copy(update={"kind": kind})})


class _Recorder:
    """Captures the chain's ContactTracker arguments (to rebuild it on the stored contacts)."""

    args: tuple = ()
    kwargs: dict = {}


def run_scene(kind: str, seed: int, cache: Path, folder: Path | None = None) -> dict:
    """The chain's contacts per ping, its tracker's arguments, geometry and truth (cached pickle); ``folder``: a
    scene already simulated (``sonartrack simulate --kind active``) of this pulse and seed."""
    import pandas as pd

    import sonartrack.systems.active.run as run_mod
    from sonartrack.systems.active.files import run_active_files
    from sonartrack.systems.active.settings import ActiveSettings
    from sonartrack.systems.simulate.active_files import write_active_scene

    path = cache / f"{kind}_{seed}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    sc = scene(kind, seed)
    spacing = sc.sonar.spacing_m or sc.sound_speed_mps / (2.0 * sc.waveform.carrier_hz)
    real = run_mod.ContactTracker

    class Recording(real):
        def __init__(self, *args, **kwargs):
            _Recorder.args, _Recorder.kwargs = args, kwargs
            super().__init__(*args, **kwargs)

    run_mod.ContactTracker = Recording
    try:
        with tempfile.TemporaryDirectory() as tmp:
            where = Path(folder) if folder is not None else Path(tmp)
            if folder is None:
                write_active_scene(sc, where)
            res = run_active_files(where, where / "nav.csv", ActiveSettings(spacing_m=spacing,
                                                                             elements=sc.sonar.elements))
            truth = pd.read_csv(where / "truth.csv")
    finally:
        run_mod.ContactTracker = real
    a = _Recorder.args
    out = {"contacts": res.contacts, "time_s": res.ping_time_s, "geometry": res.geometry, "truth": truth,
           "settings": res.settings, "rate_sd": a[3], "kwargs": {k: v for k, v in _Recorder.kwargs.items()
                                                                if k in ("clutter_area_m2", "scan_interval_s")}}
    cache.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(out))
    return out


class _Spy:
    """A deleter layer's stand-in that records the tracks its ``inner`` layer removed, with its depth."""

    def __init__(self, inner, depth: int, log: dict):
        self.inner, self.depth, self.log = inner, depth, log

    def new_track_attrs(self, k: int) -> dict:
        return self.inner.new_track_attrs(k)

    def manage(self, T, hit):
        out = self.inner.manage(T, hit)
        gone = set(T.track_id.tolist()) - set(out.track_id.tolist())
        for tid in gone:  # the deepest layer that removed a track is the one that removed it
            if self.depth > self.log.get(tid, (-1, ""))[0]:
                self.log[tid] = (self.depth, type(self.inner).__name__)
        return out


def _spy_deleters(tracker, log: dict) -> None:
    """Wrap each layer of the tracker's deleter chain (outermost .. innermost) in a :class:`_Spy`."""
    layers, d = [], tracker.deleter
    while d is not None:
        layers.append(d)
        d = getattr(d, "inner", None)
    for depth, layer in enumerate(layers):
        if depth + 1 < len(layers):
            object.__setattr__(layer, "inner", _Spy(layers[depth + 1], depth + 1, log))
    tracker.deleter = _Spy(layers[0], 0, log)


REASONS = {"RateConfirmation": "coasted out", "ExistenceDeleter": "coasted out", "DuplicateMerger": "merged",
           "GhostDeleter": "ghost", "StillHold": "held"}


def _alias(s, c: dict):
    """The chain's endfire alias for the cached scene (its pulse from the scene's settings: the cache keeps none)."""
    from sonartrack.systems.active.contact_tracker import endfire_alias_of

    return endfire_alias_of(s, scene(c["kind"], c["seed"]).waveform.waveform())


def track(c: dict, settings=None, extra: dict | None = None):
    """The chain's tracker stage over the cached contacts with ``settings`` (default: ActiveSettings() on the path,
    the CW contacts' errors as cached); returns (ActiveTracks, {track: reason it ended})."""
    from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of
    from sonartrack.systems.active.settings import ActiveSettings

    s = settings or ActiveSettings(spacing_m=c["settings"].spacing_m, elements=c["settings"].elements)
    trk = ContactTracker(s.tracker_settings(), c["geometry"], s.range_rate_gate_sigma, c["rate_sd"],
                         s.side_turn_deg, s.merge_probability, s.max_range_rate_mps, turns=s.turn_modes(),
                         clutter_map=clutter_map_of(s), **c["kwargs"],
                         **({"rejoin_s": s.rejoin_s} if hasattr(s, "rejoin_s") else {}),  # (an older chain: none)
                         **({"claims": s.contact_claims} if hasattr(s, "contact_claims") else {}),
                         **({"keep_apart": s.merge_keep_apart} if hasattr(s, "merge_keep_apart") else {}),
                         **({"reunite_scans": s.merge_reunite_scans} if hasattr(s, "merge_reunite_scans") else {}),
                         **({"endfire_alias": _alias(s, c)} if hasattr(s, "endfire_alias") else {}), **(extra or {}))
    log: dict = {}
    _spy_deleters(trk.tracker, log)
    con = c["contacts"]
    for t in c["time_s"]:
        trk.step(float(t), con.rows(np.nonzero(np.isclose(con.time_s, t))[0]))
    return trk.result(), {tid: REASONS.get(name, name) for tid, (_, name) in log.items()}


def _truth_arrays(truth, geometry):
    from sonartrack.systems.active.targets import _reflect

    tt = np.asarray(truth["time_s"], float)
    xy = np.stack([np.asarray(truth["x_m"], float), np.asarray(truth["y_m"], float)], -1)
    mirror = np.array([_reflect(geometry, a, b) for a, b in zip(tt, xy, strict=True)]).reshape(-1, 2)
    return tt, np.asarray(truth["target"]).astype(str), xy, mirror


def track_labels(tracks, truth, geometry, gate_m: float) -> dict:
    """track id -> (true target name or "false", ghost share): the target within ``gate_m`` (it or its mirror) on
    most of the track's confirmed rows; the share of those rows nearer its mirror."""
    t = tracks.tracks
    tt, names, xy, mirror = _truth_arrays(truth, geometry)
    out = {}
    for tid in np.unique(t.track_id[t.confirmed]):
        votes, ghost = {}, {}
        for r in np.nonzero((t.track_id == tid) & t.confirmed)[0]:
            at = np.nonzero(np.isclose(tt, t.time_s[r]))[0]
            d, dm = np.hypot(*(xy[at] - t.x[r, :2]).T), np.hypot(*(mirror[at] - t.x[r, :2]).T)
            k = int(np.argmin(np.minimum(d, dm))) if len(at) else -1
            name = names[at[k]] if k >= 0 and min(d[k], dm[k]) < gate_m else "false"
            votes[name] = votes.get(name, 0) + 1
            ghost[name] = ghost.get(name, 0) + (k >= 0 and dm[k] < d[k])
        n = sum(votes.values())
        best = max(votes, key=lambda k: (votes[k], k != "false"))
        out[int(tid)] = (best if votes[best] * 2 > n or best != "false" else "false", ghost[best] / votes[best])
    return out


def _ping(c, t_s: float) -> int:
    return int(np.argmin(np.abs(c["time_s"] - t_s)))


def report(c: dict, res, reasons: dict, gate_m: float = 1000.0, label: str = "") -> dict:
    """Print the rows, segments, held % and ends of one run (module doc); returns the counts."""
    from bench_cw_held import detectable_rows
    from sonartrack.systems.active.targets import mirror_targets, truth_scores

    g, truth, t = c["geometry"], c["truth"], res.tracks
    targets = mirror_targets(res, g)
    labels = track_labels(res, truth, g, gate_m)
    det = detectable_rows(truth)
    detectable = sorted(set(det["target"].astype(str)))
    held = truth_scores(res, targets, det, g)["held"]
    rows_of: dict[str, int] = {}
    false_rows = ghost_rows = short_rows = 0
    mixed: list[str] = []
    for k in range(len(targets)):
        short_rows += _ping(c, targets.last_s[k]) - _ping(c, targets.first_s[k]) + 1 <= 2
        tid = int(targets.track_id[k]) if targets.track_id[k] >= 0 else int(targets.mirror_track_id[k])
        name = labels.get(tid, ("false", 0))[0]
        rows_of[name] = rows_of.get(name, 0) + 1
        false_rows += name == "false"
        ghost_rows += bool(targets.decision[k] == "decided" and targets.track_id[k] < 0)
        held_by = {labels[m][0] for m in targets.chains[k][0] + targets.chains[k][1]
                   if m in labels and labels[m][1] <= 0.5} - {"false"}  # (a ghost's label is ambiguous: left out)
        if len(held_by) > 1:  # one row listing the tracks of two or more true targets (merged / re-joined)
            mixed.append(f"row {k + 1}: {'+'.join(sorted(held_by))}")
    short, ends, lines = 0, {}, []
    for name in detectable + sorted({v[0] for v in labels.values()} - set(detectable)):
        segs = []
        for tid, (lab, ghost) in labels.items():
            if lab != name:
                continue
            rows = np.nonzero(t.track_id == tid)[0]
            conf = rows[t.confirmed[rows]]
            p0, p1, born = _ping(c, t.time_s[conf[0]]), _ping(c, t.time_s[conf[-1]]), _ping(c, t.time_s[rows[0]])
            why = reasons.get(tid, "alive")
            ends[why] = ends.get(why, 0) + 1
            short += p1 - p0 + 1 <= 2
            segs.append(f"{tid}:{p0}-{p1}({p1 - p0 + 1}p, conf@{p0 - born + 1}{', ghost' if ghost > 0.5 else ''}, "
                        f"{why})")
        h = held.get(name)
        lines.append(f"    {name}: rows {rows_of.get(name, 0)}, held {'-' if h is None else f'{100 * h:.0f}'} %; "
                     + " ".join(segs))
    n_false = rows_of.get("false", 0)
    extra = sum(max(rows_of.get(n, 0) - 1, 0) for n in detectable) + sum(
        v for n, v in rows_of.items() if n not in detectable and n != "false")
    print(f"{label}: {len(targets)} rows for {len(detectable)} detectable targets; false rows {n_false}, duplicate/"
          f"extra rows {extra}, ghost-only rows {ghost_rows}, rows of <= 2 pings {short_rows}; confirmed tracks "
          f"{len(labels)}, of them confirmed on <= 2 pings {short}; ends {ends}; held % of detectable pings (mean) "
          f"{100 * np.mean([held.get(n, 0) for n in detectable]):.0f}; rows holding 2+ true targets {len(mixed)}"
          + (f" ({', '.join(mixed)})" if mixed else ""))
    print("\n".join(lines))
    return {"rows": len(targets), "false": n_false, "short_rows": short_rows, "extra": extra, "ghost_rows": ghost_rows,
            "mixed": len(mixed),
            "short": short, "held": {n: held.get(n, 0.0) for n in detectable}}


def with_changes(c: dict, changes: list[str]):
    """ActiveSettings() on the path for the cached scene with ``NAME=VALUE`` changes (``tracker.NAME``: the
    tracker's)."""
    import json

    from sonartrack.systems.active.settings import ActiveSettings

    s = ActiveSettings(spacing_m=c["settings"].spacing_m, elements=c["settings"].elements)
    for item in changes:
        name, value = item.split("=", 1)
        if name.startswith("tracker."):
            s = s.model_copy(update={"tracker": s.tracker.model_copy(update={name[8:]: json.loads(value)})})
        else:
            s = s.model_copy(update={name: json.loads(value)})
    return s


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--cache", default="/tmp/active_rows")
    p.add_argument("--kinds", nargs="+", default=["lfm", "cw"], help="lfm, cw, cwb (bench_cw_held.py's scene b)")
    p.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    p.add_argument("--gate-m", type=float, default=1000.0)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="an ActiveSettings field (tracker.NAME for the tracker's), the value read as JSON; repeatable")
    p.add_argument("--reunite", type=int, default=None,
                   help="ContactTracker reunite_scans (default: the settings' merge_reunite_scans)")
    a = p.parse_args()
    for kind in a.kinds:
        for seed in a.seeds:
            c = {**run_scene(kind, seed, Path(a.cache)), "kind": kind, "seed": seed}
            extra = {} if a.reunite is None else {"reunite_scans": a.reunite}
            res, reasons = track(c, with_changes(c, a.set), extra)
            report(c, res, reasons, a.gate_m, f"{kind.upper()} seed {seed}")


if __name__ == "__main__":
    main()
