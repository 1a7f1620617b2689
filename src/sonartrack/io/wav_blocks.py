"""Streaming reader of N-channel recordings: fixed-size blocks, memory independent of the file's length.

Formats, decoded by libsndfile through ``soundfile``: WAV (plain and WAVE_FORMAT_EXTENSIBLE), RF64 and Sony
W64 (the 64-bit WAV variants recorders switch to past 4 GiB), and FLAC; samples 16-, 24- or 32-bit PCM or
32/64-bit IEEE float. Integers are scaled to [-1, 1): x / 2^(bits - 1) (libsndfile's rule for reading
integers as floating point). Each block is decoded with ``SoundFile.buffer_read_into`` into one reused
buffer of the file's own sample type (float32, float64, or int32 holding any integer width left-justified),
then cast and scaled into the float64 block in one pass; so reading a recording of any length holds about two
blocks in memory. (Asking libsndfile for float64 directly is 2-3 times slower: its conversion loop runs in
small pieces.) One reader serves every format: it reads a 16-channel float32 WAV as fast as a plain RIFF
``readinto`` reader giving the same C-ordered blocks (benchmarks/bench_readers.py).

``compact`` blocks (:func:`block_dtype`) are float32 where every sample of the file is exactly a float32 --
float32 files, and 16- and 24-bit PCM (k / 2^15 and k / 2^23 need at most 24 significant bits) -- so the values
are the float64 blocks' to the last bit at half the memory and copying; a float32 file is then decoded straight
into the block (no buffer, no copy). 32-bit PCM and float64 files stay float64.

libsndfile quietly shortens a WAV-family file whose data ends before its header says; this module walks the
RIFF / RF64 / W64 chunks itself to read the stated data size and refuses such a file. A truncated FLAC is
caught up front by seeking to its last frame (the decoder loses sync there). The walk also reads the
Broadcast WAV ``bext`` chunk: its OriginationDate + OriginationTime (taken as UTC) is the recording's start
time, refined to the sample by TimeReference (samples since midnight) when the two agree within a second.

Refused with a one-line :class:`InputError` naming the file and the fix: a missing file or a folder, a file
that is none of the formats above, a truncated header, 8-bit or companded samples, lossy codecs, no frames,
data shorter than the header states (a truncated copy: the frames present are never read silently), and a
block holding NaN/inf or a sample beyond 1e15 (named by its start time).
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import soundfile as sf

from sonartrack.core.errors import InputError, require

#: libsndfile sub-type -> (our sample format name, bytes per sample in a WAV-family data chunk)
_SUBTYPES = {"PCM_16": ("int16", 2), "PCM_24": ("int24", 3), "PCM_32": ("int32", 4), "FLOAT": ("float32", 4),
             "DOUBLE": ("float64", 8)}
#: libsndfile major format -> our container name
#: sample format -> (type libsndfile decodes to, scale to [-1, 1)): integers arrive left-justified in int32
_NATIVE = {"int16": ("int32", 2.0**-31), "int24": ("int32", 2.0**-31), "int32": ("int32", 2.0**-31),
           "float32": ("float32", 1.0), "float64": ("float64", 1.0)}
_CONTAINERS = {"WAV": "WAV", "WAVEX": "WAV", "RF64": "RF64", "W64": "W64", "FLAC": "FLAC"}
_CONVERT = "convert it to 16/24-bit PCM or 32-bit float WAV or FLAC (e.g. sox in.wav -b 24 out.wav, or ffmpeg -i " \
           "in.wav -c:a pcm_f32le out.wav)"
_W64_RIFF = b"riff\x2e\x91\xcf\x11\xa5\xd6\x28\xdb\x04\xc1\x00\x00"

#: a float sample beyond this is no pressure in pascals nor a normalised sample (as io/wav.py)
MAX_FLOAT_SAMPLE = 1e15
#: file name suffixes read as recordings when a folder is given (io/recording_sequence.py)
RECORDING_SUFFIXES = (".wav", ".rf64", ".w64", ".flac", ".bwf")


@dataclass(frozen=True)
class WavInfo:
    """What the header of a recording says: channels, sample rate (Hz), frames, sample format (int16, int24,
    int32, float32, float64), container (WAV, RF64, W64, FLAC) and the UTC start time when a Broadcast WAV
    ``bext`` chunk carries one (else None)."""

    path: Path
    channels: int
    sample_rate_hz: float
    frames: int
    sample_format: str
    container: str = "WAV"
    start_utc: datetime | None = None

    @property
    def duration_s(self) -> float:
        """Length of the recording (s)."""
        return self.frames / self.sample_rate_hz


@dataclass(frozen=True, slots=True)
class _Header:
    """What our own chunk walk found: the data size the header states (bytes) and the bext start time."""

    data_bytes: int | None
    start_utc: datetime | None


def _read_exact(fh, n: int, path: Path, what: str) -> bytes:
    data = fh.read(n)
    if len(data) < n:
        raise InputError(f"{path}: the WAV header is truncated ({what} cut short): the file is incomplete; copy "
                         "or export it again")
    return data


def _chunks(fh, path: Path, w64: bool):
    """(chunk id, body size, offset of its body) of each chunk after the RIFF/RF64/W64 header, in file order.
    W64 ids are 16-byte GUIDs whose first 4 bytes spell the RIFF id; sizes are 64-bit, include the 24-byte
    chunk header, and chunks start on 8-byte boundaries."""
    file_size = path.stat().st_size
    pos, head = (40, 24) if w64 else (12, 8)
    while pos + head <= file_size:
        fh.seek(pos)
        raw = _read_exact(fh, head, path, "chunk header")
        if w64:
            cid, size = raw[:4], struct.unpack("<Q", raw[16:24])[0] - 24
            step = 24 + size + (-(24 + size) % 8)
        else:
            cid, size = struct.unpack("<4sI", raw)
            step = 8 + size + (size & 1)
        yield cid, size, pos + head
        if step <= 0:
            return
        pos += step


def _bext_start(body: bytes) -> datetime | None:
    """UTC start of a Broadcast WAV bext chunk (EBU Tech 3285: OriginationDate at byte 320, OriginationTime at
    330, TimeReference (uint64, samples since midnight) at 338); None when the date is blank or malformed."""
    if len(body) < 346:
        return None
    text = body[320:338].decode("ascii", "replace").replace(":", "-").replace("/", "-").replace(".", "-")
    try:
        return datetime.strptime(text, "%Y-%m-%d%H-%M-%S").replace(tzinfo=UTC)
    except ValueError:
        return None


def _refine_start(start: datetime | None, time_ref: int, rate: float) -> datetime | None:
    """TimeReference gives the start to the sample; it is trusted only when it agrees with OriginationTime."""
    if start is None or time_ref <= 0:
        return start
    midnight = start.replace(hour=0, minute=0, second=0, microsecond=0)
    precise = midnight + timedelta(seconds=time_ref / rate)
    return precise if abs((precise - start).total_seconds()) < 1.0 else start


def _walk_header(p: Path, rate: float) -> _Header:
    """Stated data size (bytes) and bext start of a RIFF, RF64 or W64 file; a FLAC has neither here."""
    with open(p, "rb") as fh:
        head = fh.read(40)
        if head[:4] == b"fLaC":
            return _Header(None, None)
        w64 = head[:16] == _W64_RIFF
        require(w64 or (len(head) >= 12 and head[:4] in (b"RIFF", b"RF64") and head[8:12] == b"WAVE"),
                f"{p} is not a RIFF/WAVE, RF64, W64 or FLAC recording (starts with {head[:4]!r}): {_CONVERT}")
        data_bytes, ds64, start, time_ref = None, None, None, 0
        for cid, size, _body in _chunks(fh, p, w64):
            if cid == b"ds64":
                ds64 = struct.unpack("<Q", _read_exact(fh, 16, p, "ds64 chunk")[8:16])[0]
            elif cid == b"bext":
                raw = fh.read(min(size, 346))
                start, time_ref = _bext_start(raw), (struct.unpack("<Q", raw[338:346])[0] if len(raw) >= 346 else 0)
            elif cid == b"data":
                data_bytes = ds64 if (head[:4] == b"RF64" and size == 0xFFFFFFFF) else size
                break
    require(data_bytes is not None, f"{p}: no data chunk: the file is truncated or empty; export the recording again")
    return _Header(int(data_bytes), _refine_start(start, time_ref, rate))


def _check_path(path) -> Path:
    p = Path(path)
    require(p.exists(), f"recording not found: {p}: check the path (--wav)")
    require(p.is_file(), f"{p} is a directory, not a recording: give a file inside it, or read it as a sequence "
                         "of files (io/recording_sequence.py)")
    return p


def _sound_info(p: Path):
    """libsndfile's view of the file; its refusal turned into one line."""
    with open(p, "rb") as fh:
        head = fh.read(12)
    require(not (len(head) < 12 and head[:4] == b"RIFF"[: len(head)]),
            f"{p}: the WAV header is truncated ({len(head)} bytes): the file is incomplete; export it again")
    try:
        return sf.info(str(p))
    except (sf.LibsndfileError, RuntimeError) as e:
        msg = str(e).splitlines()[-1] if str(e) else type(e).__name__
        if head[:4] in (b"RIFF", b"RF64", b"fLaC", b"riff"):
            raise InputError(f"{p}: the header is truncated or damaged (libsndfile: {msg}): the file is "
                             "incomplete; copy or export it again") from None
        raise InputError(f"{p} is not a RIFF/WAVE, RF64, W64 or FLAC recording (starts with {head[:4]!r}): "
                         f"{_CONVERT}") from None


