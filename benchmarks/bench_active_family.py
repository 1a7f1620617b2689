"""Where the active-chain study's false confirmed tracks come from, on the study's own family of scenes.

Runs the reverberation-only twin of chosen trials of study ``active-chain`` at full size (the trial's scene drawn
exactly as studies/active_chain.py ``run_trial`` draws it: ``trial_rng(seed, i)``, two seeds, then
studies/active_chain_family.py ``draw_scene``; the twin keeps the clutter points and takes the second seed), through
the chain of ``sonartrack active``, and prints per confirmed track (every one of them is a false track to the study):
the trial's axes, its confirmed span (pings), where it sits, its speed, and whether the study is right to call it false.

Where a track sits, tested in this order on its confirmed rows (the majority label is printed):

* ``clutter`` within ``--gate`` of a persistent clutter point (a still point target: false, rightly);
* ``mirror`` within ``--gate`` of a clutter point's mirror about the array axis (a ghost of clutter: false);
* ``lobe`` at a clutter point's bistatic range (within ``--range-tol``) but elsewhere in cone (a grating- or
  side-lobe image of its echo: false);
* ``early`` travel time below ``--early`` s (the near, loud reverberation and the blanking edge);
* ``ridge`` (CW only) the track's predicted bistatic range rate within ``--ridge`` m/s of a still point's at its
  place (the reverberation ridge: zero Doppler in the world);
* ``none`` nowhere in particular.

Usage: ``python benchmarks/bench_active_family.py --trials 4 1 --minutes 20``; each trial's chain output is kept as
a pickle under ``--cache`` (the same trial, seed, length and code are not re-run: delete the folder after a change).
Minutes of CPU per trial-hour.

Measured (2026-12-07, seed 2017, 1 h twins; false confirmed tracks, study at c9e14ab -> 19a2d3c -> h10-actfam):
trial 1 (CW, 8 x 0.5 m, 1 kHz, Rayleigh +5 dB, 14 points) 41 -> 43 -> (20 min: 9 -> 9): 10 on points, 5 on their
mirrors, 27 at a point's bistatic range elsewhere in cone (sidelobes), 38 of 43 in mirror pairs; trial 4 (LFM 16 x
0.25 m, spiky K, 14 points) 54 -> 4 -> 0; trial 8 (LFM 32 x 0.25 m, K +10 dB, 14 points) 12 -> ? -> 2; trial 2
(LFM 32 x 0.5 m, K +10 dB, no points) 13 -> (20 min: 6) -> 5, at broadside near delays moving with the ownship.

Measured (2026-12-07, h11-fam2, main at 0e2e8dd; ``--lobe-margin-db 3 --mftd-cell-lobes``: detection/lobes.py
``cell_images`` on the single-ping and the MFTD detections, the CW cells carrying the power before the ridge notch,
a detection on the skirt of a notched echo withheld with it): trial 1, 1 h: 37 -> 6 false confirmed (at a point's
range elsewhere in cone 21 -> 0, on points 7 -> 4, on mirrors 4 -> 2, nowhere 4 -> 0, early 1 -> 0; 15 before the
skirt rule); 20 min: trial 1 9 -> 2, trial 2 4 -> 2, trial 4 0 -> 0, trial 8 2 -> 2; 1 h with it: trial 2 2 (both
early, one mirror pair), trial 8 2 (one pair on a point). The lobe test costs
~1.3 s CPU per hour of LFM pings (trials 2, 4, 8), 0.1 s per CW hour. Left on trial 1: the clutter map on one TS
30 dB point: replayed on the chain's contacts it gives a contact on ~35 of 120 pings (a still point is on its own
beam's reverberation ridge, which the CW front end notches), 400-900 m from it with sds 220-570 m, recurring on some
pings but never shown still in the map's 24-ping fit. On trial 8 a track at 0.18 m/s on a TS 24 dB point was
confirmed at ping 7, the map's verdict came at ping 9: with StillHold's ``moving_gamma`` (tracking/deleters.py,
chi2_2 at 0.9, ``--still-moving-p 0.9``; built by contact_tracker.py, not ours) 2 -> 0 in 20 min.

Measured (2026-12-07, h11-fam3, main at 09bf76c; ``--skirt-margin-db 3``: detection/cw_cells.py ``notch_skirts``, a
notched echo's delay-Doppler skirt not searched): trial 1, 1 h: 6 -> 0 false confirmed (20 min: 0), 3.6 s CPU per
CW hour for the test, 6.3 % of the cells not searched. Why the 6 were there: the TS 30 dB point gave contacts on
only ~10 pings, 600-1000 m off in bistatic range and 1.5-2.4 m/s off its range rate (the CW ambiguity's skirt at
half a pulse off in delay, where the Doppler main lobe is twice as wide; so the travel time of these contacts is NOT
accurate, and a stillness test on bistatic range would not hold them), and each track was confirmed on 2 strong
contacts 30 s apart (existence 0.05 -> 0.87-0.98) and then coasted confirmed for 10-40 pings on nothing. Sources
of the skirt at s >= 30: 6 -> 4; only the echo's peak as source: 6 -> 2. Off by default: on the default scene as
CW (bench_active_rows.py, seeds 1, 2; contacts compared ping by ping with main's) the test removed no contact of
the approacher and crossing-a/b but 1-3, and 9-14 of the maneuvering target's (pings 13-21 and 45-52, while it held
the sea's Doppler: its own echo notched, its skirt had kept its confirmed track; held 91 -> 65 % on seed 1). A
still point and a target on the ridge are the same thing on one ping; what tells them apart is that the target is
confirmed before and after. So ``--skirt-to-confirmed 3`` (the proposed change to systems/active/*, not ours,
measured by wrapping: the skirt cells searched as before, their detections' contacts given only to confirmed tracks
whose gate holds them, as the clutter map's): trial 1, 1 h: 6 -> 2 (the mirror pair on the TS 30 dB point from
ping 76 is left); default scene as CW (rows, false, extra; held %): seed 1 7, 1, 2; 95/75/100/89 (main 7, 1, 2;
95/75/100/91), seed 2 7, 1, 2; 90/82/100/84 (main 5, 0, 1; 90/76/100/85; the CW rows move by 1-2 with any change of
the contacts, ACTHOLD's sweeps). 28 contacts flagged in seed 2's 120 pings.

Measured (2026-12-07 session 12, h12-cwmap, main at e4c2ec6; 1 h twins, ~2.5-4 min a trial at load 8-11): the CW
chain's ridge map (systems/active/contact_tracker.py ``ridge_map_of``, ``_ridge_clutter``): the echoes under each
beam's ridge notch (detection/cw_cells.py ``ridge_echoes``) in a clutter map of their own, and the contacts in a
known still point's gate or within c tau and 2.5 Doppler cells of its echo (clutter_map.py ``echo_images``) given only
to confirmed tracks. False confirmed tracks (listed rows), main -> this: trial 15 (CW, K +5 dB, 16 x 0.5 m, 2.4 kHz,
14 points) 9 (5) -> 0 (0); trial 1 (CW, Rayleigh +5 dB, 8 x 0.5 m, 1 kHz, 14 points) 6 (1) -> 4 (1): the pair 37/38
on point 13 from ping 76 gone, left the pairs of pings 11-37 and 50-63 on the same TS 30 dB point at cone 5-15 deg,
whose hidden echoes come on about half the pings, 100-1400 m off it with 300-540 m sds across the beam (the 8-element
array's beams near endfire), so the ridge map shows it still only from ping 58; trial 11 (CW, spiky K +10 dB, 32 x
0.25 m, 2.4 kHz, 6 points) 4 (2) -> 4 (2): two pairs at 0.2-0.3 m/s on points 3 (TS 27 dB) and 4 (22 dB), each
confirmed on two skirt contacts 700-800 m off the point (r_B +1100-1400 m) and then coasting; point 3's hidden echo
comes on 15 of the first 40 pings, so the ridge map shows it still only from ping 44, and at ping 45 (the second
skirt contact) no hidden echo was found; trial 8 (LFM, K +10 dB, 14 points) 0 -> 0 (the ridge map is a CW's).
Cost: finding the hidden echoes 2.75 s CPU per hour on trial 15 (22 a ping, most of them the sea's
ridge peaks), 1.1 s on trial 1; the ridge map's updates within the tracker stage's noise (benchmarks/
bench_cw_ridge_map.py). On the default scene as CW (bench_cw_ridge_map.py, seeds 1 and 2, the same contacts with and
without): rows, false rows and held % of every target unchanged (seed 1 6, 1, 1; 95/75/100/91; seed 2 4, 0, 0;
90/76/100/85); 13 ridge contacts shown still on seed 2 (no clutter points there), 14 contacts marked: the same
confirmed tracks (two ids shifted); bench_cw_held.py's scene b (32 x 0.3 m, 2.4 kHz) seed 1: identical, 0 shown
still. A first version feeding the hidden echoes to the tracker's own map (3 hits) gave trial 15 0
too, but seed 2 4 -> 5 rows (19 ridge contacts shown still, the sea's ridge peaks recurring by chance). Tried and
left off: the window also about every known ridge point's echo (its place, a still point's range rate there) on pings
where its hidden peak was not found: trial 11 4 -> 4 (the pairs confirm before the point is known), default scene
seed 2 4 -> 5 rows (81 contacts marked instead of 14). Left: a track confirmed on two skirt contacts 30 s apart
before the ridge map knows the point, which then coasts confirmed for 10-20 pings on nothing (trials 1, 11; FAM3's
note): the map cannot act before it has ~10 pings of the point, so this is the confirmation's to fix.

Measured (2026-12-08 session 12, h12-pt18 on h12-lead 25a932b; 1 h twins, ~2.5 min a trial, cache deleted between):
trial 18 (LFM 50 Hz at 1.5 kHz, 48 x 0.75 m, Rayleigh, 14 points) 4 -> 0 false confirmed tracks (2 -> 0 rows), trial
8 0 -> 0. Neither pair was what its label said. The pair "on" point 0 (TS 24 dB, labels clutter/mirror, 4.2 m/s) was
the grating image of point 6 (TS 30 dB at cone 0-2 deg, its own contacts recurring and withheld on every ping): at
d = 0.75 lambda the array factor repeats every 4/3 in u = cos(cone), so the point is also heard at cone 109; the image
moves in the world with the array (so the map never shows it still) and passed point 0's place at ping 107; its r_B
was 1-32 m (median ~17 m, 2-3 delay cells) off the point's contact, outside the 15 m image window (same_range, and
EndfireAlias's, which held only confirmed tracks' echoes anyway). The travel times the label tests are the
truth's, so the LFM's range-Doppler coupling (f_d T / B: ~145 m at 5 m/s) also hid the match with point 6 (``lobe``
wants c / B = 30 m). The "none" pair at 9.6 s (cone 16-44 deg, 3.9 m/s) was the grating image of point 10 (TS 27 dB,
cone 112-128 deg). Fix (systems/active/contact_tracker.py): a contact within the alias lobe of a contact the map
shows still (not only recurring: a moving target's echo and its image both recur) and within c / B_i of its r_B,
B_i = min(B, f_0 / N) the image's own band (the grating image passes only where it lies in the beam's main lobe),
is withheld as the map's clutter (48 m here). Replayed on the same contacts: 182 of 4316 contacts (4 %) newly
withheld from unconfirmed tracks, on 57 of 120 pings. Default scene LFM seeds 1, 2 (bench_active_rows.py on the
cached contacts of /tmp/lead11/rows11, i.e. e4c2ec6's front end; the change is the tracker's): identical output, and
CW seeds 1, 2 identical. With the targets (the trials' full scenes, 1 h): trial 18, the tracker replayed on the same
contacts, 9 -> 7 confirmed tracks, every target's pings held unchanged (24/20/45/57/0 of 120); trial 15 (CW, 16 x 0.5
m at 2.4 kHz, d = 0.8 lambda; the chain run twice) identical, 20 confirmed tracks, the same pings held.
"""

