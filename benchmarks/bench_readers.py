"""Benchmark: reading recordings in 1 s blocks (io/wav_blocks.py), in MB/s of file and x real time.

A 16-channel 4 kHz recording of five minutes of noise is written (io/recording_writer.py) as float32 WAV
(77 MB), RF64, W64, 24-bit WAV, and its first 8 channels as 24-bit FLAC (the FLAC format holds at most 8),
then read in 1 s blocks (channels, 4000) of float64 by the library
reader (libsndfile through soundfile, NaN/magnitude checks included). The reference is a plain RIFF reader:
``readinto`` one reused byte buffer, a numpy view, transpose + cast to C-ordered float64 and the same checks
(the algorithm of our former hand-written parser), on the same float32 WAV. Best of three passes each, after one
warm-up pass so that every reader reads from the page cache.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

CHANNELS, FS, DURATION_S = 16, 4000, 300


def _write(folder: Path) -> dict[str, Path]:
    from sonartrack.io.recording_writer import recording_writer

    rng = np.random.default_rng(0)
    noise = [0.05 * rng.standard_normal((CHANNELS, FS)) for _ in range(10)]
    paths = {}
    for label, name, fmt, ch in [("float32 WAV", "f.wav", "float32", CHANNELS),
                                 ("float32 RF64", "f.rf64", "float32", CHANNELS),
                                 ("float32 W64", "f.w64", "float32", CHANNELS),
                                 ("int24 WAV", "p24.wav", "int24", CHANNELS),
                                 ("int24 FLAC, 8 ch (FLAC's limit)", "p24.flac", "int24", 8)]:
        paths[label] = folder / name
        with recording_writer(folder / name, ch, FS, fmt) as w:
            for k in range(DURATION_S):
                w.write(noise[k % len(noise)][:ch])
    return paths


def _plain_riff(path: Path) -> None:
    """The reference: float32 RIFF read with readinto into one buffer (data offset from the library's walk)."""
    from sonartrack.io.wav_blocks import check_block

    size = path.stat().st_size
    n_data = DURATION_S * FS * CHANNELS * 4
    raw = bytearray(FS * CHANNELS * 4)
    view = np.frombuffer(raw, dtype="<f4").reshape(FS, CHANNELS)
    with open(path, "rb") as fh:
        fh.seek(size - n_data)  # the data chunk is last in a file libsndfile writes
        for k in range(DURATION_S):
            fh.readinto(raw)
            block = np.ascontiguousarray(view.T, dtype=np.float64)  # C-ordered, as the library reader gives
            check_block(block, path, float(k))


def _library(path: Path) -> None:
    from sonartrack.io.wav_blocks import iter_wav_blocks

    for _ in iter_wav_blocks(path, FS):
        pass


def _best(fn, path: Path) -> float:
    fn(path)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        fn(path)
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        paths = _write(Path(tmp))
        runs = [("plain RIFF readinto (reference)", _plain_riff, paths["float32 WAV"])]
        runs += [(f"library reader, {label}", _library, p) for label, p in paths.items()]
        for label, fn, path in runs:
            dt = _best(fn, path)
            mb = path.stat().st_size / 1e6
            print(f"{label}: {mb / dt:.0f} MB/s of file ({mb:.0f} MB), {DURATION_S / dt:.0f} x real time")


if __name__ == "__main__":
    main()