def _sample_format(si, p: Path) -> str:
    require(si.format in _CONTAINERS, f"{p} is a {si.format_info} file: give WAV, RF64, W64 or FLAC ({_CONVERT})")
    if si.subtype in _SUBTYPES:
        return _SUBTYPES[si.subtype][0]
    what = {"PCM_U8": "8-bit PCM", "PCM_S8": "8-bit PCM", "ULAW": "8-bit mu-law", "ALAW": "8-bit A-law"}
    raise InputError(f"{p}: {what.get(si.subtype, si.subtype_info)} samples are not supported (too coarse or lossy "
                     f"for array processing): {_CONVERT}")


def _check_complete(p: Path, si, header: _Header) -> None:
    """Refuse a file whose data ends before its header says (the frames present are never read silently)."""
    if header.data_bytes is not None:
        stated = header.data_bytes // (si.channels * _SUBTYPES[si.subtype][1])
        require(si.frames >= stated, f"{p} is truncated: the header states {stated} frames "
                                     f"({stated / si.samplerate:.1f} s) but only {si.frames} are present "
                                     f"({si.frames / si.samplerate:.1f} s): copy the file again, or repair its "
                                     "header (e.g. sox --ignore-length in.wav out.wav)")
        return
    try:
        with sf.SoundFile(str(p)) as f:
            f.seek(si.frames - 1)
            complete = f.read(1, dtype="float64").shape[0] == 1
    except (sf.LibsndfileError, RuntimeError):
        complete = False
    require(complete, f"{p} is truncated: its header states {si.frames} frames ({si.frames / si.samplerate:.1f} s) "
                      "but the last of them cannot be decoded: copy the file again")