from __future__ import annotations

import argparse
import pickle
import time
from pathlib import Path

import numpy as np

AXIS_NAMES = ("pulse", "model", "elements", "spacing", "carrier", "bandwidth", "tow", "level", "clutter")


def trial_scene(config, seed: int, index: int, minutes: float | None):
    """The trial's reverberation-only twin scene (module doc) and its axes' values."""
    from sonartrack.core.random import trial_rng
    from sonartrack.studies.active_chain import MANEUVERING
    from sonartrack.studies.active_chain_claims import _labels
    from sonartrack.studies.active_chain_family import draw_scene, is_clutter

    rng = trial_rng(seed, index)
    seeds = rng.integers(0, 2**31 - 1, size=2)
    drawn, axes = draw_scene(config.scene, config.family, rng, MANEUVERING)
    labels = list(_labels(config).values())
    values = {n: labels[a][int(axes[a])] for a, n in enumerate(AXIS_NAMES)}
    dur = drawn.duration_s if minutes is None else 60.0 * minutes
    clutter = [t for t in drawn.targets if is_clutter(t.name)]
    return drawn.model_copy(update={"seed": int(seeds[1]), "targets": clutter, "duration_s": dur}), values


def run_quiet(config, scene, cache: Path):
    """The chain's result on ``scene`` (cached by the scene's JSON)."""
    import hashlib

    from sonartrack.studies.active_chain import run_scene

    key = hashlib.sha1((scene.model_dump_json() + config.chain.model_dump_json()).encode()).hexdigest()[:12]
    path = cache / f"quiet-{key}.pkl"
    if path.exists():
        with path.open("rb") as f:
            return pickle.load(f), 0.0
    t0 = time.perf_counter()
    result = run_scene(config.model_copy(update={"scene": scene}), scene)[0]
    cache.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        pickle.dump(result, f)
    return result, time.perf_counter() - t0


