"""A folder a recorder is writing, read live: its recordings in name order as one stream, the newest read as it
grows (io/stream/growing.py), new files picked up as they appear.

Files: those with a recording suffix (io/wav_blocks.py ``RECORDING_SUFFIXES``: .wav .rf64 .w64 .flac .bwf) whose
names do not start with "." (io/atomic.py's files in the making are hidden). A file is finished when a file
after it in name order has appeared, or when nothing has grown for ``idle_end_s`` (then the stream ends). A FLAC
file is read once finished (it cannot be decoded before). A file that appears with a name before the one being
read, or with other channels or another sample rate than the first, is refused with an event and skipped.

Time axis (as io/recording_sequence.py places a sequence): index 0 is the first file's first sample; its UTC
start is the time in its name (``name_start_utc``: rec_YYYYmmdd_HHMMSS and the like) or its Broadcast WAV start,
else 1970-01-01 with an event ("no_start_time"). A later file whose stated start lies within
``join_tolerance_s`` of the end of the one before follows it sample after sample; later, the samples between
are a gap (event "gap"); earlier, its first samples repeat the earlier file's and are dropped (event
"overlap"). Without start times the files follow each other.

Blocks: ``block_s`` seconds, counted from each file's first kept frame (the same blocks whatever the polling's
timing), the last of a file shorter.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.recording_sequence import DEFAULT_NAME_PATTERNS, name_start_utc
from sonartrack.io.stream._threaded import ThreadedSource
from sonartrack.io.stream.growing import GrowingWav
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader
from sonartrack.io.wav_blocks import RECORDING_SUFFIXES

_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)


class _FlacFile:
    """A finished FLAC file read through io/wav_blocks.py, with the layout's fields the folder reader uses."""

    def __init__(self, path: Path):
        from sonartrack.io.wav_blocks import read_wav_info

        self.info = read_wav_info(path)
        self.path, self.channels, self.rate_hz = path, self.info.channels, self.info.sample_rate_hz
        self.start_utc = None

    def frames_present(self, finished: bool) -> int:
        return self.info.frames if finished else 0

    def read(self, first: int, n: int) -> np.ndarray:
        from sonartrack.io.wav_blocks import iter_wav_blocks

        block = next(iter_wav_blocks(self.info, n, start_frame=first, stop_frame=first + n, compact=True))
        return np.ascontiguousarray(block.T, dtype=np.float32)