def read_wav_info(path) -> WavInfo:
    """Read and check the header of the recording at ``path`` (module doc).

    Parameters
    ----------
    path : str or Path
        A WAV, RF64, W64 or FLAC file.

    Returns
    -------
    WavInfo
        Channels, sample rate (Hz), frames, sample format, container, UTC start (from bext, else None).
    """
    p = _check_path(path)
    si = _sound_info(p)
    sample_format = _sample_format(si, p)
    require(si.channels >= 1 and si.samplerate > 0, f"{p}: the header states {si.channels} channels at "
                                                    f"{si.samplerate} Hz: the header is damaged; export it again")
    header = _walk_header(p, float(si.samplerate))
    require(si.frames > 0 and header.data_bytes != 0,
            f"{p} holds no samples (empty data): record or export a non-empty file")
    _check_complete(p, si, header)
    return WavInfo(p, int(si.channels), float(si.samplerate), int(si.frames), sample_format,
                   _CONTAINERS[si.format], header.start_utc)


def check_block(block: np.ndarray, path, start_s: float) -> None:
    """Refuse a block holding NaN/inf or a sample beyond :data:`MAX_FLOAT_SAMPLE`.

    Two reductions and no temporary: max and -min are NaN or inf if any sample is.

    Parameters
    ----------
    block : ndarray of float64
        Samples (Pa, or normalised full scale).
    path : str or path-like
        The recording, named in the message.
    start_s : float
        Start time of the block (s), named in the message.

    Raises
    ------
    InputError
        On a NaN/inf or an implausibly large sample.
    """
    hi, lo = float(block.max()), float(block.min())
    peak = max(hi, -lo)
    if not (np.isfinite(hi) and np.isfinite(lo)):
        raise InputError(f"{path} holds NaN/inf samples in the block starting at {start_s:.3f} s: repair or cut that "
                         "part of the recording")
    if peak > MAX_FLOAT_SAMPLE:
        raise InputError(f"{path} holds samples of magnitude {peak:.3g} in the block starting at {start_s:.3f} s: "
                         "no pressure (Pa) or normalised sample is that large; the file is corrupt or not audio")


def native_buffer(info: WavInfo, frames: int) -> np.ndarray:
    """A reusable buffer of the type libsndfile decodes ``info``'s samples to without a conversion loop of its own.

    Parameters
    ----------
    info : WavInfo
        The recording's header (its sample format and channel count).
    frames : int
        Rows of the buffer.

    Returns
    -------
    ndarray, shape (frames, channels)
        Uninitialised; float32, float64, or int32 for every integer width.
    """
    return np.empty((int(frames), info.channels), dtype=_NATIVE[info.sample_format][0])


