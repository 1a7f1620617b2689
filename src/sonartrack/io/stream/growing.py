"""A recording still being written, read as it grows: its header walked as far as the data chunk, then the whole
frames present, whatever length the header states.

A recorder writes a WAV-family file's header first, with a data size of 0, 0xFFFFFFFF or a guess, and corrects
it when it closes the file. io/wav_blocks.py refuses a file whose header disagrees with its data (rightly, for a
finished file); a file being written is read here instead: the chunks of the RIFF, RF64 (EBU Tech 3306) or Sony
Wave64 header are walked (the layouts of io/riff_header.py; ``fmt`` checked by its :func:`check_fmt`) until the
``data`` chunk's first byte, and the frames are the whole ``block_align``-byte frames between it and the end of
the file. A header still incomplete is waited for (:meth:`GrowingWav.open` returns None). When the file is
finished (a newer one appeared, or the folder fell idle) and its header states a data size that ends before the
file does, followed by a chunk or padding (io/riff_header.py's rule), the frames end there; otherwise every
whole frame present is read. FLAC cannot be decoded before it is complete: :mod:`folder` reads a FLAC file once
it is finished, through io/wav_blocks.py.

Samples: PCM 16/24/32-bit k / 2^(bits - 1) and IEEE float 32/64-bit as stored (io/wav_blocks.py's scaling),
returned as float32 (n, channels).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.io.riff_header import W64_RIFF, _bext_start, _is_chunk_or_padding, check_fmt
from sonartrack.io.stream.frames import decode_samples

#: (format tag, bits) -> sample format; tag 0xFFFE (extensible) takes the sub-format GUID's first two bytes
_FORMATS = {(1, 16): "int16", (1, 24): "int24", (1, 32): "int32", (3, 32): "float32", (3, 64): "float64"}
#: longest header walked (bytes) before the data chunk must have begun
MAX_HEADER_BYTES = 1 << 20
#: RIFF / RF64 data sizes that state nothing (a file being written)
_UNSTATED = (0, 0xFFFFFFFF)


@dataclass(frozen=True, slots=True)
class GrowingWav:
    """A WAV-family file's layout: channels, rate (Hz), sample format, bytes per frame, offset of the first data
    byte, the data size its header states (None when it states none), its bext start (UTC or None), W64 or not."""

    path: Path
    channels: int
    rate_hz: float
    sample_format: str
    block_align: int
    data_offset: int
    stated_bytes: int | None
    start_utc: datetime | None
    w64: bool

    @classmethod
    def open(cls, path: Path) -> GrowingWav | None:
        """The layout of ``path`` once its header is complete (None before); InputError for a file that is none of
        the formats or whose header contradicts itself.

        Parameters
        ----------
        path : Path
            A .wav, .rf64, .w64 or .bwf file, complete or being written.

        Returns
        -------
        GrowingWav or None
            None while the header is still being written.
        """
        with open(path, "rb") as fh:
            head = fh.read(40)
            if len(head) < 12:
                return None
            w64 = head[:16] == W64_RIFF
            if not (w64 or (head[:4] in (b"RIFF", b"RF64") and head[8:12] == b"WAVE")):
                raise InputError(f"{path} is not a RIFF/WAVE, RF64 or W64 recording (starts with {head[:4]!r})")
            return _walk(fh, path, w64, head[:4] == b"RF64")

    def frames_present(self, finished: bool) -> int:
        """Whole frames in the file now; for a finished file, up to the stated end when chunks follow it.

        Parameters
        ----------
        finished : bool
            The writer is done with the file.

        Returns
        -------
        int
            Frames readable.
        """
        size = self.path.stat().st_size
        present = max(size - self.data_offset, 0)
        stated = self.stated_bytes
        if finished and stated is not None and stated < present:
            with open(self.path, "rb") as fh:
                end = self.data_offset + stated
                if _is_chunk_or_padding(fh, end + (-end % 8 if self.w64 else stated & 1), size, self.w64):
                    present = stated
        return present // self.block_align

    def read(self, first: int, n: int) -> np.ndarray:
        """Frames ``first`` .. ``first + n - 1`` as float32 (n, channels), scaled as io/wav_blocks.py scales.

        Parameters
        ----------
        first, n : int
            First frame and number of frames (all present).

        Returns
        -------
        ndarray of float32, shape (n, channels)
        """
        with open(self.path, "rb") as fh:
            fh.seek(self.data_offset + first * self.block_align)
            raw = fh.read(n * self.block_align)
        if len(raw) < n * self.block_align:
            raise InputError(f"{self.path} shrank while being read: the recorder rewrote it")
        fmt = self.sample_format
        if fmt in ("int16", "int24", "float32"):
            return decode_samples(raw, n, self.channels, fmt)
        k = np.frombuffer(raw, "<i4" if fmt == "int32" else "<f8").reshape(n, self.channels)
        return (k * (2.0**-31 if fmt == "int32" else 1.0)).astype(np.float32)


def _walk(fh, path: Path, w64: bool, rf64: bool) -> GrowingWav | None:
    """Chunks from the first until the data chunk's body (module doc); None where the file ends first."""
    size = path.stat().st_size
    head = 24 if w64 else 8
    pos, fmt, ds64, start = (40 if w64 else 12), None, None, None
    while pos + head <= min(size, MAX_HEADER_BYTES):
        fh.seek(pos)
        raw = fh.read(head)
        cid, body_bytes = (raw[:4], struct.unpack("<Q", raw[16:24])[0] - 24) if w64 else struct.unpack("<4sI", raw)
        body = pos + head
        if cid == b"data":
            if fmt is None:
                raise InputError(f"{path}: the data chunk comes before any fmt chunk: the header is damaged")
            stated = ds64 if (rf64 and body_bytes == 0xFFFFFFFF) else body_bytes
            stated = None if (stated in _UNSTATED and not w64) or stated is None or stated <= 0 else int(stated)
            return GrowingWav(path, fmt[0], float(fmt[1]), fmt[2], fmt[3], body, stated, start, w64)
        if body + body_bytes > size:
            return None  # a chunk before the data still being written
        chunk = fh.read(min(body_bytes, 400))
        if cid == b"fmt ":
            fmt = _fmt(chunk, path)
        elif cid == b"ds64" and len(chunk) >= 16:
            ds64 = struct.unpack("<Q", chunk[8:16])[0]
        elif cid == b"bext":
            start = _bext_start(chunk)
        end = body + body_bytes
        pos = end + (-end % 8 if w64 else body_bytes & 1)
    if pos + head > MAX_HEADER_BYTES:
        raise InputError(f"{path}: no data chunk in its first {MAX_HEADER_BYTES} bytes: not a recording")
    return None


def _fmt(body: bytes, path: Path) -> tuple[int, int, str, int]:
    """(channels, rate, sample format, block align) of a fmt chunk, checked by io/riff_header.py."""
    align = check_fmt(body, path)
    tag, channels, rate, _, _, bits = struct.unpack("<HHIIHH", body[:16])
    if tag == 0xFFFE and len(body) >= 26:
        tag = struct.unpack("<H", body[24:26])[0]
    fmt = _FORMATS.get((tag, bits))
    if fmt is None or channels == 0:
        raise InputError(f"{path}: format tag {tag} with {bits}-bit samples and {channels} channels is not read live "
                         "(give 16/24/32-bit PCM or 32/64-bit float)")
    return channels, rate, fmt, align
