"""Benchmark: the contacts a CW ping gives the tracker, against the truth: one per echo, errors as stated.

On the default active scene simulated with a CW pulse and on the second CW scene of bench_cw_held.py (32 x 0.3 m,
2.4 kHz), the chain's tracked detections (the MFTD's with the strong single-ping ones, run.py ``with_strong``; each
one mirror pair of contacts) are matched per ping to the true
echoes (truth.csv: travel time, cone, bistatic range rate). Printed per true target: the number of detections
near its echo per ping (near: within ``NEAR`` of it in travel time, cone and range rate; more than one = a source
that fragments into several contacts), Pd on its detectable pings (echo SNR >= 15 dB, in the window, clear of
the blast) and on all its pings in the window, and the errors of the nearest detection in travel time, cone and
range rate divided by the contact's STATED standard deviation (settings.contacts after cw_contact_errors, the
cone sd of ContactSettings.cone_sigmas_rad, the rate sd of cw_rate_sd_mps): their sd (should be ~1; robust sd
1.4826 MAD in brackets) and the share beyond 3. Over all detections: the share with |range rate| > 15 m/s
(no target of these scenes can have it), the false detections per ping (near no target, the weak one too) and
where they sit: on a beam's reverberation ridge (within 2 Doppler resolution cells of it), in the blast's
delays (the first 2 pulse lengths after the blanking), at the other early delays (< 10 s), elsewhere.

Usage: ``python benchmarks/bench_cw_contacts.py [--scene default|b|both] [--seeds 1 2] [--duration-s D]
[--cache DIR] [--cw NAME=VALUE ...]`` (``--cache``: simulate each scene once into DIR and reuse it).
Measures, not tests: nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_cw_held import scene_settings  # noqa: E402

#: a detection is near an echo within these: travel time (pulse lengths), cone (deg), range rate (m/s)
NEAR = (2.0, 10.0, 3.0)


def ridge_distance_mps(det, geometry, array, carrier_hz: float, c_mps: float, beam_cone_deg) -> np.ndarray:
    """|range rate - the nearest ridge rate of the detection's beam| (m/s), the ridge as detection/cw_ridge.py's
    (pattern above -10 dB, both mirrors) at the ping's heading and velocities."""
    from sonartrack.detection.cw_ridge import PATTERN_STEP_DEG, beam_pattern_power, ridge_range_rates

    cone = np.arange(0.0, 180.0 + PATTERN_STEP_DEG / 2, PATTERN_STEP_DEG)
    heard = beam_pattern_power(cone, beam_cone_deg, array.elements, array.spacing_m, carrier_hz, c_mps) >= 0.1
    out = np.full(len(det.ping), np.inf)
    for t in np.unique(det.time_s):
        rows = np.nonzero(det.time_s == t)[0]
        rates = ridge_range_rates(cone, float(geometry.heading_at(t)), geometry.velocity(t, "tx"),
                                  geometry.velocity(t, "rx"))
        for r in rows:
            ridge = rates[heard[int(det.beam[r])]].ravel()
            out[r] = np.abs(det.range_rate_mps[r] - ridge).min() if ridge.size else np.inf
    return out


def rows_of(det, keep):
    """The rows ``keep`` of a detections record."""
    return type(det)(**{f: np.asarray(getattr(det, f))[keep] for f in det.__dataclass_fields__})


def tracked_detections(res, tau_s: float):
    """The detections the tracker got: the MFTD's and the strong single-ping ones that join them (run.py
    ``with_strong``; ``res.detections`` holds the MFTD's alone), ping by ping."""
    from sonartrack.detection.cw_cells import cw_threshold
    from sonartrack.detection.ping_mftd import concat_detections
    from sonartrack.systems.active.run import with_strong

    s = res.settings
    if s.detector != "mftd" or s.mftd_strong_pfa is None:
        return res.detections
    strong = cw_threshold(s.mftd_strong_pfa, s.cw)
    step = s.front_end_settings().cw_hop * tau_s  # the CW delay cells' step
    m, one = res.mftd, res.single
    parts = []
    for t in res.ping_time_s:
        a, b = np.isclose(m.time_s, t), np.isclose(one.time_s, t)
        parts.append(with_strong(rows_of(m, a), rows_of(one, b), strong, step))
    return concat_detections(parts)


