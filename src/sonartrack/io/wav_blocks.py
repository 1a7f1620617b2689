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

libsndfile believes a header: it quietly shortens a WAV-family file whose data ends before its header says, and
reads only as far as a header that states less than the data. Headers are checked, not believed: io/riff_header.py
walks the RIFF / RF64 / W64 chunks (fmt fields against each other, the stated data size against the file, the
Broadcast WAV ``bext`` start time: OriginationDate + OriginationTime taken as UTC, refined to the sample by
TimeReference when the two agree within a second); io/flac_header.py compares a FLAC's STREAMINFO with its first
and last frame headers (rate, channels, bits, length; a length of 0, "unknown", is taken from the frames). A
FLAC's last frame must decode (a file cut inside it keeps its header).

Refused with a one-line :class:`InputError` naming the file and the fix: a missing file or a folder, a file
that is none of the formats above, a truncated header, 8-bit or companded samples, lossy codecs, no frames,
data shorter than the header states (a truncated copy: the frames present are never read silently) or longer
(the header would cut the recording), a header that contradicts itself or its frames, data libsndfile cannot
decode or seek in (named by where it breaks: :func:`damaged`), and a block holding NaN/inf or a sample beyond
1e15 (named by its start time).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np
import soundfile as sf

from sonartrack.core.errors import InputError, require
from sonartrack.io.flac_header import check_flac
from sonartrack.io.riff_header import CONVERT as _CONVERT
from sonartrack.io.riff_header import walk_riff

#: libsndfile sub-type -> (our sample format name, bytes per sample in a WAV-family data chunk)
_SUBTYPES = {"PCM_16": ("int16", 2), "PCM_24": ("int24", 3), "PCM_32": ("int32", 4), "FLOAT": ("float32", 4),
             "DOUBLE": ("float64", 8)}
#: libsndfile major format -> our container name
#: sample format -> (type libsndfile decodes to, scale to [-1, 1)): integers arrive left-justified in int32
_NATIVE = {"int16": ("int32", 2.0**-31), "int24": ("int32", 2.0**-31), "int32": ("int32", 2.0**-31),
           "float32": ("float32", 1.0), "float64": ("float64", 1.0)}
_CONTAINERS = {"WAV": "WAV", "WAVEX": "WAV", "RF64": "RF64", "W64": "W64", "FLAC": "FLAC"}
#: frames per read when a FLAC is decoded to count its frames or to find where it is damaged
_SCAN_FRAMES = 4096
#: largest number of samples decoded to find where a damaged file breaks (beyond it the message names the frame
#: the reader stopped at, with "at or before")
_LOCATE_SAMPLES = 50_000_000

#: a float sample beyond this is no pressure in pascals nor a normalised sample (as io/wav.py)
MAX_FLOAT_SAMPLE = 1e15
#: file name suffixes read as recordings when a folder is given (io/recording_sequence.py)
RECORDING_SUFFIXES = (".wav", ".rf64", ".w64", ".flac", ".bwf")


@dataclass(frozen=True)
class WavInfo:
    """What the header of a recording says: channels, sample rate (Hz), frames, sample format (int16, int24,
    int32, float32, float64), container (WAV, RF64, W64, FLAC), the UTC start time when a Broadcast WAV
    ``bext`` chunk carries one (else None), and whether the header left the length unstated (a FLAC stream whose
    STREAMINFO total is 0: ``frames`` is then the frames' own count)."""

    path: Path
    channels: int
    sample_rate_hz: float
    frames: int
    sample_format: str
    container: str = "WAV"
    start_utc: datetime | None = None
    length_unstated: bool = False

    @property
    def duration_s(self) -> float:
        """Length of the recording (s)."""
        return self.frames / self.sample_rate_hz


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


def _riff_frames(p: Path, si, data_bytes: int) -> int:
    """Frames of a WAV-family file; refused when its data ends before its header says (the frames present are
    never read silently; a header stating less than the data is refused by io/riff_header.py)."""
    stated = data_bytes // (si.channels * _SUBTYPES[si.subtype][1])
    rate = si.samplerate
    require(si.frames >= stated, f"{p} is truncated: the header states {stated} frames ({stated / rate:.1f} s) but "
                                 f"only {si.frames} are present ({si.frames / rate:.1f} s): copy the file again, or "
                                 "repair its header (e.g. sox --ignore-length in.wav out.wav)")
    return int(si.frames)


def _read_native(f, part: np.ndarray, dtype: str, unseeking: bool) -> int:
    """Frames decoded from ``f`` into the C-ordered ``part``. ``unseeking``: through libsndfile's own read call,
    without the seek to the new position that soundfile makes after every read: libFLAC cannot seek to the end of a
    stream whose STREAMINFO leaves the length unstated, so soundfile's read of the last frames fails after reading
    them."""
    if not unseeking:
        return f.buffer_read_into(part, dtype)
    ctype = {"int32": "int", "float32": "float", "float64": "double"}[dtype]
    got = getattr(sf._snd, f"sf_readf_{ctype}")(f._file, sf._ffi.cast(ctype + "*", part.ctypes.data), part.shape[0])
    sf._error_check(f._errorcode)
    return int(got)