def _cone_deg(geometry, t, xy) -> np.ndarray:
    rx, h = geometry.rx_at(t), geometry.heading_at(t)
    d = xy - rx
    a = np.stack([np.sin(h), np.cos(h)], -1)
    return np.rad2deg(np.arccos(np.clip(np.einsum("ni,ni->n", d, a) / np.hypot(*d.T), -1, 1)))


def _bistatic_m(geometry, t, xy) -> np.ndarray:
    return np.hypot(*(xy - geometry.tx_at(t)).T) + np.hypot(*(xy - geometry.rx_at(t)).T)


def _mirror(geometry, t, xy) -> np.ndarray:
    rx, h = geometry.rx_at(t), geometry.heading_at(t)
    a = np.stack([np.sin(h), np.cos(h)], -1)
    d = xy - rx
    return rx + 2.0 * np.einsum("ni,ni->n", d, a)[:, None] * a - d


def _still_rate(geometry, t, xy) -> np.ndarray:
    """Bistatic range rate (m/s) of a still point at ``xy``: the platforms' motion alone."""
    dt = 1.0
    return (_bistatic_m(geometry, t + dt, xy) - _bistatic_m(geometry, t, xy)) / dt


def classify(result, scene, args) -> list[dict]:
    """One row per confirmed track (module doc)."""
    from sonartrack.studies.active_chain_family import is_clutter

    tr, g = result.tracks.tracks, result.geometry
    pts = np.array([[t.x_m, t.y_m] for t in scene.targets if is_clutter(t.name)], float).reshape(-1, 2)
    ping_of = {float(t): k + 1 for k, t in enumerate(result.ping_time_s)}
    c = scene.sound_speed_mps
    out = []
    for tid in np.unique(tr.track_id[tr.confirmed]):
        rows = np.nonzero((tr.track_id == tid) & tr.confirmed)[0]
        t, xy = tr.time_s[rows], tr.x[rows, :2]
        labels, near_pt = [], []
        for k in range(len(rows)):
            tk = np.full(len(pts), t[k])
            lab, j = "none", -1
            if len(pts):
                d = np.hypot(*(pts - xy[k]).T)
                dm = np.hypot(*(_mirror(g, tk, pts) - xy[k]).T)
                dr = np.abs(_bistatic_m(g, tk, pts) - _bistatic_m(g, t[k:k + 1], xy[k:k + 1]))
                if d.min() < args.gate:
                    lab, j = "clutter", int(d.argmin())
                elif dm.min() < args.gate:
                    lab, j = "mirror", int(dm.argmin())
                elif dr.min() < args.range_tol:
                    lab, j = "lobe", int(dr.argmin())
            if lab == "none" and _bistatic_m(g, t[k:k + 1], xy[k:k + 1])[0] / c < args.early:
                lab = "early"
            if lab == "none" and scene.waveform.kind == "cw":
                rr_track = _rate_of(g, t[k], tr.x[rows[k]])
                if abs(rr_track - _still_rate(g, t[k:k + 1], xy[k:k + 1])[0]) < args.ridge:
                    lab = "ridge"
            labels.append(lab)
            near_pt.append(j)
        vals, counts = np.unique(labels, return_counts=True)
        lab = str(vals[counts.argmax()])
        js = [j for j, lb in zip(near_pt, labels, strict=True) if lb == lab and j >= 0]
        j = int(np.bincount(js).argmax()) if js else -1
        mid = len(rows) // 2
        info = {"track": int(tid), "pings": f"{ping_of.get(float(t[0]), -1)}-{ping_of.get(float(t[-1]), -1)}",
                "n": len(rows), "where": lab, "share": float(counts.max() / len(rows)),
                "speed_mps": float(np.median(np.hypot(tr.x[rows, 2], tr.x[rows, 3]))),
                "delay_s": float(_bistatic_m(g, t[mid:mid + 1], xy[mid:mid + 1])[0] / c),
                "cone_deg": float(_cone_deg(g, t[mid:mid + 1], xy[mid:mid + 1])[0]), "point": j}
        if j >= 0:
            info["point_cone_deg"] = float(_cone_deg(g, t[mid:mid + 1], pts[j:j + 1])[0])
            info["point_ts_db"] = float([x for x in scene.targets if is_clutter(x.name)][j].target_strength_db)
        out.append(info)
    return out


