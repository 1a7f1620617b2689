"""A FLAC file's STREAMINFO checked against its frame headers: the header is compared, not believed.

Every FLAC frame starts with a header of its own (RFC 9639 "Free Lossless Audio Codec", 2024, section 9.1):
sync code 0xFFF8 (fixed block size) or 0xFFF9 (variable), a block-size code, a sample-rate code, a channel code,
a bit-depth code, the frame number (fixed) or first sample number (variable) in UTF-8-like coding, the
uncommon block size and rate where the codes say so, and a CRC-8 (polynomial x^8 + x^2 + x + 1) over the
header. libsndfile believes STREAMINFO: a rate of 8 kHz on 4 kHz frames halves every time, a total of half the
samples stops the reader half-way, a total of 0 (allowed: "unknown", a stream) breaks its seek to the end. So:

- the first frame's rate, channels and bit depth are compared with STREAMINFO's (a code meaning "see
  STREAMINFO" compares nothing); a contradiction is refused naming both values;
- the frames' own length is the last frame's first sample plus its block size: the last header in the file's tail
  that passes its CRC-8 and agrees with the first frame (blocking, rate, channels, bits). A total that
  disagrees is refused (shorter: the header would cut the recording; longer: the file is truncated); a total of
  0 takes the frames' own length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sonartrack.core.errors import InputError, require

_RATES = {1: 88200, 2: 176400, 3: 192000, 4: 8000, 5: 16000, 6: 22050, 7: 24000, 8: 32000, 9: 44100, 10: 48000,
          11: 96000}
_BITS = {1: 8, 2: 12, 4: 16, 5: 20, 6: 24, 7: 32}
#: bytes at the end of the file searched for the last frame header when STREAMINFO gives no largest frame
_TAIL_BYTES = 4 << 20
_REENCODE = "re-encode it from its frames (e.g. ffmpeg -i in.flac -c:a flac out.flac) or export it again"


def _crc8_table() -> tuple[int, ...]:
    table = []
    for n in range(256):
        c = n
        for _ in range(8):
            c = ((c << 1) ^ 0x07) & 0xFF if c & 0x80 else (c << 1) & 0xFF
        table.append(c)
    return tuple(table)


_CRC8 = _crc8_table()


def crc8(data: bytes) -> int:
    """CRC-8 of a FLAC frame header (polynomial 0x07, initial value 0; RFC 9639 section 9.1.8).

    Parameters
    ----------
    data : bytes
        The header up to, not including, its CRC byte.

    Returns
    -------
    int
        0..255.
    """
    c = 0
    for b in data:
        c = _CRC8[c ^ b]
    return c


@dataclass(frozen=True, slots=True)
class StreamInfo:
    """STREAMINFO (RFC 9639 section 8.2): rate (Hz), channels, bits per sample, total frames (0: unknown), the
    largest frame (bytes, 0: unknown), and where the first audio frame starts (byte offset)."""

    sample_rate_hz: int
    channels: int
    bits: int
    total_frames: int
    max_frame_bytes: int
    audio_offset: int


@dataclass(frozen=True, slots=True)
class FrameHeader:
    """One frame header: its offset, variable blocking, block size (frames), rate (Hz; None: see STREAMINFO),
    channels, bits (None: see STREAMINFO) and coded number (frame number, or first sample if variable)."""

    offset: int
    variable: bool
    block_frames: int
    sample_rate_hz: int | None
    channels: int
    bits: int | None
    number: int


def read_streaminfo(fh, path: Path) -> StreamInfo:
    """STREAMINFO and the offset of the first frame (after the last metadata block).

    Parameters
    ----------
    fh : binary file
        The open FLAC file (read from its start).
    path : Path
        The file, named in messages.

    Returns
    -------
    StreamInfo
        InputError when the metadata is cut short or STREAMINFO is missing.
    """
    fh.seek(0)
    head = fh.read(42)
    require(len(head) == 42 and head[:4] == b"fLaC" and head[4] & 0x7F == 0,
            f"{path}: the FLAC header is truncated or has no STREAMINFO: the file is incomplete; export it again")
    si = head[8:42]
    max_frame = int.from_bytes(si[7:10], "big")
    packed = int.from_bytes(si[10:18], "big")
    rate, channels, bits = packed >> 44, ((packed >> 41) & 7) + 1, ((packed >> 36) & 31) + 1
    total = packed & (2**36 - 1)
    pos, last = 4, False
    while not last:
        fh.seek(pos)
        block = fh.read(4)
        require(len(block) == 4, f"{path}: the FLAC metadata is truncated: the file is incomplete; export it again")
        last, pos = bool(block[0] & 0x80), pos + 4 + int.from_bytes(block[1:4], "big")
    return StreamInfo(rate, channels, bits, total, max_frame, pos)


def _coded_number(buf: bytes, j: int) -> tuple[int, int] | None:
    """The UTF-8-like coded frame or sample number at ``buf[j]`` (1 to 7 bytes) and the offset after it."""
    b = buf[j]
    extra = next((n for n, mask in enumerate((0x80, 0xE0, 0xF0, 0xF8, 0xFC, 0xFE, 0xFF)) if b & mask ==
                  (0x00, 0xC0, 0xE0, 0xF0, 0xF8, 0xFC, 0xFE)[n]), None)
    if extra is None or j + 1 + extra > len(buf):
        return None
    value = b & (0x7F >> extra) if extra else b
    for c in buf[j + 1: j + 1 + extra]:
        if c & 0xC0 != 0x80:
            return None
        value = (value << 6) | (c & 0x3F)
    return value, j + 1 + extra


def _uncommon(buf: bytes, j: int, code: int, kind: str) -> tuple[int | None, int] | None:
    """Block size or rate from its code, reading the 8 or 16 uncommon bits at ``j`` where the code says so."""
    if kind == "block":
        if code in (6, 7):
            n = 1 if code == 6 else 2
            return (int.from_bytes(buf[j:j + n], "big") + 1, j + n) if j + n <= len(buf) else None
        return (192 if code == 1 else 144 << code if code <= 5 else 1 << code), j
    if code in (12, 13, 14):
        n = 1 if code == 12 else 2
        if j + n > len(buf):
            return None
        v = int.from_bytes(buf[j:j + n], "big")
        return (v * 1000 if code == 12 else v if code == 13 else v * 10), j + n
    return _RATES.get(code), j


def parse_frame_header(buf: bytes, i: int, base: int = 0) -> FrameHeader | None:
    """The frame header at ``buf[i]`` if one is there (sync code, valid codes and CRC-8), else None.

    Parameters
    ----------
    buf : bytes
        Bytes of the file.
    i : int
        Offset of the candidate in ``buf``.
    base : int
        File offset of ``buf[0]`` (the header's :attr:`FrameHeader.offset` is ``base + i``).

    Returns
    -------
    FrameHeader or None
    """
    if i + 6 > len(buf) or buf[i] != 0xFF or buf[i + 1] & 0xFE != 0xF8:
        return None
    bs_code, rate_code, ch_code, bits_code = buf[i + 2] >> 4, buf[i + 2] & 15, buf[i + 3] >> 4, (buf[i + 3] >> 1) & 7
    if bs_code == 0 or rate_code == 15 or ch_code > 10 or bits_code == 3 or buf[i + 3] & 1:
        return None
    number = _coded_number(buf, i + 4)
    block = number and _uncommon(buf, number[1], bs_code, "block")
    rate = block and _uncommon(buf, block[1], rate_code, "rate")
    if not rate or rate[1] >= len(buf) or crc8(buf[i:rate[1]]) != buf[rate[1]]:
        return None
    return FrameHeader(base + i, bool(buf[i + 1] & 1), block[0], rate[0], ch_code + 1 if ch_code < 8 else 2,
                       _BITS.get(bits_code), number[0])


def _last_frame(fh, stream: StreamInfo, first: FrameHeader, file_size: int) -> FrameHeader | None:
    """The last frame header in the file's tail that agrees with the first frame (module doc); None if none."""
    tail = max(2 * stream.max_frame_bytes + 64, 1 << 20) if stream.max_frame_bytes else _TAIL_BYTES
    base = max(first.offset, file_size - tail)
    fh.seek(base)
    buf = fh.read(file_size - base)
    i = len(buf)
    while (i := buf.rfind(b"\xff", 0, i)) >= 0:
        h = parse_frame_header(buf, i, base)
        if h and (h.variable, h.sample_rate_hz, h.channels, h.bits) == (first.variable, first.sample_rate_hz,
                                                                           first.channels, first.bits):
            return h
    return None


@dataclass(frozen=True, slots=True)
class FlacLayout:
    """STREAMINFO, the first frame header (None: none found after the metadata) and the frames the data holds
    by its last frame header (None: not found)."""

    stream: StreamInfo
    first: FrameHeader | None
    data_frames: int | None


def read_flac_layout(p: Path) -> FlacLayout:
    """STREAMINFO, the first frame header and the frames' own length of the FLAC file ``p`` (module doc).

    Returns
    -------
    FlacLayout
    """
    file_size = p.stat().st_size
    with open(p, "rb") as fh:
        stream = read_streaminfo(fh, p)
        fh.seek(stream.audio_offset)
        first = parse_frame_header(fh.read(32), 0, stream.audio_offset)
        last = _last_frame(fh, stream, first, file_size) if first else None
    if first is None:
        return FlacLayout(stream, None, None)
    if last is None:
        return FlacLayout(stream, first, None)
    start = last.number if last.variable else last.number * first.block_frames
    return FlacLayout(stream, first, start + last.block_frames)


def check_flac(p: Path) -> tuple[int, int | None]:
    """Compare STREAMINFO with the frame headers (module doc).

    Parameters
    ----------
    p : Path
        A FLAC file.

    Returns
    -------
    stated : int
        Frames STREAMINFO states (0: unknown).
    data_frames : int or None
        Frames by the last frame header (None where no header was found; the caller decodes then); InputError on
        a contradiction.
    """
    layout = read_flac_layout(p)
    s, f = layout.stream, layout.first
    if f is not None:
        for what, unit, head, frame in (("sample rate", " Hz", s.sample_rate_hz, f.sample_rate_hz),
                                        ("channel count", "", s.channels, f.channels),
                                        ("bit depth", " bits", s.bits, f.bits)):
            require(frame is None or frame == head,
                    f"{p}: the FLAC header (STREAMINFO) states a {what} of {head}{unit} but its first frame's header "
                    f"states {frame}{unit}: the header contradicts the data; export the recording again (with the "
                    f"{what} of its frames, {frame}{unit})")
    n = layout.data_frames
    if s.total_frames and n is not None and n != s.total_frames:
        rate = float(s.sample_rate_hz)
        if n > s.total_frames:
            raise InputError(f"{p}: the FLAC header (STREAMINFO) states {s.total_frames} frames "
                             f"({s.total_frames / rate:.1f} s) but its frames run on to {n} ({n / rate:.1f} s): the "
                             f"header would cut the recording short; {_REENCODE}")
        raise InputError(f"{p} is truncated: the FLAC header (STREAMINFO) states {s.total_frames} frames "
                         f"({s.total_frames / rate:.1f} s) but its frames end at {n} ({n / rate:.1f} s): copy the file "
                         "again")
    return s.total_frames, n
