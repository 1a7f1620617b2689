"""Benchmark: the active scene simulator and the active front end on the default scene (targets: an hour of
pings = 120 pings x 16 channels simulated in well under a minute; the front end <= ~0.15 s a ping, so that the
whole active chain can run an hour in <= 36 s).

Eight pings of the default scene (LFM 1 s / 100 Hz at 1.5 kHz, 16 elements, 200 Hz complex baseband, 30 s
windows, seabed + volume reverberation, four targets) are simulated (sim/active_signals.py); each is put through
the front end (detection/cells.py: FFT + true-time-delay beams on 61 cone angles, pulse compression, OS-CFAR
along delay) and the single-ping detector. The stages are timed separately (best of three passes per ping) and
scaled to 120 pings (wall clock; the simulator's CPU time beside it shows what a loaded machine hides); the CW
waveform's front end (Doppler filter bank) is timed too. Peak resident memory of the process
(resource.getrusage) is printed.
"""

from __future__ import annotations

import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

N_PINGS = 8
PINGS_PER_HOUR = 120


def simulate(kind: str = "lfm"):
    from sonartrack.core.random import trial_rng
    from sonartrack.sim.active_scene import ActiveSceneSettings, ping_geometry, transmission_loss_model
    from sonartrack.sim.active_signals import ping_samples

    s = ActiveSceneSettings(waveform={"kind": kind})
    tl, plat = transmission_loss_model(s), ping_geometry(s)
    ping_samples(s, plat, 0, tl, trial_rng(s.seed, 0))  # warm-up (imports)
    pings, times, cpu = [], [], []
    for k in range(40, 40 + N_PINGS):
        t0, c0 = time.perf_counter(), time.process_time()
        pings.append(ping_samples(s, plat, k, tl, trial_rng(s.seed, k)))
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return s, pings, float(np.median(times)), float(np.median(cpu))


def stage_times(s, pings) -> dict[str, float]:
    """Best-of-3 seconds per ping of each front-end stage, medians over the pings."""
    from _timing import best_of
    from sonartrack.acoustics.active_beams import LineArray
    from sonartrack.detection.cells import (
        FrontEndSettings,
        cfar_stride,
        detect_ping,
        detection_threshold,
        matched_cells,
        ping_front_end,
    )
    from sonartrack.detection.cfar import cfar_normalise

    fe, w = FrontEndSettings(), s.waveform.waveform()
    array = LineArray(s.sonar.elements, s.spacing_m)
    thr = detection_threshold(fe)
    rows: dict[str, list] = {"beams + matched filter": [], "CFAR": [], "front end (all)": [], "detect": [],
                             "detections": []}
    for x in pings:
        power, delay, _ = matched_cells(x, s.sample_rate_hz, w, array, fe)
        stride = cfar_stride(w, s.sample_rate_hz, delay)
        cells = ping_front_end(x, s.sample_rate_hz, w, array, fe)
        rows["beams + matched filter"].append(best_of(lambda x=x: matched_cells(x, s.sample_rate_hz, w, array, fe),
                                                      1, 3))
        rows["CFAR"].append(best_of(lambda p=power, k=stride: cfar_normalise(np.moveaxis(p, 1, -1), fe.cfar, k),
                                    1, 3))
        rows["front end (all)"].append(best_of(lambda x=x: ping_front_end(x, s.sample_rate_hz, w, array, fe), 1, 3))
        rows["detect"].append(best_of(lambda c=cells: detect_ping(c, thr), 1, 3))
        rows["detections"].append(len(detect_ping(cells, thr)))
    return {k: float(np.median(v)) for k, v in rows.items()}


def main() -> None:
    for kind in ("lfm", "cw"):
        t0 = time.perf_counter()
        s, pings, sim_ping, sim_cpu = simulate(kind)
        print(f"active {kind}: simulate {sim_ping:.3f} s/ping (CPU {sim_cpu:.3f} s) -> "
              f"{sim_ping * PINGS_PER_HOUR:.1f} s per hour of {PINGS_PER_HOUR} pings x {s.sonar.elements} ch x "
              f"{s.samples_per_ping} samples (target: well under 60 s)")
        st = stage_times(s, pings)
        fe = st["front end (all)"] + st["detect"]
        shares = ", ".join(f"{k} {v / fe:.0%}" for k, v in st.items() if k not in ("front end (all)", "detections"))
        print(f"active {kind}: front end + detect {fe:.3f} s/ping -> {fe * PINGS_PER_HOUR:.1f} s per hour "
              f"(target <= 0.15 s/ping); {shares}; {st['detections']:.0f} detections/ping at Pfa 1e-5 "
              f"[{time.perf_counter() - t0:.0f} s]")
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"active front end: peak resident memory {rss_mb:.0f} MB")


if __name__ == "__main__":
    main()