def _rate_of(geometry, t, x) -> float:
    """Predicted bistatic range rate (m/s) of the track state ``x`` [x, y, vx, vy] at time ``t``."""
    p0, v = np.asarray(x[:2], float)[None], np.asarray(x[2:4], float)
    return float((_bistatic_m(geometry, np.array([t + 1.0]), p0 + v) - _bistatic_m(geometry, np.array([t]), p0))[0])


def mirror_pairs(result, gate_m: float = 500.0) -> int:
    """How many of the confirmed tracks are one of a mirror pair: two confirmed tracks each within ``gate_m`` of the
    other's mirror about the array axis (median over their common pings), i.e. one echo's two hypotheses (issue 34
    item 4: one row)."""
    tr, g = result.tracks.tracks, result.geometry
    ids = np.unique(tr.track_id[tr.confirmed])
    rows = {i: np.nonzero((tr.track_id == i) & tr.confirmed)[0] for i in ids}
    paired = set()
    for a in ids:
        for b in ids:
            if b <= a or a in paired or b in paired:
                continue
            ta, tb = tr.time_s[rows[a]], tr.time_s[rows[b]]
            common, ia, ib = np.intersect1d(ta, tb, return_indices=True)
            if len(common) < 2:
                continue
            xa, xb = tr.x[rows[a][ia], :2], tr.x[rows[b][ib], :2]
            if np.median(np.hypot(*(_mirror(g, common, xb) - xa).T)) < gate_m:
                paired.update((int(a), int(b)))
    return len(paired)