def stated_sds(res, scene) -> tuple[float, object, float]:
    """(travel-time sd s, cone sd function of cone rad -> rad, range-rate sd m/s) the chain states."""
    from sonartrack.systems.active.cw_tracking import cw_rate_sd_mps

    s = res.settings
    step = float(np.median(np.diff(res.bscan.cone_deg)))
    rate_sd = cw_rate_sd_mps(scene.waveform, scene.sample_rate_hz, s.front_end_settings().doppler_pad,
                             s.sound_speed_mps)
    return float(s.contacts.sigma_time_s), (lambda cone_rad: s.contacts.cone_sigmas_rad(cone_rad, step)), rate_sd


def near_matrix(det, rows, tau_s: float) -> np.ndarray:
    """(truth rows, detections) bool: the detection is near the echo (``NEAR``) on the same ping."""
    same = np.isclose(det.time_s[None, :], rows["time_s"].to_numpy()[:, None])
    dt = np.abs(det.travel_time_s[None, :] - rows["travel_time_s"].to_numpy()[:, None])
    dc = np.abs(det.cone_deg[None, :] - rows["cone_deg"].to_numpy()[:, None])
    dr = np.abs(det.range_rate_mps[None, :] - rows["range_rate_mps"].to_numpy()[:, None])
    return same & (dt <= NEAR[0] * tau_s) & (dc <= NEAR[1]) & (dr <= NEAR[2])


def target_lines(det, truth, sds, tau_s: float) -> list[str]:
    """Per true target: detections near its echo per ping, Pd, errors over the stated sds (module doc)."""
    sd_t, sd_cone, sd_rate = sds
    win = truth[truth["in_window"].astype(bool) & ~truth["in_blast"].astype(bool)]
    out = []
    for name in dict.fromkeys(win["target"]):
        rows = win[win["target"] == name]
        near = near_matrix(det, rows, tau_s)
        n = near.sum(axis=1)
        good = rows["snr_db"].to_numpy() >= 15.0
        z = []
        for i in np.nonzero(n)[0]:
            j = np.nonzero(near[i])[0]
            r = rows.iloc[i]
            zt = (det.travel_time_s[j] - r["travel_time_s"]) / sd_t
            zc = np.deg2rad(det.cone_deg[j] - r["cone_deg"]) / sd_cone(np.deg2rad(det.cone_deg[j]))
            zr = (det.range_rate_mps[j] - r["range_rate_mps"]) / sd_rate
            k = int(np.argmin(zt**2 + zc**2 + zr**2))
            z.append((zt[k], zc[k], zr[k]))
        z = np.array(z).reshape(-1, 3)
        hist = "/".join(str(int(v)) for v in (np.sum(n == 0), np.sum(n == 1), np.sum(n == 2), np.sum(n >= 3)))
        pd_det = 100 * np.mean(n[good] > 0) if good.any() else float("nan")
        errs = ", ".join(f"{lab} {np.std(z[:, c]):.2f} ({1.4826 * np.median(np.abs(z[:, c] - np.median(z[:, c]))):.2f})"
                         f" >3: {100 * np.mean(np.abs(z[:, c]) > 3):.0f} %" for c, lab in
                         enumerate(("t", "cone", "rate"))) if len(z) else "no detection"
        out.append(f"  {name:12s} pings {len(rows):3d} (snr>=15: {good.sum():3d}, median snr "
                   f"{np.median(rows['snr_db']):.1f} dB); near per ping 0/1/2/3+ {hist}; Pd {pd_det:.0f} % "
                   f"(snr>=15), {100 * np.mean(n > 0):.0f} % (all); error/stated sd: {errs}")
    return out


