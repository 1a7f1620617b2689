"""Streaming reader of N-channel WAV recordings: fixed-size blocks, memory independent of the file's length.

The RIFF/WAVE chunks are parsed here (no scipy, no memory map: mapped pages count in the resident set of a
long recording). Accepted sample formats: PCM (tag 1) 16 or 32 bit integer, IEEE float (tag 3) 32 or 64 bit,
and WAVE_FORMAT_EXTENSIBLE (tag 0xFFFE) whose sub-format GUID is PCM or IEEE float with those widths.
Unknown chunks (LIST, fact, ...) are skipped; a chunk of odd size is followed by one pad byte (RIFF rule).
Integers are scaled to [-1, 1): x / 2^(bits - 1). Each block is read with ``readinto`` into one reused
byte buffer, so reading a recording of any length holds about two blocks in memory.

Refused with a one-line :class:`InputError` naming the file and the fix: a missing file or a folder, a file
that is not RIFF/WAVE, a truncated header, 8- or 24-bit samples, compressed formats, no frames, and a data
chunk shorter than its header states (a truncated copy: the frames present are never read silently).
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require

#: (format tag, bits per sample) -> (sample format name, numpy dtype, scale to [-1, 1))
_FORMATS = {
    (1, 16): ("int16", "<i2", 1.0 / 32768.0),
    (1, 32): ("int32", "<i4", 1.0 / 2147483648.0),
    (3, 32): ("float32", "<f4", 1.0),
    (3, 64): ("float64", "<f8", 1.0),
}
_DTYPES = {name: (dtype, scale) for name, dtype, scale in _FORMATS.values()}
#: the tail shared by the KSDATAFORMAT_SUBTYPE GUIDs (bytes 2..15); bytes 0..1 carry the format tag
_GUID_TAIL = bytes.fromhex("000000001000800000aa00389b71")
_EXTENSIBLE = 0xFFFE
_CONVERT = "convert it to 16-bit PCM or 32-bit float WAV (e.g. sox in.wav -b 16 out.wav, or ffmpeg -i in.wav " \
           "-c:a pcm_f32le out.wav)"


#: a float sample beyond this is no pressure in pascals nor a normalised sample (as io/wav.py)
MAX_FLOAT_SAMPLE = 1e15


@dataclass(frozen=True)
class WavInfo:
    """What the header of a WAV file says: channels, sample rate (Hz), frames, sample format, byte offset of
    the first sample."""

    path: Path
    channels: int
    sample_rate_hz: float
    frames: int
    sample_format: str
    data_offset: int

    @property
    def duration_s(self) -> float:
        """Length of the recording (s)."""
        return self.frames / self.sample_rate_hz

    @property
    def bytes_per_frame(self) -> int:
        return self.channels * np.dtype(_DTYPES[self.sample_format][0]).itemsize


def _read_exact(fh, n: int, path: Path, what: str) -> bytes:
    data = fh.read(n)
    if len(data) < n:
        raise InputError(f"{path}: the WAV header is truncated ({what} cut short): the file is incomplete; copy "
                         "or export it again")
    return data


def _format_tag(fmt: bytes, path: Path) -> tuple[int, int, int, int]:
    """(format tag, channels, sample rate, bits) of a fmt chunk; the sub-format of WAVE_FORMAT_EXTENSIBLE."""
    require(len(fmt) >= 16, f"{path}: the WAV fmt chunk is {len(fmt)} bytes (< 16): the header is damaged; export "
                            "the recording again")
    tag, channels, rate, _, _, bits = struct.unpack("<HHIIHH", fmt[:16])
    if tag == _EXTENSIBLE:
        require(len(fmt) >= 40, f"{path}: the WAVE_FORMAT_EXTENSIBLE fmt chunk is {len(fmt)} bytes (< 40): the "
                                f"header is damaged; {_CONVERT}")
        guid = fmt[24:40]
        require(guid[2:] == _GUID_TAIL, f"{path}: unknown WAVE_FORMAT_EXTENSIBLE sub-format {guid.hex()}: {_CONVERT}")
        tag = struct.unpack("<H", guid[:2])[0]
    return tag, channels, rate, bits


def _sample_format(tag: int, bits: int, path: Path) -> str:
    if (tag, bits) in _FORMATS:
        return _FORMATS[(tag, bits)][0]
    if tag == 1 and bits in (8, 24):
        raise InputError(f"{path}: {bits}-bit PCM samples are not supported: {_CONVERT}")
    kind = {1: "PCM", 3: "float"}.get(tag, f"format tag {tag} (compressed?)")
    raise InputError(f"{path}: {bits}-bit {kind} samples are not supported: {_CONVERT}")


def _chunks(fh, path: Path, file_size: int):
    """(chunk id, size, offset of its body) of each chunk after the RIFF/WAVE header, in file order."""
    pos = 12
    while pos + 8 <= file_size:
        fh.seek(pos)
        cid, size = struct.unpack("<4sI", _read_exact(fh, 8, path, "chunk header"))
        yield cid, size, pos + 8
        pos += 8 + size + (size & 1)


def _check_path(path) -> Path:
    p = Path(path)
    require(p.exists(), f"recording not found: {p}: check the path (--wav)")
    require(p.is_file(), f"{p} is a directory, not a WAV recording: give the .wav file inside it")
    return p


def read_wav_info(path) -> WavInfo:
    """Parse the RIFF/WAVE header of ``path`` (module doc); InputError on anything unreadable."""
    p = _check_path(path)
    file_size = p.stat().st_size
    with open(p, "rb") as fh:
        head = fh.read(12)
        require(not (len(head) < 12 and head[:4] == b"RIFF"[: len(head)]),
                f"{p}: the WAV header is truncated ({len(head)} bytes): the file is incomplete; export it again")
        require(len(head) == 12 and head[:4] == b"RIFF" and head[8:12] == b"WAVE",
                f"{p} is not a RIFF/WAVE file (starts with {head[:4]!r}): give a WAV recording ({_CONVERT})")
        fmt, data = None, None
        for cid, size, body in _chunks(fh, p, file_size):
            if cid == b"fmt ":
                fmt = _read_exact(fh, size, p, "fmt chunk")
            elif cid == b"data":
                data = (size, body)
                break
    require(fmt is not None, f"{p}: no fmt chunk before the data: the WAV header is damaged or truncated; export "
                             "the recording again")
    require(data is not None, f"{p}: no data chunk: the WAV file is truncated or empty; export the recording again")
    tag, channels, rate, bits = _format_tag(fmt, p)
    sample_format = _sample_format(tag, bits, p)
    require(channels >= 1 and rate > 0, f"{p}: the header states {channels} channels at {rate} Hz: the header is "
                                        "damaged; export the recording again")
    size, offset = data
    frame_bytes = channels * bits // 8
    frames = size // frame_bytes
    require(frames > 0, f"{p} holds no samples (empty data chunk): record or export a non-empty file")
    present = (file_size - offset) // frame_bytes
    require(present >= frames, f"{p} is truncated: the header states {frames} frames ({frames / rate:.1f} s) but "
                               f"only {present} are present ({present / rate:.1f} s): copy the file again, or "
                               "repair its header (e.g. sox --ignore-length in.wav out.wav)")
    return WavInfo(p, int(channels), float(rate), int(frames), sample_format, int(offset))


def iter_wav_blocks(info_or_path, block_frames: int, *, start_frame: int = 0,
                    stop_frame: int | None = None) -> Iterator[np.ndarray]:
    """Blocks of ``block_frames`` frames as float64 arrays (channels, block_frames), integers scaled to [-1, 1).

    Frames ``start_frame`` .. ``stop_frame`` (default: the end); a partial last block (fewer than
    ``block_frames`` frames left) is dropped, as the bearing estimator drops a partial last window. Each block
    is read with seek + readinto into one reused buffer: memory does not grow with the file. A block holding
    NaN or inf raises InputError naming its start time (s)."""
    info = info_or_path if isinstance(info_or_path, WavInfo) else read_wav_info(info_or_path)
    block_frames = int(block_frames)
    require(block_frames >= 1, f"block_frames must be >= 1, got {block_frames}")
    stop = info.frames if stop_frame is None else min(int(stop_frame), info.frames)
    require(0 <= start_frame <= stop, f"start_frame {start_frame} must lie in 0..{stop}")
    dtype, scale = _DTYPES[info.sample_format]
    bpf = info.bytes_per_frame
    raw = bytearray(block_frames * bpf)
    view = np.frombuffer(raw, dtype=dtype).reshape(block_frames, info.channels)
    is_float = info.sample_format.startswith("float")
    with open(info.path, "rb") as fh:
        for first in range(int(start_frame), stop - block_frames + 1, block_frames):
            fh.seek(info.data_offset + first * bpf)
            if fh.readinto(raw) != len(raw):
                raise InputError(f"{info.path} was truncated while being read (at {first / info.sample_rate_hz:.1f}"
                                 " s): copy the file again")
            block = view.T.astype(np.float64)
            if scale != 1.0:
                block *= scale
            if is_float and not np.isfinite(block).all():
                raise InputError(f"{info.path} holds NaN/inf samples in the block starting at "
                                 f"{first / info.sample_rate_hz:.3f} s: repair or cut that part of the recording")
            if is_float and np.abs(block).max() > MAX_FLOAT_SAMPLE:
                raise InputError(f"{info.path} holds samples of magnitude {np.abs(block).max():.3g} in the block "
                                 f"starting at {first / info.sample_rate_hz:.3f} s: no pressure (Pa) or normalised "
                                 "sample is that large; the file is corrupt or not audio")
            yield block
