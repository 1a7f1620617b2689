"""A recording as a sequence of consecutive files: one block source over a folder or a glob of files.

Recorders cut a long recording into files (often of 5-60 min), each named or stamped with its start time. The
files are read in order as one recording on one frame axis (frame 0 = the first sample of the earliest
file); a window that spans two files is stitched from both, as if the recording were one file.

Start times (UTC; a name or a header without a zone is taken as UTC):

- ``header``: the Broadcast WAV ``bext`` origination date and time of each file (io/wav_blocks.py);
- ``names``: a ``strptime`` pattern searched in each file name; by default :data:`DEFAULT_NAME_PATTERNS`,
  ``%Y%m%d_%H%M%S`` (AudioMoth, Wildlife Acoustics: ``SM4_20240517_134507.wav``) or ``%Y%m%dT%H%M%S`` (ISO
  8601 basic: ``AMAR.20240517T134507Z.wav``); others by the user's pattern (SoundTrap
  ``5783.240517134507.wav``: ``.%y%m%d%H%M%S``). Directives: %Y %y %m %d %j %H %M %S %f;
- ``contiguous``: no times; the files, in name order, follow each other without gaps (stated by the user);
- ``auto`` (default): header if every file has one, else names if every name matches, else a single file
  starts at an unknown time; several files without times are refused.

Joining: a file whose stated start lies within ``join_tolerance_s`` (default 1 s, the resolution of a name)
of the end of the file before it follows it directly, frame after frame: the sample clock is trusted over
the clock that stamped the names. Further after it, the frames between are a gap; earlier, the overlap is
reported and the later file's first frames are dropped (the earlier file's samples are kept). Gaps are not
filled: :func:`iter_sequence_blocks` yields only windows whose every frame was recorded, with their start
time on the recording's axis, and :func:`present_windows` marks the windows a bearing-time record must show
as missing. Files of different channel counts or sample rates are refused (they are not one recording).
"""

from __future__ import annotations

import glob
import re
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import soundfile as sf

from sonartrack.core.errors import InputError, require
from sonartrack.io.wav_blocks import (
    RECORDING_SUFFIXES,
    WavInfo,
    block_dtype,
    check_block,
    native_buffer,
    read_frames_into,
    read_wav_info,
    seek_frame,
)

DEFAULT_NAME_PATTERNS = ("%Y%m%d_%H%M%S", "%Y%m%dT%H%M%S")
TIME_SOURCES = ("auto", "header", "names", "contiguous")
_DIRECTIVES = {"Y": r"\d{4}", "y": r"\d{2}", "m": r"\d{2}", "d": r"\d{2}", "j": r"\d{3}", "H": r"\d{2}",
               "M": r"\d{2}", "S": r"\d{2}", "f": r"\d{1,6}", "%": "%"}


@dataclass(frozen=True, slots=True)
class SequenceFile:
    """One file of a sequence: its header, its stated start (UTC or None), where its first kept frame lies on
    the recording's frame axis, and how many of its first frames are dropped (an overlap with the file before)."""

    info: WavInfo
    start_utc: datetime | None
    first_frame: int
    skip_frames: int = 0

    @property
    def end_frame(self) -> int:
        """One past the recording frame of its last sample."""
        return self.first_frame + max(self.info.frames - self.skip_frames, 0)


@dataclass(frozen=True, slots=True)
class Discontinuity:
    """A gap (frames never recorded) or an overlap (frames recorded twice, the later copy dropped) between two
    files, in seconds on the recording's time axis."""

    kind: str
    start_s: float
    end_s: float
    before: Path
    after: Path

    def describe(self) -> str:
        """One line naming the discontinuity for a warning or a status file.

        Returns
        -------
        str
            Kind, length (s), start..end (s on the recording's time axis) and the names of the two files.
        """
        return (f"{self.kind} of {self.end_s - self.start_s:.3f} s at {self.start_s:.3f}..{self.end_s:.3f} s "
                f"between {self.before.name} and {self.after.name}")