class FolderSampleSource(ThreadedSource):
    """Sample blocks from a folder a recorder writes (module doc); an iterator with ``header`` and ``close()``.

    Parameters
    ----------
    folder : str or Path
        The recorder's folder.
    block_s : float
        Seconds per block.
    poll_s : float
        How often (s) the folder and the newest file are looked at.
    idle_end_s : float, optional
        End the stream when nothing has grown for this long (s); None: wait for ever.
    join_tolerance_s : float
        A file starting this close (s) to the end of the one before follows it directly.
    name_patterns : tuple of str
        strptime patterns of the start time in the names.
    """

    _name = "folder-source"

    def __init__(self, folder, *, block_s: float = 0.1, poll_s: float = 0.2, idle_end_s: float | None = None,
                 join_tolerance_s: float = 1.0, name_patterns=DEFAULT_NAME_PATTERNS):
        super().__init__()
        self.folder = Path(folder)
        require(self.folder.is_dir(), f"recording folder not found: {self.folder}: give the folder the recorder "
                                      "writes into")
        require(block_s > 0 and poll_s > 0, "block_s and poll_s must be > 0")
        self.header: StreamHeader | None = None
        self._block_s, self._poll_s, self._idle_end_s = float(block_s), float(poll_s), idle_end_s
        self._tol_s, self._patterns = float(join_tolerance_s), tuple(name_patterns)
        self._current = None  # (file, first index on the axis, frames done in the file, skip)
        self._last_name = ""
        self._end_index = 0  # one past the last sample given out

    def _listing(self) -> list[Path]:
        return sorted(p for p in self.folder.iterdir() if p.suffix.lower() in RECORDING_SUFFIXES
                      and not p.name.startswith(".") and p.is_file())

    def _run(self) -> None:
        last_growth = time.monotonic()
        while not self._stop.is_set():
            files = self._listing()
            later = [p for p in files if p.name > self._last_name]
            idle = self._idle_end_s is not None and time.monotonic() - last_growth > self._idle_end_s
            if self._current is None and later and self._open(later[0], len(later) == 1 and not idle):
                continue
            finished = self._current is not None and (len(later) > 0 or idle)
            grew = self._current is not None and self._read(finished)
            if grew:
                last_growth = time.monotonic()
            elif finished:
                self._current = None
            elif idle:
                return
            else:
                self._stop.wait(self._poll_s)

    def _open(self, path: Path, newest: bool) -> bool:
        """Start reading ``path``; False to wait (its header, or a FLAC still being written: ``newest``). A file that
        cannot join the stream is skipped."""
        flac = path.suffix.lower() == ".flac"
        if flac and newest:
            return False
        try:
            f = _FlacFile(path) if flac else GrowingWav.open(path)
        except InputError as exc:
            self._skip(path, str(exc))
            return True
        if f is None:
            if newest:
                return False
            self._skip(path, "its header never completed")
            return True
        start = name_start_utc(path.name, self._patterns) or f.start_utc
        if self.header is None:
            self._first_file(f, start)
            return True
        h = self.header
        if (f.channels, f.rate_hz) != (h.channels, h.rate_hz):
            self._skip(path, f"{f.channels} channels at {f.rate_hz:g} Hz, not the stream's {h.channels} at "
                             f"{h.rate_hz:g} Hz: not the same recording")
            return True
        self._place(f, path, start)
        return True

    def _first_file(self, f, start) -> None:
        fmt = getattr(f, "sample_format", None) or f.info.sample_format
        wire = fmt if fmt in ("int16", "int24", "float32") else "float32"
        self.header = StreamHeader(f.channels, float(f.rate_hz), wire, start or _EPOCH, None, str(self.folder))
        if start is None:
            self._put(StreamEvent("no_start_time", f"{f.path.name}: no start time in its name or header: times are "
                                                   "counted from 1970-01-01"))
        self._current, self._last_name = (f, 0, 0, 0), f.path.name

    def _place(self, f, path: Path, start) -> None:
        """Where the next file's samples go on the axis (module doc), with the gap or overlap event."""
        h, end, skip, first = self.header, self._end_index, 0, self._end_index
        if start is not None and h.start_utc != _EPOCH:
            stated = round((start - h.start_utc).total_seconds() * h.rate_hz)
            if stated > end + self._tol_s * h.rate_hz:
                first = stated
                self._put(StreamEvent("gap", f"{path.name} starts {(stated - end) / h.rate_hz:.3f} s after the end "
                                             "of the file before", end, stated - end))
            elif stated < end - self._tol_s * h.rate_hz:
                skip = end - stated
                self._put(StreamEvent("overlap", f"{path.name} repeats the last {skip / h.rate_hz:.3f} s of the "
                                                 "file before: its copy dropped", stated, skip))
        self._current, self._last_name = (f, first - skip, skip, skip), path.name

    def _skip(self, path: Path, why: str) -> None:
        self._put(StreamEvent("refused", f"{path.name} skipped: {why}"))
        self._last_name = max(self._last_name, path.name)

    def _read(self, finished: bool) -> bool:
        """Give out the current file's whole blocks (and, finished, the rest); whether any was given."""
        f, base, done, _ = self._current
        try:
            present = f.frames_present(finished)
        except (OSError, InputError) as exc:
            self._skip(f.path, str(exc))
            self._current = None
            return False
        per = max(1, round(self._block_s * self.header.rate_hz))
        gave = False
        while not self._stop.is_set():
            n = min(per, present - done)
            if n <= 0 or (n < per and not finished):
                break
            self._put(SampleBlock(base + done, f.read(done, n)))
            done, gave = done + n, True
            self._end_index = base + done
        self._current = (f, base, done, self._current[3])
        return gave
