"""Front-end detections of generator worlds kept on disk, so that tracker settings are measured on the same pings
without re-running the front end (the front end is ~95 % of the chain's time; the tracker is what changes).

``detect_world`` runs the chain's front end and both detectors ping by ping (systems/active/run.py ``_Chain``) and
keeps each ping's single-ping and MFTD detections; ``track_cached`` then runs the chain's tracker stage
(``ContactTracker``, with the strong single-ping detections joined as the chain does when ``mftd_strong_pfa`` is
set) on them with any settings. Used by bench_active_clutter.py and bench_mftd_gain.py.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np


def detect_world(w, settings, records, ping) -> dict:
    """Every ping's detections of both detectors on generator world ``w`` (``records``/``ping``: its helpers)."""
    from sonartrack.systems.active.run import geometry_of

    table, nav = records(w)
    truth: list[dict] = []

    def pings():
        for k in range(w.pings):
            x, rows = ping(w, k)
            truth.extend(rows)
            yield k + 1, k * w.interval_s, x

    out = detect_pings(pings(), table, geometry_of(nav), settings)
    out["truth"] = truth
    return out


def detect_pings(pings, table, geometry, settings) -> dict:
    """Every ping's detections of both detectors (``pings``: (number, time s, samples) as run_active's)."""
    from sonartrack.systems.active.run import _Chain

    chain = _Chain.of_table(table, geometry, settings)
    numbers, times = [], []
    for i, (number, time_s, x) in enumerate(pings):
        chain.ping(int(number), float(time_s), np.asarray(x), table.waveform(i), float(table.fs_hz[i]))
        numbers.append(int(number))
        times.append(float(time_s))
    t = np.asarray(times)
    return {"single": chain.single, "mftd": chain.multi, "time_s": t, "ping": np.asarray(numbers),
            "geometry": geometry, "delay_step_s": float(np.median(np.diff(chain.axes.travel_time_s))),
            "beam_step_deg": chain.beam_step, "rate_sd_mps": chain.rate_sd, "hours": len(t) * float(np.median(
                np.diff(t))) / 3600.0, "front_end": chain.front_end, "cw": chain.cw, "cw_settings": chain.settings.cw,
            "contacts": chain.settings.contacts, "clutter_area_m2": chain.tracker.clutter_area}


def cached(path: Path, make) -> dict:
    """The detections at ``path`` (pickle, this benchmark's own cache), made by ``make()`` when absent."""
    path = Path(path)
    if path.exists():
        with path.open("rb") as f:
            return pickle.load(f)
    out = make()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as f:
        pickle.dump(out, f)
    tmp.replace(path)
    return out


def track_cached(c: dict, settings, detector: str = "mftd"):
    """The chain's tracker stage over cached detections with ``settings``; returns ActiveTracks."""
    from sonartrack.detection.cells import detection_threshold
    from sonartrack.detection.cw_cells import cw_threshold
    from sonartrack.systems.active.contacts import form_contacts
    from sonartrack.systems.active.run import ContactTracker, clutter_map_of, with_strong

    s = settings
    t, numbers = c["time_s"], c.get("ping", np.arange(1, len(c["time_s"]) + 1))
    strong = None
    if s.mftd_strong_pfa is not None:
        strong = cw_threshold(s.mftd_strong_pfa, c["cw_settings"]) if c.get("cw") else detection_threshold(
            c["front_end"].model_copy(update={"pfa": s.mftd_strong_pfa}))
    trk = ContactTracker(s.tracker_settings(), c["geometry"], s.range_rate_gate_sigma, c["rate_sd_mps"],
                         s.side_turn_deg, s.merge_probability, s.max_range_rate_mps, turns=s.turn_modes(),
                         clutter_area_m2=c.get("clutter_area_m2"), clutter_map=clutter_map_of(s),
                         scan_interval_s=float(np.median(np.diff(t))))
    for k in range(len(t)):
        if detector == "single":
            det = c["single"][k]
        else:
            det = c["mftd"][k]
            if strong is not None:
                det = with_strong(det, c["single"][k], strong, c["delay_step_s"])
        con = form_contacts(det, [t[k]], c["geometry"], s.sound_speed_mps, c.get("contacts", s.contacts),
                            c["beam_step_deg"], [int(numbers[k])])
        trk.step(float(t[k]), con)
    return trk.result()


def run_recorded(config, scene, rec: dict | None = None, step_ridge=None) -> dict:
    """The study's chain (studies/active_chain.py ``run_scene``) on ``scene`` with its ContactTracker recorded:
    ``rec`` (a new dict by default) gets ``args``/``kwargs`` (deep copies at construction: the clutter and ridge maps
    are stateful and would be pickled full at the run's end), ``steps`` [(t s, contacts, ridge echoes as they came)],
    ``result`` and ``seconds``. ``step_ridge`` maps the ridge echoes a step passes on to the tracker (None: as they
    came). Used by bench_cw_confirm.py and bench_cw_ridge_learn.py."""
    import copy
    import time

    import sonartrack.systems.active.run as run_mod
    from sonartrack.studies.active_chain import run_scene

    rec = {} if rec is None else rec
    rec["steps"], real = [], run_mod.ContactTracker

    class Recording(real):
        def __init__(self, *args, **kwargs):
            rec["args"], rec["kwargs"] = copy.deepcopy(args), copy.deepcopy(kwargs)
            super().__init__(*args, **kwargs)

        def step(self, t_s, contacts, ridge=None):
            rec["steps"].append((float(t_s), contacts, ridge))
            if ridge is not None and step_ridge is not None:
                ridge = step_ridge(ridge)
            return super().step(t_s, contacts, ridge)

    run_mod.ContactTracker = Recording
    t0 = time.perf_counter()
    try:
        rec["result"] = run_scene(config.model_copy(update={"scene": scene}), scene)[0]
    finally:
        run_mod.ContactTracker = real
    rec["seconds"] = time.perf_counter() - t0
    return rec