def block_dtype(info: WavInfo, compact: bool = False) -> type:
    """The blocks' sample type for ``info``'s recording: float64, or with ``compact`` float32 where each sample is
    exactly a float32 (module doc).

    Parameters
    ----------
    info : WavInfo
        The recording's header (its sample format).
    compact : bool
        Ask for float32 where that changes no value.

    Returns
    -------
    type
        ``numpy.float32`` (compact, and a float32, 16-bit or 24-bit file) or ``numpy.float64``.
    """
    exact32 = info.sample_format in ("float32", "int16", "int24")
    return np.float32 if compact and exact32 else np.float64


def read_frames_into(f, raw: np.ndarray, out: np.ndarray, info: WavInfo, start_s: float) -> None:
    """Decode ``out.shape[1]`` frames from an open SoundFile into ``out``, through ``raw``.

    Integers arrive as int32 k 2^(32 - bits) and are scaled by 2^-31 (exact in float64, and in float32 for 16 and
    24 bits). A float ``out`` of the file's own type whose transpose is C-contiguous (a slice of the blocks'
    frames x channels layout) is decoded into directly, without ``raw``.

    Parameters
    ----------
    f : soundfile.SoundFile
        The open recording, positioned at the first frame wanted.
    raw : ndarray
        Buffer from :func:`native_buffer` with at least m rows.
    out : ndarray of float64 or float32, shape (channels, m)
        Destination, written in place (float32 only for formats :func:`block_dtype` allows).
    info : WavInfo
        The recording's header.
    start_s : float
        Time of the first frame (s), named in errors.

    Raises
    ------
    InputError
        On a short read or a decoder error (the data ends early).
    """
    dtype, scale = _NATIVE[info.sample_format]
    direct = scale == 1.0 and out.dtype == np.dtype(dtype) and out.T.flags.c_contiguous
    part = out.T if direct else raw[: out.shape[1]]
    try:
        got = f.buffer_read_into(part, dtype)
    except (sf.LibsndfileError, RuntimeError) as e:
        raise InputError(f"{info.path} cannot be decoded at {start_s:.1f} s ({e}): the file is truncated or "
                         "damaged; copy it again") from None
    if got != part.shape[0]:
        raise InputError(f"{info.path} was truncated while being read (at {start_s:.1f} s): copy the file again")
    if direct:
        return
    if scale == 1.0:
        np.copyto(out, part.T)
    else:
        np.multiply(part.T, scale, out=out, dtype=out.dtype)


def iter_wav_blocks(info_or_path, block_frames: int, *, start_frame: int = 0,
                    stop_frame: int | None = None, compact: bool = False) -> Iterator[np.ndarray]:
    """Blocks of ``block_frames`` frames as float64 arrays (channels, block_frames), integers scaled to [-1, 1).

    Parameters
    ----------
    info_or_path : WavInfo or str or Path
        The recording (its header is read if a path is given).
    block_frames : int
        Frames per block.
    start_frame, stop_frame : int
        Frames ``start_frame`` .. ``stop_frame`` (default: the end) are read; a partial last block (fewer than
        ``block_frames`` frames left) is dropped, as the bearing estimator drops a partial last window.
    compact : bool
        float32 blocks where that changes no sample (:func:`block_dtype`): the same values, half the memory.

    Returns
    -------
    Iterator of ndarray
        Each block a new array (a transposed frames x channels array, the file's own layout), decoded
        through one reused buffer: memory does not grow with the
        file. A block holding NaN/inf raises InputError naming its start time (s).
    """
    info = info_or_path if isinstance(info_or_path, WavInfo) else read_wav_info(info_or_path)
    block_frames = int(block_frames)
    require(block_frames >= 1, f"block_frames must be >= 1, got {block_frames}")
    stop = info.frames if stop_frame is None else min(int(stop_frame), info.frames)
    require(0 <= start_frame <= stop, f"start_frame {start_frame} must lie in 0..{stop}")
    raw = native_buffer(info, block_frames)
    with sf.SoundFile(str(info.path)) as f:
        if start_frame:
            f.seek(int(start_frame))
        for first in range(int(start_frame), stop - block_frames + 1, block_frames):
            start_s = first / info.sample_rate_hz
            # frames x channels transposed: the layout of the interleaved file, which the front end's FFTs have
            # always been given (a C-ordered block changes their last digits)
            block = np.empty((block_frames, info.channels), dtype=block_dtype(info, compact)).T
            read_frames_into(f, raw, block, info, start_s)
            if info.sample_format.startswith("float"):
                check_block(block, info.path, start_s)
            yield block
