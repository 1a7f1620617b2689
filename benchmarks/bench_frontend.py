"""Benchmark: the passive chain's front end on a 16-channel 4 kHz recording (target: <= 15 s per hour).

Two minutes of the default passive scene are simulated to a temporary float32 WAV (streamed, block by
block), then read in 1 s blocks (io/wav_blocks.py), beamformed (CBF, the default), normalised across bearing
and peak-picked (acoustics/beamforming.py); the best of three passes is scaled to one hour. The peak resident
set size of the process (resource.getrusage) covers the simulation too, so it bounds the front end's.
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

DURATION_S = 120.0


def _write_recording(path: Path):
    from sonartrack.io.wav_writer import wav_block_writer
    from sonartrack.sim.array_signals import array_blocks
    from sonartrack.sim.scene import PassiveSceneSettings

    scene = PassiveSceneSettings(duration_s=DURATION_S)
    with wav_block_writer(path, scene.array.elements, scene.sample_rate_hz, "float32") as w:
        for block in array_blocks(scene, np.random.default_rng(0)):
            w.write(block)
    return scene


def main() -> None:
    from sonartrack.acoustics.beamforming import BeamformerSettings, bearing_time_record
    from sonartrack.acoustics.line_array import LineArray
    from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rec.wav"
        scene = _write_recording(path)
        settings = BeamformerSettings()
        info = read_wav_info(path)
        array = LineArray(info.channels, scene.spacing_m, scene.sound_speed_mps)
        nw = int(round(settings.window_s * info.sample_rate_hz))
        best, record = np.inf, None
        for _ in range(3):
            t0 = time.perf_counter()
            record = bearing_time_record(iter_wav_blocks(info, nw), info.sample_rate_hz, array, settings)
            best = min(best, time.perf_counter() - t0)
    per_hour = best * 3600.0 / info.duration_s
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    n_win = len(record.time_s)
    print(f"passive front end (read WAV + {settings.method} {settings.beams} beams + normalise + peaks), "
          f"{info.channels} ch at {info.sample_rate_hz:g} Hz: {per_hour:.1f} s per hour of recording "
          f"({3600.0 / per_hour:.0f} x real time; target <= 15 s), peak RSS {rss_mb:.0f} MB; "
          f"{n_win} windows, {len(record.peaks.time_s) / max(n_win, 1):.1f} peaks a window")


if __name__ == "__main__":
    main()