@dataclass(frozen=True, slots=True)
class RecordingSequence:
    """Consecutive files read as one recording: channels, sample rate (Hz), UTC start of frame 0 (None if
    unknown), how the start times were found, and the gaps and overlaps between files."""

    files: tuple[SequenceFile, ...]
    channels: int
    sample_rate_hz: float
    start_utc: datetime | None
    time_source: str
    gaps: tuple[Discontinuity, ...]
    overlaps: tuple[Discontinuity, ...]

    @property
    def frames(self) -> int:
        """Frames from the first sample to the last, gaps included."""
        return self.files[-1].end_frame if self.files else 0

    @property
    def duration_s(self) -> float:
        """Seconds from the first sample to the last, gaps included (``frames`` / ``sample_rate_hz``)."""
        return self.frames / self.sample_rate_hz

    @property
    def recorded_s(self) -> float:
        """Seconds actually recorded (gaps excluded)."""
        return sum(f.end_frame - f.first_frame for f in self.files) / self.sample_rate_hz


def list_recording_files(spec) -> list[Path]:
    """The files named by ``spec``: one file, a folder (its files ending in .wav, .rf64, .w64, .flac or .bwf,
    any case, not recursive) or a glob pattern (``rec/*.flac``); sorted by name.

    Parameters
    ----------
    spec : str or Path
        A file, a folder or a glob pattern.

    Returns
    -------
    list of Path
        At least one file; InputError otherwise.
    """
    text = str(spec)
    p = Path(text)
    if p.is_dir():
        files = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in RECORDING_SUFFIXES
                       and not q.name.startswith("."))
        require(files, f"directory {p} holds no recording (.wav, .rf64, .w64, .flac, .bwf): give a recording file, "
                       "or the folder of the recorder's files")
        return files
    if any(c in text for c in "*?["):
        files = sorted(Path(q) for q in glob.glob(text) if Path(q).is_file())
        require(files, f"no file matches {text}: check the pattern (quote it so that the shell does not expand it)")
        return files
    require(p.exists(), f"recording not found: {p}: give a file, a folder of files or a glob pattern (--wav)")
    return [p]


def _pattern_regex(pattern: str) -> re.Pattern:
    """A strptime pattern as a regex matching exactly what strptime would parse (digits of fixed width)."""
    parts, i = [], 0
    while i < len(pattern):
        c = pattern[i]
        if c == "%":
            d = pattern[i + 1: i + 2]
            require(d in _DIRECTIVES, f"file name pattern '{pattern}': unsupported directive %{d}: use "
                                      f"{' '.join('%' + k for k in _DIRECTIVES if k != '%')}")
            parts.append(_DIRECTIVES[d])
            i += 2
        else:
            parts.append(re.escape(c))
            i += 1
    return re.compile("".join(parts))


def name_start_utc(name: str, patterns=DEFAULT_NAME_PATTERNS) -> datetime | None:
    """The UTC start time in a file name: the first of ``patterns`` (strptime syntax, searched anywhere in the
    name; a leading or trailing ``*`` is ignored) that matches and parses; None if none does.

    Parameters
    ----------
    name : str
        A file name.
    patterns : str or sequence of str
        strptime patterns (module doc).

    Returns
    -------
    datetime or None
        Time-zone aware (UTC).
    """
    for pattern in (patterns,) if isinstance(patterns, str) else patterns:
        core = pattern.strip("*")
        for m in _pattern_regex(core).finditer(name):
            try:
                return datetime.strptime(m.group(0), core).replace(tzinfo=UTC)
            except ValueError:
                continue
    return None


def _check_alike(infos: list[WavInfo]) -> None:
    a = infos[0]
    for b in infos[1:]:
        require(b.channels == a.channels and b.sample_rate_hz == a.sample_rate_hz,
                f"{b.path.name} has {b.channels} channels at {b.sample_rate_hz:g} Hz but {a.path.name} has "
                f"{a.channels} at {a.sample_rate_hz:g} Hz: the files of one recording share both; give them as "
                "separate recordings")