def verdict(row: dict) -> str:
    """Is the study right to call this track false? (quiet scene: no targets, so every track is false.)"""
    return "false (right)"


def _patch_mftd_lobes() -> None:
    """ping_mftd's lobe filter replaced by detection/lobes.py's cell test (``--mftd-cell-lobes``: the change proposed
    to its owner; ping_mftd.drop_lobe_images tests MFTD detections against each other only)."""
    import sonartrack.detection.ping_mftd as pm
    from sonartrack.detection.lobes import drop_cell_images

    pm.drop_lobe_images = drop_cell_images


def _patch_still_hold(probability: float) -> None:
    """tracking/deleters.py StillHold built with ``moving_gamma`` (``--still-moving-p``: the chi-square(2) quantile at
    this probability; contact_tracker.py builds it, not ours: the change proposed to its owner)."""
    import functools

    import sonartrack.tracking.deleters as dl
    from sonartrack.association.gating import gate_threshold

    dl.StillHold.__init__ = functools.partialmethod(dl.StillHold.__init__,
                                                    moving_gamma=float(gate_threshold(probability, 2)))


SKIRT = {"mask": None, "flags": {}}  # the last CW ping's skirt cells; contact flags by ping time (s)


def _patch_skirt_to_confirmed(margin_db: float) -> None:
    """``--skirt-to-confirmed``: a notched echo's skirt (detection/cw_cells.py notch_skirts) is searched as before,
    but the contacts of detections on it go only to confirmed tracks whose gate holds them, as the clutter map's
    (the proposed change to systems/active/*, not ours: here by wrapping the front end, the contact forming and
    ContactTracker._not_clutter). The source test reads s before the notch as power / level."""
    import sonartrack.detection.cw_cells as cc
    import sonartrack.systems.active.contact_tracker as ct
    import sonartrack.systems.active.run as run_mod

    front, forms, inner = cc.cw_ping_cells, (run_mod.form_contacts, run_mod.cw_form_contacts), \
        ct.ContactTracker._not_clutter

    def cells_with_mask(*a, **k):
        cells = front(*a, **k)
        notch = (cells.statistic == 0).all(axis=1)
        if cells.power is None or not notch.any():
            SKIRT["mask"] = None
            return cells
        power = np.asarray(cells.power, float)
        SKIRT["mask"] = cc.notch_skirts(power, power / np.maximum(np.asarray(cells.level, float), 1e-30), notch,
                                        np.asarray(cells.delay_s), np.asarray(cells.doppler_hz), a[2].duration_s,
                                        margin_db)
        return cells

    def flagged(form):
        def wrapped(det, *a, **k):
            c = form(det, *a, **k)
            m = SKIRT["mask"]
            if m is not None and len(c):
                i = c.detection
                SKIRT["flags"][round(float(c.time_s[0]), 3)] = m[det.beam[i], det.delay_cell[i], det.doppler_cell[i]]
            return c
        return wrapped

    def not_clutter(self, t_s, contacts):
        keep = inner(self, t_s, contacts)
        flag = SKIRT["flags"].get(round(float(t_s), 3))
        if flag is None or len(flag) != len(contacts) or not flag.any():
            return keep
        from sonartrack.systems.active.contact_tracker import in_position_gate

        x, P, _ = self._predicted_confirmed(t_s)
        held = in_position_gate(contacts, x, P, self.settings.gate_probability).any(axis=0) if len(x) else False
        return keep & (~flag | held)

    cc.cw_ping_cells = cells_with_mask
    run_mod.form_contacts, run_mod.cw_form_contacts = (flagged(f) for f in forms)
    ct.ContactTracker._not_clutter = not_clutter