def _decoded_frames(p: Path, si, limit: int | None = None) -> tuple[int, str | None]:
    """Frames decoded from the start until the end, the first error or ``limit``; and libsndfile's error (or None)."""
    buf = np.empty((_SCAN_FRAMES, si.channels), dtype=np.int32 if si.subtype.startswith("PCM") else np.float64)
    n = 0
    try:
        with sf.SoundFile(str(p)) as f:
            while limit is None or n < limit:
                got = _read_native(f, buf, buf.dtype.name, True)
                n += got
                if got < _SCAN_FRAMES:
                    return n, None
    except (sf.LibsndfileError, RuntimeError) as e:
        return n, _libsndfile_message(e)
    return n, None


def _libsndfile_message(e: Exception) -> str:
    text = str(e).splitlines()[-1].strip() if str(e) else type(e).__name__
    return text.removeprefix("Error : ").rstrip(".")


def damaged(path, channels: int, rate: float, frame: int, exc: Exception) -> InputError:
    """The one-line error for a recording that libsndfile cannot decode or seek in at ``frame``: where it breaks
    (decoded from the start to find the first frame it cannot, when that is at most :data:`_LOCATE_SAMPLES`
    samples) and the fix.

    Parameters
    ----------
    path : str or Path
        The recording.
    channels : int
        Its channels.
    rate : float
        Its sample rate (Hz).
    frame : int
        The frame the reader was at (reading or seeking to it).
    exc : Exception
        libsndfile's error.

    Returns
    -------
    InputError
        To raise.
    """
    p = Path(path)
    where, cut = f"at or before frame {frame} ({frame / rate:.3f} s)", frame
    if (frame + _SCAN_FRAMES) * channels <= _LOCATE_SAMPLES:
        good, err = _decoded_frames(p, sf.info(str(p)), frame + _SCAN_FRAMES)
        if err is not None:
            where, cut = (f"between frames {good} and {good + _SCAN_FRAMES} ({good / rate:.3f}-"
                          f"{(good + _SCAN_FRAMES) / rate:.3f} s)"), good
    return InputError(f"{p} is damaged: its data cannot be decoded {where} (libsndfile: {_libsndfile_message(exc)}): "
                      f"export the recording again, or cut it before the damage ({cut / rate:.3f} s)")


def _flac_frames(p: Path, si) -> tuple[int, bool]:
    """Frames of a FLAC (STREAMINFO compared with the frame headers: io/flac_header.py; an unstated length counted
    from the frames) and whether STREAMINFO left the length unstated. The last frame must decode: a file cut
    inside its last frame keeps that frame's header."""
    stated, counted = check_flac(p)
    if stated == 0 and counted is None:
        counted, err = _decoded_frames(p, si)
        if err is not None:
            raise damaged(p, si.channels, si.samplerate, counted, RuntimeError(err))
    frames = stated or counted
    try:
        with sf.SoundFile(str(p)) as f:
            f.seek(frames - 1)
            complete = _read_native(f, np.empty((1, si.channels), np.float64), "float64", stated == 0) == 1
    except (sf.LibsndfileError, RuntimeError):
        complete = False
    require(complete, f"{p} is truncated or damaged at its end: its header states {frames} frames "
                      f"({frames / si.samplerate:.1f} s) but the last of them cannot be decoded: copy the file again, "
                      "or export it again")
    return frames, stated == 0


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
    header = walk_riff(p, float(si.samplerate))
    empty = f"{p} holds no samples (empty data): record or export a non-empty file"
    if header is None:
        require(si.frames > 0, empty)
        frames, unstated = _flac_frames(p, si)
    else:
        require(si.frames > 0 and header.data_bytes != 0, empty)
        frames, unstated = _riff_frames(p, si, header.data_bytes), False
    require(frames > 0, empty)
    return WavInfo(p, int(si.channels), float(si.samplerate), int(frames), sample_format, _CONTAINERS[si.format],
                   header.start_utc if header else None, unstated)


def seek_frame(f, info: WavInfo, frame: int) -> None:
    """Seek the open recording ``f`` to ``frame``; a file libsndfile cannot seek in is refused as damaged
    (:func:`damaged`).

    Parameters
    ----------
    f : soundfile.SoundFile
        The open recording.
    info : WavInfo
        Its header.
    frame : int
        Frame to seek to.
    """
    try:
        f.seek(int(frame))
    except (sf.LibsndfileError, RuntimeError) as e:
        raise damaged(info.path, info.channels, info.sample_rate_hz, int(frame), e) from None

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
        got = _read_native(f, part, dtype, info.length_unstated)
    except (sf.LibsndfileError, RuntimeError) as e:
        frame = int(round(start_s * info.sample_rate_hz))
        raise damaged(info.path, info.channels, info.sample_rate_hz, frame, e) from None
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
            seek_frame(f, info, start_frame)
        for first in range(int(start_frame), stop - block_frames + 1, block_frames):
            start_s = first / info.sample_rate_hz
            # frames x channels transposed: the layout of the interleaved file, which the front end's FFTs have
            # always been given (a C-ordered block changes their last digits)
            block = np.empty((block_frames, info.channels), dtype=block_dtype(info, compact)).T
            read_frames_into(f, raw, block, info, start_s)
            if info.sample_format.startswith("float"):
                check_block(block, info.path, start_s)
            yield block