def _start_times(infos: list[WavInfo], time_source: str, patterns) -> tuple[list[datetime | None], str]:
    """Each file's stated start and the source used (module doc)."""
    require(time_source in TIME_SOURCES, f"unknown time source '{time_source}': choose {', '.join(TIME_SOURCES)}")
    headers = [i.start_utc for i in infos]
    names = [name_start_utc(i.path.name, patterns) for i in infos]
    if time_source == "contiguous":
        return [None] * len(infos), "contiguous"
    shown = patterns if isinstance(patterns, str) else " or ".join(patterns)
    if time_source == "header" or (time_source == "auto" and all(h is not None for h in headers)):
        missing = [i.path.name for i, h in zip(infos, headers, strict=True) if h is None]
        if missing:
            raise InputError(f"{missing[0]} has no start time in its header (Broadcast WAV bext chunk): read the "
                             f"times from the names (time source 'names', pattern {shown})")
        return headers, "header"
    if time_source == "names" or all(n is not None for n in names):
        missing = [i.path.name for i, n in zip(infos, names, strict=True) if n is None]
        if missing:
            raise InputError(f"no start time in the file name {missing[0]} (pattern {shown}): give the pattern of "
                             "the names (strptime syntax, e.g. 'rec_%Y%m%d_%H%M%S')")
        return names, "names"
    require(len(infos) == 1, f"cannot place the {len(infos)} files in time: {infos[0].path.name} has no start time "
                             f"in its header nor in its name (pattern {shown}): give the pattern of the names, or "
                             "state that the files are contiguous (time source 'contiguous')")
    return [None], "none"


def _place(infos, starts, tol_s: float) -> tuple[list[SequenceFile], list[Discontinuity], list[Discontinuity]]:
    """Frame positions of the files in start order, and the gaps and overlaps between them (module doc)."""
    fs = infos[0].sample_rate_hz
    order = sorted(range(len(infos)), key=lambda i: (starts[i] or datetime.min.replace(tzinfo=UTC),
                                                     infos[i].path.name))
    t0 = starts[order[0]]
    placed, gaps, overlaps = [], [], []
    for i in order:
        info, start = infos[i], starts[i]
        if not placed:
            placed.append(SequenceFile(info, start, 0))
            continue
        prev = placed[-1]
        expected = prev.end_frame
        stated = expected if start is None else int(round((start - t0).total_seconds() * fs))
        if abs(stated - expected) <= tol_s * fs:
            placed.append(SequenceFile(info, start, expected))
        elif stated > expected:
            gaps.append(Discontinuity("gap", expected / fs, stated / fs, prev.info.path, info.path))
            placed.append(SequenceFile(info, start, stated))
        else:
            skip = min(expected - stated, info.frames)
            overlaps.append(Discontinuity("overlap", stated / fs, (stated + skip) / fs, prev.info.path, info.path))
            placed.append(SequenceFile(info, start, expected, skip))
    return placed, gaps, overlaps


def open_sequence(spec, *, time_source: str = "auto", name_pattern=None,
                  join_tolerance_s: float = 1.0) -> RecordingSequence:
    """Read the headers of the files named by ``spec`` and place them on one time axis (module doc).

    Parameters
    ----------
    spec : str or Path
        A file, a folder or a glob pattern (:func:`list_recording_files`).
    time_source : str
        auto, header, names or contiguous.
    name_pattern : str or sequence of str, optional
        strptime pattern(s) of the start time in the names (default :data:`DEFAULT_NAME_PATTERNS`).
    join_tolerance_s : float
        Largest difference (s) between a file's stated start and the end of the file before it for the two to
        be joined frame after frame.

    Returns
    -------
    RecordingSequence
        The files in time order with their frame positions, the gaps and the overlaps.
    """
    require(join_tolerance_s >= 0, f"join tolerance must be >= 0 s, got {join_tolerance_s:g}")
    infos = [read_wav_info(p) for p in list_recording_files(spec)]
    _check_alike(infos)
    starts, source = _start_times(infos, time_source, name_pattern or DEFAULT_NAME_PATTERNS)
    files, gaps, overlaps = _place(infos, starts, float(join_tolerance_s))
    return RecordingSequence(tuple(files), infos[0].channels, infos[0].sample_rate_hz, files[0].start_utc, source,
                             tuple(gaps), tuple(overlaps))


def _runs(files) -> list[list[SequenceFile]]:
    """Maximal chains of files that follow each other frame after frame (no gap between them)."""
    runs: list[list[SequenceFile]] = []
    for f in files:
        if f.end_frame <= f.first_frame:
            continue
        if runs and runs[-1][-1].end_frame == f.first_frame:
            runs[-1].append(f)
        else:
            runs.append([f])
    return runs