LOBE_CPU = {"s": 0.0, "calls": 0}


def _time_lobes() -> None:
    """Count the CPU seconds spent in detection/lobes.py ``cell_images`` (the lobe test's cost)."""
    import sonartrack.detection.cells as cells
    import sonartrack.detection.lobes as lobes

    inner = lobes.cell_images

    def timed(*a, **k):
        t0 = time.process_time()
        out = inner(*a, **k)
        LOBE_CPU["s"] += time.process_time() - t0
        LOBE_CPU["calls"] += 1
        return out

    lobes.cell_images = cells.cell_images = timed


RIDGE_CPU = {"s": 0.0, "calls": 0, "echoes": 0}


def _time_ridge() -> None:
    """Count the CPU seconds spent finding the echoes under the CW ridge notch and forming their contacts
    (systems/active/run.py ``_Chain._ridge_contacts``: the clutter map's extra input)."""
    import sonartrack.systems.active.run as run_mod

    inner = getattr(run_mod._Chain, "_ridge_contacts", None)
    if inner is None:  # (a chain without it)
        return

    def timed(self, *a, **k):
        t0 = time.process_time()
        out = inner(self, *a, **k)
        RIDGE_CPU["s"] += time.process_time() - t0
        RIDGE_CPU["calls"] += 1
        RIDGE_CPU["echoes"] += 0 if out is None else len(out) // 2
        return out

    run_mod._Chain._ridge_contacts = timed


