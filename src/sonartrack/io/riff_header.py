"""The header of a RIFF/WAVE, RF64 or W64 recording checked against itself and against the file: not believed.

Our own walk of the chunks (io/wav_blocks.py reads the samples through libsndfile, which takes a header's fields
as given) reads the ``fmt`` fields, the data size the header states (the ``data`` chunk's size, or for RF64 the
``ds64`` chunk's 64-bit data size) and the Broadcast WAV ``bext`` start time, and refuses, in one line naming the
field and the fix:

- a block align that is not channels x bytes per sample, or a byte rate that is not sample rate x block align
  (the fields contradict each other: which one is wrong cannot be told, and a reader that believes the wrong one
  reads noise or a wrong time axis);
- a stated data size shorter than the data (the bytes after the stated end are neither a chunk nor zero padding):
  a reader would silently cut the recording to the stated length; a stated size longer than the file is the
  truncated copy that io/wav_blocks.py refuses by the frames libsndfile finds.

Layouts: RIFF (Microsoft "Multimedia Programming Interface and Data Specifications 1.0", 1991: 8-byte chunk
headers, bodies padded to even length), RF64 (EBU Tech 3306: ``ds64`` holds the 64-bit RIFF and data sizes, the
32-bit fields read 0xFFFFFFFF), Sony Wave64 (16-byte GUID ids whose first 4 bytes spell the RIFF id, 64-bit sizes
that include the 24-byte chunk header, chunks on 8-byte boundaries).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

from sonartrack.core.errors import InputError, require

#: how to make a recording this reader takes
CONVERT = "convert it to 16/24-bit PCM or 32-bit float WAV or FLAC (e.g. sox in.wav -b 24 out.wav, or ffmpeg -i " \
          "in.wav -c:a pcm_f32le out.wav)"
W64_RIFF = b"riff\x2e\x91\xcf\x11\xa5\xd6\x28\xdb\x04\xc1\x00\x00"
#: bytes after the stated end of the data looked at for zero padding (a recorder's sector fill)
_PAD_PROBE_BYTES = 65536
_REPAIR = "repair the header (e.g. ffmpeg -ignore_length 1 -i in.wav -c:a copy -rf64 auto out.wav)"


@dataclass(frozen=True, slots=True)
class RiffHeader:
    """What the walk found: the data size the header states (bytes), the bext start time (UTC or None), and the
    ``fmt`` block align (bytes per frame; 0 when the file has no fmt chunk before its data)."""

    data_bytes: int
    start_utc: datetime | None
    block_align: int


def read_exact(fh, n: int, path: Path, what: str) -> bytes:
    """``n`` bytes from ``fh``; a short read is a truncated header (one line naming ``what``).

    Parameters
    ----------
    fh : binary file
        Open file, positioned.
    n : int
        Bytes wanted.
    path : Path
        The file, named in the message.
    what : str
        What the bytes are (named in the message).

    Returns
    -------
    bytes
        Exactly ``n`` bytes.
    """
    data = fh.read(n)
    if len(data) < n:
        raise InputError(f"{path}: the WAV header is truncated ({what} cut short): the file is incomplete; copy "
                         "or export it again")
    return data


def _chunks(fh, path: Path, w64: bool, pos: int | None = None):
    """(chunk id, body size, offset of its body) of each chunk from ``pos`` (default: after the RIFF/RF64/W64
    header), in file order (module doc for the layouts)."""
    file_size = path.stat().st_size
    head = 24 if w64 else 8
    pos = (40 if w64 else 12) if pos is None else pos
    while pos + head <= file_size:
        fh.seek(pos)
        raw = read_exact(fh, head, path, "chunk header")
        if w64:
            cid, size = raw[:4], struct.unpack("<Q", raw[16:24])[0] - 24
        else:
            cid, size = struct.unpack("<4sI", raw)
        yield cid, size, pos + head
        step = _padded_end(pos + head, size, w64) - pos
        if step <= 0:
            return
        pos += step


def _padded_end(body: int, size: int, w64: bool) -> int:
    """Offset of the next chunk after a body of ``size`` bytes at ``body`` (RIFF pads to 2 bytes, W64 to 8)."""
    end = body + size
    return end + (-end % 8) if w64 else end + (size & 1)


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


def check_fmt(body: bytes, path: Path) -> int:
    """Check a ``fmt`` chunk's fields against each other; its block align (bytes per frame).

    Parameters
    ----------
    body : bytes
        The fmt chunk's body (at least its first 16 bytes).
    path : Path
        The file, named in the message.

    Returns
    -------
    int
        Block align (bytes); InputError when it is not channels x ceil(bits / 8), or when the byte rate is not
        sample rate x block align.
    """
    require(len(body) >= 16, f"{path}: the fmt chunk is {len(body)} bytes, fewer than its 16 bytes of fields: the "
                             "header is damaged; export the file again")
    _tag, channels, rate, byte_rate, align, bits = struct.unpack("<HHIIHH", body[:16])
    if channels == 0 or bits == 0:
        return align  # nothing to compare against; libsndfile refuses such a header itself
    expected = channels * -(-bits // 8)
    require(align == expected, f"{path}: the fmt chunk's block align is {align} for {channels} channels of {bits} "
                               f"bits: expected {expected} bytes (channels x bytes per sample); the header is damaged: "
                               "export the file again from the recorder or the program that wrote it")
    require(byte_rate == rate * align, f"{path}: the fmt chunk's byte rate is {byte_rate} bytes/s for {rate} Hz "
                                       f"x {align} bytes per frame: expected {rate * align}; the header contradicts "
                                       "itself (is the sample rate right?): export the file again")
    return align


def _is_chunk_or_padding(fh, pos: int, file_size: int, w64: bool) -> bool:
    """Whether the bytes from ``pos`` to the end of the file may follow a data chunk: nothing, fewer bytes than a
    chunk header, zero padding, or a chunk (a printable 4-character id and a size that fits in the file)."""
    head = 24 if w64 else 8
    if file_size - pos < head:
        return True
    fh.seek(pos)
    probe = fh.read(min(file_size - pos, _PAD_PROBE_BYTES))
    if not probe.strip(b"\0"):
        return True
    cid = probe[:4]
    size = struct.unpack("<Q", probe[16:24])[0] - 24 if w64 else struct.unpack("<I", probe[4:8])[0]
    return all(32 <= c < 127 for c in cid) and 0 <= size <= file_size - pos - head


def _check_data_size(fh, p: Path, w64: bool, body: int, stated: int, align: int, field: str) -> None:
    """Refuse a stated data size shorter than the data that follows it (module doc)."""
    file_size = p.stat().st_size
    if body + stated >= file_size or _is_chunk_or_padding(fh, _padded_end(body, stated, w64), file_size, w64):
        return
    per = max(align, 1)
    raise InputError(f"{p}: the header ({field}) states {stated // per} frames of data but the data runs on to the "
                     f"end of the file, {(file_size - body) // per} frames: the header is wrong and would cut the "
                     f"recording short; {_REPAIR}")


def walk_riff(p: Path, rate: float) -> RiffHeader | None:
    """Check and read the header of a RIFF, RF64 or W64 file (module doc); None for a FLAC.

    Parameters
    ----------
    p : Path
        The recording.
    rate : float
        Its sample rate (Hz), for the bext TimeReference.

    Returns
    -------
    RiffHeader or None
        Stated data size, bext start, block align; InputError on a header that contradicts itself or the file.
    """
    with open(p, "rb") as fh:
        head = fh.read(40)
        if head[:4] == b"fLaC":
            return None
        w64 = head[:16] == W64_RIFF
        require(w64 or (len(head) >= 12 and head[:4] in (b"RIFF", b"RF64") and head[8:12] == b"WAVE"),
                f"{p} is not a RIFF/WAVE, RF64, W64 or FLAC recording (starts with {head[:4]!r}): {CONVERT}")
        ds64, start, time_ref, align = None, None, 0, 0
        for cid, size, body in _chunks(fh, p, w64):
            if cid == b"ds64":
                ds64 = struct.unpack("<Q", read_exact(fh, 16, p, "ds64 chunk")[8:16])[0]
            elif cid == b"fmt ":
                align = check_fmt(fh.read(min(size, 40)), p)
            elif cid == b"bext":
                raw = fh.read(min(size, 346))
                start, time_ref = _bext_start(raw), (struct.unpack("<Q", raw[338:346])[0] if len(raw) >= 346 else 0)
            elif cid == b"data":
                rf64 = head[:4] == b"RF64" and size == 0xFFFFFFFF and ds64 is not None
                stated = ds64 if rf64 else size
                _check_data_size(fh, p, w64, body, stated, align, "ds64 data size" if rf64 else "data chunk size")
                return RiffHeader(int(stated), _refine_start(start, time_ref, rate), align)
    raise InputError(f"{p}: no data chunk: the file is truncated or empty; export the recording again")