def present_windows(seq: RecordingSequence, block_frames: int) -> np.ndarray:
    """Which windows k (frames k W .. (k + 1) W, W = ``block_frames``) of the recording were wholly recorded.

    Parameters
    ----------
    seq : RecordingSequence
        The recording.
    block_frames : int
        Frames per window.

    Returns
    -------
    ndarray of bool
        One entry per window of the span (``seq.frames // block_frames``); False where a gap touches it.
    """
    w = int(block_frames)
    mask = np.zeros(seq.frames // w, dtype=bool)
    for run in _runs(seq.files):
        mask[-(-run[0].first_frame // w): run[-1].end_frame // w] = True
    return mask


def _run_blocks(run, lo: int, hi: int, w: int, fs: float, compact: bool) -> Iterator[tuple[float, np.ndarray]]:
    """Windows of frames lo..hi (multiples of w) of one run, stitched across its files (float32 only where every
    file of the run allows it: io/wav_blocks.py ``block_dtype``)."""
    raws: dict[str, np.ndarray] = {}
    dtype = np.result_type(*(block_dtype(item.info, compact) for item in run))
    block, fill, block_start, where = None, 0, lo, (None, 0.0)
    for item in run:
        a, b = max(lo, item.first_frame), min(hi, item.end_frame)
        if a >= b:
            continue
        info = item.info
        raw = raws.setdefault(info.sample_format, native_buffer(info, w))
        with sf.SoundFile(str(info.path)) as f:
            seek_frame(f, info, item.skip_frames + a - item.first_frame)
            pos = a
            while pos < b:
                in_file_s = (item.skip_frames + pos - item.first_frame) / fs
                if block is None:
                    # (channels, w) view of a frames x channels array: the layout io/wav_blocks.py yields, so
                    # that the front end's sums run in the same order (the same digits) for one file or many
                    block, block_start, where = np.empty((w, info.channels), dtype).T, pos, (info.path, in_file_s)
                take = min(w - fill, b - pos)
                read_frames_into(f, raw, block[:, fill: fill + take], info, in_file_s)
                fill, pos = fill + take, pos + take
                if fill == w:
                    check_block(block, *where)
                    yield block_start / fs, block
                    block, fill = None, 0


def iter_sequence_blocks(seq: RecordingSequence, block_frames: int, *, start_frame: int = 0,
                         stop_frame: int | None = None, compact: bool = False) -> Iterator[tuple[float, np.ndarray]]:
    """The recorded windows of the sequence, in time order, as (start time (s) on the recording's axis, block).

    Parameters
    ----------
    seq : RecordingSequence
        The recording (:func:`open_sequence`).
    block_frames : int
        Frames per window; windows lie on the grid k ``block_frames`` from frame 0.
    start_frame, stop_frame : int
        Only the windows wholly inside frames ``start_frame`` .. ``stop_frame`` (default: the end) of the
        recording's axis are read (an excerpt: the files before it are not decoded).
    compact : bool
        float32 blocks where every file's samples are exactly float32 (io/wav_blocks.py ``block_dtype``): the same
        values at half the memory.

    Returns
    -------
    Iterator of (float, ndarray)
        Each block a new (channels, block_frames) float64 (or compact) array, stitched across file boundaries;
        windows a gap touches are skipped (:func:`present_windows`, ``seq.gaps``). NaN/inf or absurd samples raise
        InputError naming the time.
    """
    w = int(block_frames)
    require(w >= 1, f"block_frames must be >= 1, got {w}")
    first, last = -(-int(start_frame) // w) * w, (seq.frames if stop_frame is None else int(stop_frame)) // w * w
    for run in _runs(seq.files):
        lo = max(-(-run[0].first_frame // w) * w, first)
        hi = min(run[-1].end_frame // w * w, last)
        if hi > lo:
            yield from _run_blocks(run, lo, hi, w, seq.sample_rate_hz, compact)


def check_no_gaps(seq: RecordingSequence) -> None:
    """Refuse a sequence with gaps where a caller needs one unbroken recording (one line naming the first).

    Parameters
    ----------
    seq : RecordingSequence
        The sequence; raises :class:`InputError` when it has a gap.
    """
    if seq.gaps:
        raise InputError(f"the recording has {len(seq.gaps)} gap(s), the first a {seq.gaps[0].describe()}: "
                         "process the parts separately, or join the files with the gaps filled")
