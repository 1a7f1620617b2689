"""Why a tentative track on an LFM target takes many pings to confirm: the IPDA ledger of each ping from the target's
entry to its first held ping, and the acquisition / held / false tracks of tracker variants on the same contacts.

Re-tracks the cached chain results of study ``active-chain`` trials (benchmarks/bench_active_held.py's pickles,
``--cache``; the tracker alone, ~1-2 min a trial; the run reproduces the stored tracks row for row, checked and
printed) with the tracker instrumented: per scan, every live track's existence before, predicted and after, its
ln Lambda (Musicki, Evans, Stankovic 1994, eq. 29), its predicted position covariance (combined state, CV) and the
rate rule's threshold (tracking/deleters.py RateConfirmation). For each target (``--ledger``), each ping from entry
(first detectable ping) to first held is given one state:

* ``no contact, no track`` / ``miss on tentative``: no contact within 3 sqrt(trace R) of the target or its mirror
  (the detector's miss, or a contact withheld by the gates), with no live track near (1500 m) / with one;
* ``hit on tentative``: the tentative track nearest in existence took the target's contact (its ln Lambda printed);
* ``contact, new track``: the contact started a track (none alive near: the last one was deleted);
* ``contact, track did not gate it``: a young track near but its gate missed the contact (a wrong velocity);
* ``confirmed track, not held``: a confirmed track near (1500 m), not the study's holder (its mirror, or off);
* ``[ABOVE THR, not confirmed]``: the existence passed the threshold but a deleter part (StillHold, MinHits, ...)
  took the confirmation back.

Per target the hits' median ln Lambda, sqrt det S against sqrt det R (the prediction's cost per hit: ln of their
ratio) and the existence prediction's total loss are summed. Variants (``--variants``): ``base`` (the settings),
``lr`` (tracker.confirm_statistic = likelihood_ratio: the rate rule held against O_0 prod Lambda, the quantity
Ville's inequality bounds, rather than the existence, whose odds p11 caps at 49, below the rule's threshold),
``pd05`` (the tracker's pd 0.5), ``v375`` (a one-point track's velocity prior from the chain's speed bound,
tracking/initiators.py ``velocity_std_from_speed_bound(max_range_rate_mps / 2)``: 3.75 m/s per axis against 5),
combinations joined (``lrv375``). ``lr`` needs the wiring diff of the h13-acq report
in systems/active/contact_tracker.py ``_rate_confirmation`` (``statistic=settings.confirm_statistic``); until then
:func:`wire` applies it here.

Usage: ``PYTHONPATH=src python benchmarks/bench_acquisition.py --trials 2 14 18 [--ledger] [--variants base,lr]``.

Measured (2026-12-08, h13-acq at main f7e0a61; bench_active_held.py's caches of trials 2, 14, 18 (LFM; 11 targets
entering, 10 of them at 15 dB), ~2-4 min a variant and trial at load 6-7 on 2 cores; every base run reproduced the
stored tracks):
* ledger, 336 target pings from entry to first held: no contact on the target 164 (49 %: a tentative track alive
  123, none 41), the target's contact taken by a tentative track still short of the threshold 116 (35 %), the
  track lost and restarted 22 (7 %: the contact started a new track 14, a young track's gate missed it 8), a
  confirmed track near but not the holder (its mirror twin, or off) 31 (9 %); held back above the threshold
  (StillHold, MinHits: off on the LFM chain) 0 (StillHold took back 10 and 16 confirmations on trials 14 and 18,
  all away from the targets). A hit on a tentative track: ln Lambda median 1.09 (quartiles 0.08, 1.61), a miss
  -1.18 (pd 0.7), against 6.7-7.7 nats needed (threshold 0.975-0.994 from 6.5-18.3 tracks started a ping at 30 s,
  1 false track/h, P_0 0.05); per hit, sqrt det S / sqrt det R median 9.9 (ln 2.29 nats: the one-point track's
  velocity prior and the IMM's maneuver modes against contacts known to ~15 m in range), the tracker's 1e-6 /m^2
  against the contacts' ~1e-8 ~4.5 nats; the existence prediction lost 8.5 nats in all, near p11's cap.
* acquisition (pings from entry; trials 2 / 14 / 18) and held counted pings: base inf 30 30 / 33 1 7 9 / 38 61 43 46,
  held 65/172, 251/282, 125/306; ``lr`` inf 30 29 / 33 1 6 8 / 36 60 43 46, held 67, 253, 128; ``v375`` 36 30 29 /
  11 1 4 8 / 1 54 43 46, held 60, 268, 147 (441 -> 475 of 760); ``lrv375`` on 14 as ``v375``; ``pd05`` on 14:
  inf 1 31 11, held 202 (worse: not pursued). False confirmed tracks on the study's scoring: 0 in every run.
* 1 h reverberation-only twins (bench_active_family.py's scenes, trials 14 K, 18 Rayleigh, 10 spiky K; all LFM):
  base 0/0/0, ``lr`` 0/0/0, ``v375`` 0/2/0 (twin 18: one mirror pair confirmed at 3480 s, 4 pings, at the bistatic
  range of a 19 dB still point 90 deg away in cone: a lobe image).
* bench_active_turns.py (18 LFM turn scenes, cached contacts): acquired 8 -> 12 (``lr``) -> 14 (``v375``) of 18,
  seed 1 at 18 pings in 3 scenes -> 17 in 7 (``lr``) -> 17 in 9 (``v375``); none within 5; false tracks 0 in all;
  turn pings lost 155 -> 131 -> 117 of 191. bench_active_rows.py (default scene LFM seeds 1, 2): false rows 0/0 in
  all; ``lr`` seed 2's crossing-b confirmed at ping 9 not 12, the maneuvering target at 7 not 8 (one more ghost
  twin confirmed for 7 pings); ``v375`` held % 83/87 -> 85/87.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

LOG: list = []  # per scan: the instrumented tracker's record (dict)
GATE = 9.21 * 1.5  # a contact "in" a track's gate for the ledger (combined state, no Q: a little wider than 0.99)


def _logit(p):
    p = np.clip(np.asarray(p, float), 1e-12, 1 - 1e-12)
    return np.log(p / (1 - p))


def wire() -> None:
    """The chain's rate confirmation given the settings' ``confirm_statistic`` (the report's contact_tracker diff)."""
    import sonartrack.systems.active.contact_tracker as ct

    if getattr(ct._rate_confirmation, "_wired", False):
        return
    orig = ct._rate_confirmation

    def rate_confirmation(settings, scan_interval_s):
        d = orig(settings, scan_interval_s)
        getattr(d, "inner", d).statistic = getattr(settings, "confirm_statistic", "existence")
        return d
    rate_confirmation._wired = True
    ct._rate_confirmation = rate_confirmation


def instrument() -> None:
    """Record each scan's tracks before and after the update (module doc) into :data:`LOG`."""
    import sonartrack.tracking.multi_target as mt
    from sonartrack.tracking.tracks import TrackSnapshot

    if getattr(mt.MultiTargetTracker._update, "_ledger", False):
        return
    update, step = mt.MultiTargetTracker._update, mt.MultiTargetTracker.step

    def _update(self, T, scan, dt_s, turn_deg=0.0):
        snap = TrackSnapshot.of(0.0, T)
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt_s
        rec = {"t": scan.time_s, "ids": T.track_id.copy(), "e0": T.existence.copy(), "conf0": T.confirmed.copy(),
               "z": scan.z.copy(), "R": scan.R.copy(), "xp": snap.x @ F.T, "Pp": F @ snap.P @ F.T}
        ex = self.existence

        class Spy:
            def predict(self_, e):
                rec["epred"] = ex.predict(e)
                return rec["epred"]

            def update(self_, e_pred, log_total):
                rec["loglam"] = np.asarray(log_total).copy()
                return ex.update(e_pred, log_total)
        self.existence = Spy()
        try:
            out = update(self, T, scan, dt_s, turn_deg)
        finally:
            self.existence = ex
        rec.update(e1=out[0].existence.copy(), hit=out[1].copy())
        LOG.append(rec)
        return out

    def _step(self, time_s, z, R=None, amplitude=None, array_turn_deg=0.0):
        snap = step(self, time_s, z, R, amplitude, array_turn_deg)
        d = self.deleter
        while d is not None and not hasattr(d, "confirm_threshold"):
            d = getattr(d, "inner", None)
        if LOG and LOG[-1]["t"] == time_s:
            LOG[-1].update(after_ids=snap.track_id.copy(), after_conf=snap.confirmed.copy(),
                           thr=None if d is None else d.confirm_threshold)
        return snap
    _update._ledger = True
    mt.MultiTargetTracker._update, mt.MultiTargetTracker.step = _update, _step


def retrack(config, result):
    """The chain's ContactTracker (systems/active/run.py's arguments, an LFM's) over the result's contacts."""
    from sonartrack.systems.active.aliases import endfire_alias_of
    from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of

    s, t = result.settings, np.asarray(result.ping_time_s, float)
    trk = ContactTracker(s.tracker_settings(), result.geometry, s.range_rate_gate_sigma, 1.0, s.side_turn_deg,
                         s.merge_probability, s.max_range_rate_mps, turns=s.turn_modes(), clutter_area_m2=None,
                         clutter_map=clutter_map_of(s), scan_interval_s=float(np.median(np.diff(t))),
                         rejoin_s=s.rejoin_s, claims=s.contact_claims, keep_apart=s.merge_keep_apart,
                         reunite_scans=s.merge_reunite_scans,
                         endfire_alias=endfire_alias_of(s, config.scene.waveform.waveform()))
    con = result.contacts
    for tk in t:
        trk.step(float(tk), con.rows(np.nonzero(np.isclose(con.time_s, tk))[0]))
    return trk.result()


def variant(settings, name: str):
    """The chain's settings with the variant's tracker changes (module doc)."""
    upd = {}
    if "lr" in name:
        upd["confirm_statistic"] = "likelihood_ratio"
    if "pd05" in name:
        upd["pd"] = 0.5
    if "v375" in name:  # the velocity prior from the chain's speed bound (tracking/initiators.py)
        from sonartrack.tracking.initiators import velocity_std_from_speed_bound

        upd["init_velocity_std_mps"] = velocity_std_from_speed_bound(0.5 * settings.max_range_rate_mps)
    return settings.model_copy(update={"tracker": settings.tracker.model_copy(update=upd)})


def _ping_state(rec, tgt, mir):
    """(state, track index or None, contact index or None) of one target ping (module doc)."""
    z, R = rec["z"], rec["R"]
    c = None
    if len(z):
        d = np.minimum(np.hypot(*(z - tgt).T), np.hypot(*(z - mir).T))
        j = int(np.argmin(d))
        c = j if d[j] < 3 * np.sqrt(np.trace(R[j])) else None
    k = None
    if c is not None and len(rec["ids"]):
        nu = z[c] - rec["xp"][:, :2]
        d2 = np.einsum("ti,tij,tj->t", nu, np.linalg.inv(rec["Pp"][:, :2, :2] + R[c]), nu)
        g = np.nonzero(d2 <= GATE)[0]
        k = g[np.argmax(rec["e0"][g])] if len(g) else None
    if k is None and len(rec["ids"]):
        d = np.minimum(np.hypot(*(rec["xp"][:, :2] - tgt).T), np.hypot(*(rec["xp"][:, :2] - mir).T))
        near = np.nonzero(d < 1500.0)[0]
        k = near[np.argmax(rec["e0"][near])] if len(near) else None
    if k is None:
        return ("contact, new track" if c is not None else "no contact, no track"), None, c
    if rec["conf0"][k]:
        state = "confirmed track, not held"
    elif c is not None:
        state = "hit on tentative" if rec["hit"][k] else "contact, track did not gate it"
    else:
        state = "miss on tentative"
    j = np.nonzero(rec["after_ids"] == rec["ids"][k])[0]
    if not rec["conf0"][k] and rec["e1"][k] > rec["thr"] and len(j) and not rec["after_conf"][j[0]]:
        state += " [ABOVE THR, not confirmed]"
    return state, k, c


def ledger(config, truth, held, geometry, verbose: bool) -> tuple[Counter, list]:
    """Each target's pings from entry to first held, one state each (module doc); (states, hits' numbers)."""
    from sonartrack.studies.active_chain import _mirror, detectable_grid, truth_grid

    det = detectable_grid(config, truth) > 0.5
    tt = truth_grid(config, truth, "time_s")
    xy = np.stack([truth_grid(config, truth, "x_m"), truth_grid(config, truth, "y_m")], -1)
    scans = {round(r["t"], 6): r for r in LOG}
    states, hits = Counter(), []
    for i in np.nonzero(det.any(axis=1))[0]:
        p0 = int(np.argmax(det[i]))
        after = held[i] & (np.arange(det.shape[1]) >= p0)
        p1 = int(np.argmax(after)) if after.any() else det.shape[1] - 1
        if verbose:
            print(f"  target {i}: entry ping {p0 + 1}, first held {p1 + 1 if after.any() else 'never'}")
        for p in range(p0, p1 + 1):
            rec = scans.get(round(float(tt[i, p]), 6)) if np.isfinite(tt[i, p]) else None
            if rec is None:
                continue
            mir = _mirror(geometry, np.array([tt[i, p]]), xy[i, p][None])[0]
            state, k, c = _ping_state(rec, xy[i, p], mir)
            states[state] += 1
            if k is not None and state.startswith("hit on tentative"):
                S = rec["Pp"][k, :2, :2] + rec["R"][c]
                hits.append((rec["loglam"][k], np.sqrt(np.linalg.det(S)), np.sqrt(np.linalg.det(rec["R"][c])),
                             _logit(rec["epred"][k]) - _logit(rec["e0"][k])))
            if verbose and k is not None:
                print(f"    p{p + 1:3d} trk {rec['ids'][k]:6d} logit e {_logit(rec['e0'][k]):+.2f} -> pred "
                      f"{_logit(rec['epred'][k]):+.2f} -> {_logit(rec['e1'][k]):+.2f} (lnL {rec['loglam'][k]:+.2f}) "
                      f"thr {_logit(rec['thr']):+.2f}  {state}")
            elif verbose:
                print(f"    p{p + 1:3d} {state}")
    return states, hits


def measure(config, result, truth, name: str, show_ledger: bool, verbose: bool) -> None:
    """One variant on one trial: latency per target, held counted pings, false confirmed tracks; the ledger."""
    from sonartrack.studies.active_chain import detectable_grid, score_tracks, truth_grid
    from sonartrack.studies.active_chain_scoring import acquisition_pings, entering_level_db

    LOG.clear()
    tracks = retrack(config, replace(result, settings=variant(result.settings, name)))
    same = name == "base" and len(tracks.tracks) == len(result.tracks.tracks) and np.allclose(
        tracks.tracks.x, result.tracks.tracks.x, equal_nan=True)
    score = score_tracks(config, tracks, result, truth)
    held = score["held_pings"] > 0.5
    det = detectable_grid(config, truth) > 0.5
    counted = det & (np.cumsum(det, axis=1) > config.acquire_pings)
    lat = acquisition_pings(det, held)
    level = entering_level_db(truth_grid(config, truth, "ebr_db"), det, config.acquire_pings)
    false = {k: v for k, v in score.items() if "false" in k}
    print(f"  {name:7s} latency (pings; * at 15 dB) "
          + " ".join(f"{v:g}{'*' if lv >= 15 else ''}" for v, lv in zip(lat, level, strict=True) if np.isfinite(v)
                     or v == np.inf)
          + f"  held {int((held & counted).sum())}/{int(counted.sum())}  false {false}"
          + ("  (reproduces the stored run)" if same else ""), flush=True)
    if show_ledger:
        states, hits = ledger(config, truth, held, result.geometry, verbose)
        h = np.array(hits).reshape(-1, 4)
        print("    ledger: " + ", ".join(f"{k} {v}" for k, v in states.most_common()))
        if len(h):
            print(f"    hits on tentative tracks: {len(h)}, ln Lambda median {np.median(h[:, 0]):.2f}; sqrt det S "
                  f"median {np.median(h[:, 1]):.0f} m^2 against sqrt det R {np.median(h[:, 2]):.0f} (ln ratio "
                  f"median {np.median(np.log(h[:, 1] / h[:, 2])):.2f}); existence prediction's loss "
                  f"{h[:, 3].sum():.1f} nats")


def main() -> None:
    import bench_active_held as bh
    from sonartrack.studies.active_chain import Config

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[2, 14, 18])
    ap.add_argument("--seed", type=int, default=2017)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_held"))
    ap.add_argument("--variants", default="base,lr")
    ap.add_argument("--ledger", action="store_true", help="the per-ping ledger's totals (base variant)")
    ap.add_argument("-v", "--verbose", action="store_true", help="every ledger ping")
    a = ap.parse_args()
    wire()
    instrument()
    for i in a.trials:
        config, _ = bh.trial_config(Config(), a.seed, i)
        result, truth, *_ = bh.run_cached(config, a.cache, i)
        print(f"trial {i} ({config.scene.waveform.kind})")
        for name in a.variants.split(","):
            measure(config, result, truth, name, a.ledger and name == "base", a.verbose)


if __name__ == "__main__":
    main()