def false_lines(det, truth, res, scene, tau_s: float) -> list[str]:
    """False detections per ping and where they sit; the share of impossible range rates (module doc)."""
    from sonartrack.acoustics.active_beams import LineArray

    near = near_matrix(det, truth, tau_s).any(axis=0)
    false = ~near
    n_pings = len(res.ping_time_s)
    s = res.settings
    array = LineArray(int(s.elements), float(s.spacing_m))
    ridge = ridge_distance_mps(det, res.geometry, array, scene.waveform.carrier_hz, s.sound_speed_mps,
                               res.bscan.cone_deg)
    cell_mps = s.sound_speed_mps / (scene.waveform.carrier_hz * tau_s)
    blank = s.front_end_settings().blank_s
    on_ridge = ridge <= 2 * cell_mps
    blast = ~on_ridge & (det.travel_time_s < blank + 2 * tau_s)
    early = ~on_ridge & ~blast & (det.travel_time_s < 10.0)
    rest = ~on_ridge & ~blast & ~early
    where = ", ".join(f"{lab} {np.sum(false & m)}" for lab, m in
                      (("ridge", on_ridge), ("blast", blast), ("early", early), ("elsewhere", rest)))
    edges = [0, 5, 10, 15, 20, 25, 31]
    hist = " ".join(f"{a}-{b}s:{np.sum(false & (det.travel_time_s >= a) & (det.travel_time_s < b))}"
                    for a, b in zip(edges[:-1], edges[1:], strict=True))
    fast = np.abs(det.range_rate_mps) > 15.0
    return [f"  detections {len(det.ping)} ({len(det.ping) / n_pings:.1f}/ping), near a target {near.sum()}, "
            f"|range rate| > 15 m/s: {100 * np.mean(fast):.1f} %",
            f"  false {false.sum()} ({false.sum() / n_pings:.2f}/ping): {where}; by delay {hist}"]


class CellProbe:
    """While the chain runs, each CW ping's cells at the true echoes (detection/cw_cells.py ``cw_ping_cells``
    wrapped): per truth row, the largest statistic s within +-1 beam, +-2 delay cells and +-1 Doppler resolution
    cell of the echo's cell (s - 1 estimates the echo-to-background ratio; 0 in the ridge notch), whether the
    echo's cell is notched, and 10 log10 of the background estimate mu there over the ping's median mu (the
    reverberation above the ping's typical, mostly noise, level)."""

    def __init__(self, truth):
        self.truth, self.rows = truth, {}

    def __enter__(self):
        import sonartrack.detection.cw_cells as cw_cells

        self.module, self.original = cw_cells, cw_cells.cw_ping_cells

        def probed(*args, **kwargs):
            cells = self.original(*args, **kwargs)
            self.record(cells)
            return cells

        cw_cells.cw_ping_cells = probed
        return self

    def __exit__(self, *exc):
        self.module.cw_ping_cells = self.original

    def record(self, cells) -> None:
        t = self.truth
        at = np.nonzero(np.isclose(t["time_s"].to_numpy(), cells.time_s))[0]
        stat, mu = cells.statistic, cells.level
        pad = max(int(round(1.0 / (np.median(np.diff(cells.doppler_hz)) * self.tau_s))), 1)
        median_mu = float(np.median(mu))
        for i in at:
            r = t.iloc[i]
            b = int(np.argmin(np.abs(cells.cone_deg - r["cone_deg"])))
            d = int(np.argmin(np.abs(cells.delay_s - r["travel_time_s"])))
            j = int(np.argmin(np.abs(cells.range_rate_mps - r["range_rate_mps"])))
            box = stat[max(b - 1, 0):b + 2, max(d - 2, 0):d + 3, max(j - pad, 0):j + pad + 1]
            self.rows[i] = (float(box.max()) if box.size else np.nan, bool(stat[b, d, j] == 0.0),
                            10 * np.log10(max(float(mu[b, d, j]), 1e-30) / median_mu))