def main() -> None:
    from sonartrack.studies.active_chain import Config

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[4, 1])
    ap.add_argument("--seed", type=int, default=2017, help="the study's master seed (sonartrack reproduce's default)")
    ap.add_argument("--minutes", type=float, default=None, help="length of the twin (not set: the scene's, 1 h)")
    ap.add_argument("--gate", type=float, default=1500.0, help="on a point / its mirror within this (m; study match)")
    ap.add_argument("--range-tol", type=float, default=None, help="lobe image: bistatic range within this (m; not "
                    "set: c / B for an LFM, c tau / 2 for a CW)")
    ap.add_argument("--early", type=float, default=3.0, help="early delays: travel time below this (s)")
    ap.add_argument("--ridge", type=float, default=0.3, help="CW ridge: range rate within this of a still point's")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_family"))
    ap.add_argument("--lobe-margin-db", type=float, default=None, help="the front end's lobe-image margin (cells.py "
                    "lobe_margin_db; not set: the chain's default)")
    ap.add_argument("--heavy-tail-cells", default=None, help="the front end's heavy_tail_cells ('none': one K "
                    "shape for all beams, as before 10a6196; not set: the chain's default)")
    ap.add_argument("--mftd-cell-lobes", action="store_true", help="measure the proposed ping_mftd.py change (not "
                    "ours: MFTDGAIN's): its detections' lobe images found by detection/lobes.py cell_images")
    ap.add_argument("--skirt-margin-db", type=float, default=None, help="the CW front end's skirt test (detection/"
                    "cw_cells.py skirt_margin_db: a notched echo's delay-Doppler skirt not searched; not set: default)")
    ap.add_argument("--skirt-to-confirmed", type=float, default=None, help="the proposed change (not ours): skirt "
                    "contacts (notch_skirts at this margin, dB) go only to confirmed tracks, instead of not searched")
    ap.add_argument("--still-moving-p", type=float, default=None, help="StillHold's moving test at this confidence "
                    "(tracking/deleters.py moving_gamma; not set: the speed estimate alone)")
    args = ap.parse_args()
    args._tol = args.range_tol
    if args.still_moving_p is not None:
        _patch_still_hold(args.still_moving_p)
    _time_lobes()
    _time_ridge()
    if args.skirt_to_confirmed is not None:
        _patch_skirt_to_confirmed(args.skirt_to_confirmed)
    if args.mftd_cell_lobes:
        _patch_mftd_lobes()
    config = Config()
    update = {} if args.lobe_margin_db is None else {"lobe_margin_db": args.lobe_margin_db}
    if args.heavy_tail_cells is not None:
        update["heavy_tail_cells"] = None if args.heavy_tail_cells == "none" else int(args.heavy_tail_cells)
    fe = config.chain.front_end.model_copy(update=update)
    chain_update = {"front_end": fe}
    if args.skirt_margin_db is not None:
        chain_update["cw"] = config.chain.cw.model_copy(update={"skirt_margin_db": args.skirt_margin_db})
    config = config.model_copy(update={"chain": config.chain.model_copy(update=chain_update)})
    total_false, total_h = 0, 0.0
    for i in args.trials:
        scene, values = trial_scene(config, args.seed, i, args.minutes)
        result, sec = run_quiet(config, scene, args.cache)
        w = scene.waveform
        args.range_tol = tol if (tol := getattr(args, "_tol", None)) is not None else (
            scene.sound_speed_mps / w.bandwidth_hz if w.kind == "lfm" else 0.5 * scene.sound_speed_mps * w.duration_s)
        rows = classify(result, scene, args)
        hours = scene.duration_s / 3600.0
        total_false, total_h = total_false + len(rows), total_h + hours
        print(f"trial {i}: " + " ".join(f"{k}={v}" for k, v in values.items()) +
              f" | {len(rows)} false confirmed in {hours:.2f} h ({len(rows) / hours:.1f}/h), run {sec:.0f} s")
        by = {}
        for r in rows:
            by[r["where"]] = by.get(r["where"], 0) + 1
            extra = (f" point {r['point']} (TS {r['point_ts_db']:.0f} dB, cone {r['point_cone_deg']:.0f})"
                     if r["point"] >= 0 else "")
            print(f"  track {r['track']:4d} pings {r['pings']:>7s} ({r['n']:3d}) {r['where']:7s} {r['share']:.0%} "
                  f"speed {r['speed_mps']:5.2f} m/s delay {r['delay_s']:5.1f} s cone {r['cone_deg']:5.1f}{extra} "
                  f"-> {verdict(r)}")
        from sonartrack.systems.active.targets import mirror_targets

        n_rows = len(mirror_targets(result.tracks, result.geometry))
        print("  by place: " + ", ".join(f"{k} {v}" for k, v in sorted(by.items())) +
              f"; {mirror_pairs(result)} of them in mirror pairs (one echo, two hypotheses); {n_rows} listed rows "
              "(systems/active/targets.py mirror_targets: all false here)")
    print(f"all: {total_false} false confirmed tracks in {total_h:.2f} h = {total_false / max(total_h, 1e-9):.1f}/h")
    if LOBE_CPU["calls"]:
        print(f"lobe test: {LOBE_CPU['s']:.2f} s CPU in {LOBE_CPU['calls']} calls (runs not cached only)")
    if RIDGE_CPU["calls"]:
        print(f"ridge echoes: {RIDGE_CPU['s']:.2f} s CPU in {RIDGE_CPU['calls']} pings, {RIDGE_CPU['echoes']} echoes "
              "(runs not cached only)")


if __name__ == "__main__":
    main()
