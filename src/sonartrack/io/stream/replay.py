"""A finished recording played back as a live stream (``sonartrack live --wav FILE --speed N``): the same blocks a
recorder's stream would give, paced at N times real time.

The recording is read through io/wav_blocks.py (any format ``passive`` reads: WAV, RF64, W64, FLAC; its checks
included) in blocks of ``block_s`` seconds, scaled as ``passive`` scales (full scale = 1.0). Block k (first sample
index i_k) is given out no earlier than i_k / (f_s N) seconds after the first, so the chain sees the samples as
a recorder's live feed would bring them, N times faster; ``speed`` = inf gives them as fast as they are taken.
The UTC start is the time in the file's name (io/recording_sequence.py's patterns) or its Broadcast WAV start,
else 1970-01-01 with an event ("no_start_time"), as the folder source does.
"""

from __future__ import annotations

import math
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from sonartrack.core.errors import require
from sonartrack.io.recording_sequence import DEFAULT_NAME_PATTERNS, name_start_utc
from sonartrack.io.stream._threaded import ThreadedSource
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader

_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)


class ReplaySampleSource(ThreadedSource):
    """Sample blocks of a finished recording at ``speed`` times real time; an iterator with ``header``, ``close()``.

    Parameters
    ----------
    path : str or Path
        The recording.
    speed : float
        Times real time (> 0; inf: no pacing).
    block_s : float
        Seconds per block (the last block of the file shorter).
    """

    _name = "replay-source"

    def __init__(self, path, *, speed: float = 1.0, block_s: float = 0.1):
        from sonartrack.io.wav_blocks import read_wav_info

        super().__init__()
        require(speed > 0 and not math.isnan(speed), f"--speed must be > 0 (got {speed:g})")
        require(block_s > 0, "block_s must be > 0")
        self.path = Path(path)
        self._info = read_wav_info(self.path)
        self._speed, self._block_s = float(speed), float(block_s)
        start = name_start_utc(self.path.name, DEFAULT_NAME_PATTERNS) or self._info.start_utc
        fmt = self._info.sample_format
        wire = fmt if fmt in ("int16", "int24", "float32") else "float32"
        self.header = StreamHeader(self._info.channels, float(self._info.sample_rate_hz), wire, start or _EPOCH, None,
                                   str(self.path))
        self._no_start = start is None

    def _run(self) -> None:
        from sonartrack.io.wav_blocks import iter_wav_blocks

        if self._no_start:
            self._put(StreamEvent("no_start_time", f"{self.path.name}: no start time in its name or header: times "
                                                   "are counted from 1970-01-01"))
        rate, frames = self.header.rate_hz, self._info.frames
        per = max(1, round(self._block_s * rate))
        whole = frames - frames % per
        t0 = time.monotonic()
        first = 0
        parts = [iter_wav_blocks(self._info, per, stop_frame=whole, compact=True)]
        if whole < frames:
            parts.append(iter_wav_blocks(self._info, frames - whole, start_frame=whole, compact=True))
        for blocks in parts:
            for block in blocks:
                if not self._pace(t0, first / (rate * self._speed)):
                    return
                samples = np.ascontiguousarray(block.T, dtype=np.float32)
                if not self._put(SampleBlock(first, samples)):
                    return
                first += samples.shape[0]

    def _pace(self, t0: float, due_s: float) -> bool:
        """Wait until ``due_s`` after ``t0`` (no wait at infinite speed); False when closed meanwhile."""
        if math.isinf(self._speed):
            return not self._stop.is_set()
        wait = t0 + due_s - time.monotonic()
        return not (wait > 0 and self._stop.wait(wait))