def probe_lines(probe: CellProbe, truth, threshold: float) -> list[str]:
    """Per target (pings in the window, clear of the blast, echo SNR >= 15 dB): the echo's statistic and
    background (:class:`CellProbe`)."""
    out = []
    ok = truth["in_window"].astype(bool) & ~truth["in_blast"].astype(bool) & (truth["snr_db"] >= 15.0)
    for name in dict.fromkeys(truth["target"]):
        idx = [i for i in np.nonzero((ok & (truth["target"] == name)).to_numpy())[0] if i in probe.rows]
        if not idx:
            continue
        v = np.array([probe.rows[i] for i in idx])
        s_db = 10 * np.log10(np.maximum(v[:, 0] - 1.0, 1e-3))
        out.append(f"  {name:12s} at its {len(idx)} pings of snr>=15: s - 1 median {np.median(s_db):.1f} dB "
                   f"[p25 {np.percentile(s_db, 25):.1f}, p75 {np.percentile(s_db, 75):.1f}], s >= the single-ping "
                   f"threshold {100 * np.mean(v[:, 0] >= threshold):.0f} %, notched {100 * np.mean(v[:, 1] > 0):.0f}"
                   f" %, background over the ping's median {np.median(v[:, 2]):.1f} dB")
    return out


def measure(which: str, seed: int, duration_s: float, cache: str | None, cw: dict, dump: str | None = None) -> None:
    import pandas as pd

    from sonartrack.systems.active.files import run_active_files
    from sonartrack.systems.active.settings import ActiveSettings
    from sonartrack.systems.simulate.active_files import write_active_scene

    scene = scene_settings(which, seed, duration_s)
    spacing = scene.sonar.spacing_m or scene.sound_speed_mps / (2.0 * scene.waveform.carrier_hz)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(cache) / f"{which}{seed}_{duration_s:.0f}" if cache else Path(tmp)
        if not (folder / "truth.csv").exists():
            folder.mkdir(parents=True, exist_ok=True)
            write_active_scene(scene, folder)
        settings = ActiveSettings(spacing_m=spacing, elements=scene.sonar.elements)
        settings = settings.model_copy(update={"cw": settings.cw.model_copy(update=cw)})
        truth = pd.read_csv(folder / "truth.csv")
        c0 = time.process_time()
        with CellProbe(truth) as probe:
            probe.tau_s = scene.waveform.duration_s
            res = run_active_files(folder, folder / "nav.csv", settings)
        cpu = time.process_time() - c0
    if dump:
        import pickle

        Path(dump).write_bytes(pickle.dumps((res, truth, scene)))
    tau = scene.waveform.duration_s
    sds = stated_sds(res, scene)
    print(f"CW scene {which}, seed {seed}, {duration_s:.0f} s (chain CPU {cpu:.0f} s): stated sds t {sds[0]:.3f} s, "
          f"rate {sds[2]:.2f} m/s, cone at broadside {np.rad2deg(sds[1](np.array([np.pi / 2]))[0]):.2f} deg")
    print(f" the echoes' cells (single-ping threshold s = {res.thresholds['single']:.1f}):")
    for line in probe_lines(probe, truth, res.thresholds["single"]):
        print(line)
    tracked = tracked_detections(res, tau)
    for label, det in ((f"tracked ({res.settings.detector} + strong)", tracked), ("single-ping", res.single)):
        print(f" {label}:")
        for line in target_lines(det, truth, sds, tau) + false_lines(det, truth, res, scene, tau):
            print(line)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    p.add_argument("--duration-s", type=float, default=3600.0)
    p.add_argument("--scene", default="both", choices=["default", "b", "both"])
    p.add_argument("--cache", default=None, help="folder to keep the simulated scenes in (reused)")
    p.add_argument("--dump", default=None, help="pickle (result, truth, scene) to this path + scene and seed")
    p.add_argument("--cw", action="append", default=[], metavar="NAME=VALUE",
                   help="a CwNormaliserSettings field (detection/cw_cells.py), repeatable; the value read as JSON")
    a = p.parse_args()
    cw = {k: json.loads(v) for k, v in (item.split("=", 1) for item in a.cw)}
    for which in (["default", "b"] if a.scene == "both" else [a.scene]):
        for seed in a.seeds if which == "default" else a.seeds[:1]:
            measure(which, seed, a.duration_s, a.cache, cw, a.dump and f"{a.dump}.{which}{seed}")


if __name__ == "__main__":
    main()
