"""The TCP framing of a sample stream: a header frame, data frames of sample blocks, an end frame; each frame
checked (magic, version, bounded length, CRC-32, sane fields) by an incremental decoder that never dies on bad bytes.

Byte layout (all integers little-endian). Every frame::

    offset  size  field
    0       4     magic b"SNTK"
    4       1     version (1)
    5       1     kind: 1 header, 2 data, 3 end of stream, 4 ping
    6       2     reserved (0)
    8       4     body length L (uint32; at most MAX_BODY_BYTES)
    12      L     body
    12+L    4     CRC-32 (zlib/IEEE 802.3 polynomial) of bytes 0 .. 12+L-1

Header body (L = 28)::

    0   2  channels (uint16, 1..1024)
    2   1  sample format: 1 int16, 2 int24, 3 float32
    3   1  reserved (0)
    4   8  sample rate (float64, Hz, 100 .. 1e6)
    12  8  UTC time of sample index 0 (int64, microseconds since 1970-01-01T00:00:00Z)
    20  8  full-scale voltage of integer samples (float64, V; NaN: not stated)

Data body (L = 12 + n x channels x bytes per sample)::

    0   8  first sample index (uint64, samples since the header's start)
    8   4  n, frames in the block (uint32, 1 .. MAX_BLOCK_FRAMES)
    12  .  samples, frame after frame, each frame channel 1 .. channels: int16, int24 (3-byte two's complement) or
           float32 (IEEE 754)

End body (L = 8): the index one past the last sample sent (uint64). A recorder that stops for good sends it;
a connection that drops without it is a disconnect (the source reconnects).

Ping body (L = 48 + 8 n x channels), an active sonar's ping: its listening window as complex baseband, sent when
the window is complete (``sonartrack simulate --kind active --stream``; channels are the header's; the header's rate
and sample format are the stream's and do not apply to pings)::

    0   4  ping number (uint32, from 1)
    4   4  n, samples per channel (uint32, 1 .. MAX_BLOCK_FRAMES)
    8   8  transmit time (float64, s after the header's start)
    16  8  baseband sample rate (float64, Hz, 100 .. 1e6)
    24  8  carrier frequency (float64, Hz)
    32  8  bandwidth (float64, Hz; 0: a CW pulse, else an LFM sweep)
    40  8  pulse length (float64, s)
    48  .  samples, complex64 (real then imaginary float32), channel after channel: (channels, n) as a ping file
           of systems/active holds them

A stream may carry pings alone (an active sonar) or between the data frames of a passive stream.

Integers are read as passive's file reader reads them, k / 2^(bits - 1) (io/wav_blocks.py), and written as
round(x 2^(bits - 1)) clipped to the integer range (io/recording_writer.py's rule); float32 is sent as is.

The decoder (:class:`FrameDecoder`) is fed bytes as they arrive and returns what they completed: a
:class:`~sonartrack.io.stream.types.StreamHeader`, a :class:`~sonartrack.io.stream.types.SampleBlock`, a
:class:`StreamEnd`, or a ``StreamEvent("bad_frame", ...)`` naming what was wrong. After a bad frame it resyncs on
the next magic; it never allocates from a length it has not bounded (a body longer than MAX_BODY_BYTES is a bad
frame, not a wait), so a hostile peer cannot make it hold more than one largest frame.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.stream.types import SAMPLE_FORMATS, PingBlock, SampleBlock, StreamEvent, StreamHeader

MAGIC = b"SNTK"
VERSION = 1
KIND_HEADER, KIND_DATA, KIND_END, KIND_PING = 1, 2, 3, 4
#: bytes of a frame's fixed prefix (magic .. body length) and of its CRC
PREFIX_BYTES, CRC_BYTES = 12, 4
#: the largest body taken (bytes): 16 MiB, a 1 s block of 1024 channels of float32 at 4 kHz
MAX_BODY_BYTES = 1 << 24
#: the most frames in one data block
MAX_BLOCK_FRAMES = 1 << 20
#: channels, sample rate (Hz) and full-scale voltage (V) a header may state
MAX_CHANNELS, MIN_RATE_HZ, MAX_RATE_HZ, MAX_FULL_SCALE_V = 1024, 100.0, 1e6, 1e4
#: a float sample beyond this is no pressure nor a normalised sample (io/wav_blocks.py's MAX_FLOAT_SAMPLE)
MAX_FLOAT_SAMPLE = 1e15
#: sample format -> (code on the wire, bytes per sample)
FORMAT_CODES = {"int16": (1, 2), "int24": (2, 3), "float32": (3, 4)}
_FORMAT_OF_CODE = {code: name for name, (code, _) in FORMAT_CODES.items()}
_HEADER = struct.Struct("<HBBdqd")
_DATA = struct.Struct("<QI")
_PING = struct.Struct("<IIddddd")
_PREFIX = struct.Struct("<4sBBHI")
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
#: latest start time taken (a clock that far off is garbage)
_LATEST_US = int((datetime(2200, 1, 1, tzinfo=UTC) - _EPOCH).total_seconds() * 1e6)


@dataclass(frozen=True, slots=True)
class StreamEnd:
    """The recorder's end of stream: ``end_index`` is one past the last sample it sent."""

    end_index: int


def _frame(kind: int, body: bytes) -> bytes:
    head = _PREFIX.pack(MAGIC, VERSION, kind, 0, len(body))
    return head + body + struct.pack("<I", zlib.crc32(body, zlib.crc32(head)))


def check_header(header: StreamHeader) -> None:
    """Refuse a header a stream cannot carry (one line naming the field and the range).

    Parameters
    ----------
    header : StreamHeader
        The stream's description.
    """
    require(1 <= int(header.channels) <= MAX_CHANNELS, f"a stream carries 1..{MAX_CHANNELS} channels, "
                                                       f"not {header.channels}")
    rate = float(header.rate_hz)
    require(math.isfinite(rate) and MIN_RATE_HZ <= rate <= MAX_RATE_HZ,
            f"a stream's sample rate must lie in {MIN_RATE_HZ:g}..{MAX_RATE_HZ:g} Hz, not {rate:g}")
    require(header.sample_format in SAMPLE_FORMATS, f"sample format {header.sample_format!r}: choose one of "
                                                    f"{', '.join(SAMPLE_FORMATS)}")
    require(header.start_utc.tzinfo is not None, "a stream's start_utc must be timezone-aware (UTC)")
    fs = header.full_scale_v
    require(fs is None or (math.isfinite(fs) and 0 < fs <= MAX_FULL_SCALE_V),
            f"full-scale voltage {fs}: give a positive voltage up to {MAX_FULL_SCALE_V:g} V, or none")


def encode_header(header: StreamHeader) -> bytes:
    """The header frame of ``header`` (module doc).

    Parameters
    ----------
    header : StreamHeader
        Channels, rate, sample format, UTC start, full scale.

    Returns
    -------
    bytes
        One frame; InputError for a header outside the ranges a stream carries.
    """
    check_header(header)
    micros = round((header.start_utc - _EPOCH) / timedelta(microseconds=1))
    fs = math.nan if header.full_scale_v is None else float(header.full_scale_v)
    body = _HEADER.pack(int(header.channels), FORMAT_CODES[header.sample_format][0], 0, float(header.rate_hz),
                        micros, fs)
    return _frame(KIND_HEADER, body)


def encode_samples(samples: np.ndarray, sample_format: str) -> bytes:
    """Samples (n, channels) as the wire's bytes: float32 as is, integers round(x 2^(bits-1)) clipped.

    Parameters
    ----------
    samples : ndarray, shape (n, channels)
        Samples (full scale 1.0 for the integer formats).
    sample_format : str
        int16, int24 or float32.

    Returns
    -------
    bytes
        n x channels x bytes per sample, frame after frame.
    """
    x = np.asarray(samples)
    if sample_format == "float32":
        return np.ascontiguousarray(x, dtype="<f4").tobytes()
    bits = 16 if sample_format == "int16" else 24
    top = 2.0 ** (bits - 1)
    k = np.clip(np.round(np.asarray(x, np.float64) * top), -top, top - 1)
    if bits == 16:
        return np.ascontiguousarray(k, dtype="<i2").tobytes()
    four = np.ascontiguousarray(k, dtype="<i4").reshape(-1).view(np.uint8).reshape(-1, 4)
    return np.ascontiguousarray(four[:, :3]).tobytes()


def encode_block(block: SampleBlock, sample_format: str) -> bytes:
    """The data frame of ``block`` (module doc).

    Parameters
    ----------
    block : SampleBlock
        First sample index and samples (n, channels).
    sample_format : str
        The stream's sample format (its header's).

    Returns
    -------
    bytes
        One frame; InputError for an empty or oversized block.
    """
    x = np.asarray(block.samples)
    require(x.ndim == 2 and 1 <= x.shape[0] <= MAX_BLOCK_FRAMES and 1 <= x.shape[1] <= MAX_CHANNELS,
            f"a block must be (n, channels) samples with 1..{MAX_BLOCK_FRAMES} frames, got {x.shape}")
    require(sample_format in FORMAT_CODES, f"sample format {sample_format!r}: choose one of {', '.join(FORMAT_CODES)}")
    require(0 <= int(block.first_index) < 2**63, f"first sample index {block.first_index} is outside 0..2^63")
    payload = encode_samples(x, sample_format)
    require(len(payload) + _DATA.size <= MAX_BODY_BYTES, f"a block of {x.shape[0]} frames of {x.shape[1]} channels "
                                                         f"exceeds the {MAX_BODY_BYTES} bytes of a frame: send "
                                                         "shorter blocks")
    return _frame(KIND_DATA, _DATA.pack(int(block.first_index), x.shape[0]) + payload)


def encode_ping(ping: PingBlock) -> bytes:
    """The ping frame of ``ping`` (module doc).

    Parameters
    ----------
    ping : PingBlock
        The ping: number, times, pulse, rate and complex samples (channels, n).

    Returns
    -------
    bytes
        One frame; InputError for a ping a frame cannot carry.
    """
    x = np.asarray(ping.samples)
    require(x.ndim == 2 and 1 <= x.shape[0] <= MAX_CHANNELS and 1 <= x.shape[1] <= MAX_BLOCK_FRAMES,
            f"a ping must be (channels, n) samples with 1..{MAX_BLOCK_FRAMES} per channel, got {x.shape}")
    payload = np.ascontiguousarray(x, dtype="<c8").tobytes()
    require(len(payload) + _PING.size <= MAX_BODY_BYTES, f"ping {ping.ping}: {x.shape} samples exceed the "
                                                         f"{MAX_BODY_BYTES} bytes of a frame")
    head = _PING.pack(int(ping.ping), x.shape[1], float(ping.transmit_time_s), float(ping.fs_hz), float(ping.fc_hz),
                      float(ping.bandwidth_hz), float(ping.duration_s))
    return _frame(KIND_PING, head + payload)


def encode_end(end_index: int) -> bytes:
    """The end-of-stream frame: ``end_index`` is one past the last sample sent.

    Parameters
    ----------
    end_index : int
        One past the last sample index sent.

    Returns
    -------
    bytes
        One frame.
    """
    return _frame(KIND_END, struct.pack("<Q", int(end_index)))


def decode_samples(payload, n: int, channels: int, sample_format: str) -> np.ndarray:
    """The wire's bytes as float32 (n, channels), integers scaled by 2^-(bits-1) (exact in float32).

    Parameters
    ----------
    payload : bytes-like
        n x channels samples, frame after frame.
    n, channels : int
        Frames and channels.
    sample_format : str
        int16, int24 or float32.

    Returns
    -------
    ndarray of float32, shape (n, channels)
        A new array.
    """
    if sample_format == "float32":
        return np.frombuffer(payload, "<f4", n * channels).reshape(n, channels).astype(np.float32)
    if sample_format == "int16":
        k = np.frombuffer(payload, "<i2", n * channels)
        return (k * np.float32(2.0**-15)).astype(np.float32).reshape(n, channels)
    raw = np.frombuffer(payload, np.uint8, 3 * n * channels).reshape(-1, 3)
    four = np.zeros((raw.shape[0], 4), np.uint8)
    four[:, 1:] = raw  # the 24 bits in the top of an int32: the shift back keeps the sign
    k = four.view("<i4").reshape(-1) >> 8
    return (k * np.float32(2.0**-23)).astype(np.float32).reshape(n, channels)


class FrameDecoder:
    """Incremental decoder of the framing (module doc): :meth:`feed` bytes as they arrive, get the items they
    completed. A bad frame is a ``StreamEvent("bad_frame", ...)`` and the decoder resyncs on the next magic."""

    def __init__(self, source: str = "stream"):
        self.source = source
        self.header: StreamHeader | None = None
        self._buf = bytearray()
        self._skipping = False  # already reported the bytes being skipped

    @property
    def buffered_bytes(self) -> int:
        """Bytes held waiting for the rest of a frame (at most one largest frame)."""
        return len(self._buf)

    def feed(self, data) -> list:
        """Take ``data`` (bytes as received); the headers, blocks, ends and bad-frame events it completed.

        Parameters
        ----------
        data : bytes-like
            The next bytes of the stream.

        Returns
        -------
        list
            StreamHeader | SampleBlock | StreamEnd | StreamEvent, in stream order.
        """
        self._buf += data
        out: list = []
        pos = 0
        while True:
            pos, item, done = self._next(pos, out)
            if item is not None:
                out.append(item)
            if done:
                break
        del self._buf[:pos]
        return out

    def flush(self) -> list:
        """The end of the bytes (the connection closed): a frame cut short is a bad frame; the buffer is emptied.

        Returns
        -------
        list of StreamEvent
            One "bad_frame" event when bytes of an incomplete frame were left, else none.
        """
        left, self._buf, self._skipping = len(self._buf), bytearray(), False
        if not left:
            return []
        return [StreamEvent("bad_frame", f"{self.source}: a frame cut short ({left} bytes) when the connection "
                                         "ended: dropped")]

    def _bad(self, pos: int, why: str, out: list) -> int:
        """Report a bad frame at ``pos`` and step past its magic (resync on the next)."""
        out.append(StreamEvent("bad_frame", f"{self.source}: {why}: frame dropped, resyncing on the next frame"))
        self._skipping = True
        return pos + 1

    def _next(self, pos: int, out: list):
        """(new position, item or None, whether to wait for more bytes) at ``pos``."""
        buf = self._buf
        at = buf.find(MAGIC, pos)
        if at < 0:  # keep a tail that may be the start of a magic
            keep = max(pos, len(buf) - (len(MAGIC) - 1))
            self._note_skip(keep - pos, out)
            return keep, None, True
        self._note_skip(at - pos, out)
        if len(buf) - at < PREFIX_BYTES:
            return at, None, True
        _, version, kind, _, length = _PREFIX.unpack_from(buf, at)
        if version != VERSION:
            return self._bad(at, f"version {version} (this reader takes {VERSION})", out), None, False
        if kind not in (KIND_HEADER, KIND_DATA, KIND_END, KIND_PING):
            return self._bad(at, f"unknown frame kind {kind}", out), None, False
        if length > MAX_BODY_BYTES:
            return self._bad(at, f"a body of {length} bytes (at most {MAX_BODY_BYTES})", out), None, False
        end = at + PREFIX_BYTES + length
        if len(buf) < end + CRC_BYTES:
            return at, None, True
        (crc,) = struct.unpack_from("<I", buf, end)
        if zlib.crc32(memoryview(buf)[at:end]) != crc:
            return self._bad(at, f"CRC mismatch on a {length}-byte body", out), None, False
        try:
            item = self._body(kind, memoryview(buf)[at + PREFIX_BYTES:end])
        except InputError as exc:
            return self._bad(at, str(exc), out), None, False
        self._skipping = False
        return end + CRC_BYTES, item, False

    def _note_skip(self, n: int, out: list) -> None:
        if n > 0 and not self._skipping:
            out.append(StreamEvent("bad_frame", f"{self.source}: {n} bytes that are no frame skipped"))
        if n > 0:
            self._skipping = True

    def _body(self, kind: int, body) -> StreamHeader | SampleBlock | StreamEnd | PingBlock:
        if kind == KIND_HEADER:
            return self._header(body)
        if kind == KIND_PING:
            return self._ping(body)
        if kind == KIND_END:
            require(len(body) == 8, f"an end frame of {len(body)} bytes (8 expected)")
            return StreamEnd(struct.unpack("<Q", body)[0])
        return self._block(body)

    def _header(self, body) -> StreamHeader:
        require(len(body) == _HEADER.size, f"a header of {len(body)} bytes ({_HEADER.size} expected)")
        channels, code, _, rate, micros, fs = _HEADER.unpack(body)
        require(code in _FORMAT_OF_CODE, f"unknown sample format code {code}")
        require(0 <= micros <= _LATEST_US, f"a start time {micros} us after 1970 (not before 2200)")
        header = StreamHeader(channels, rate, _FORMAT_OF_CODE[code], _EPOCH + timedelta(microseconds=micros),
                              None if math.isnan(fs) else fs, self.source)
        check_header(header)
        self.header = header
        return header

    def _block(self, body) -> SampleBlock:
        require(self.header is not None, "a data frame before any header")
        require(len(body) >= _DATA.size, f"a data frame of {len(body)} bytes (at least {_DATA.size})")
        first, n = _DATA.unpack_from(body)
        h = self.header
        width = FORMAT_CODES[h.sample_format][1]
        require(1 <= n <= MAX_BLOCK_FRAMES, f"a block of {n} frames (1..{MAX_BLOCK_FRAMES})")
        require(first < 2**62, f"first sample index {first} (beyond any recording)")
        require(len(body) == _DATA.size + n * h.channels * width,
                f"a block of {n} frames x {h.channels} channels x {width} bytes in a {len(body)}-byte body")
        x = decode_samples(body[_DATA.size:], n, h.channels, h.sample_format)
        if h.sample_format == "float32":
            hi, lo = float(x.max()), float(x.min())
            require(math.isfinite(hi) and math.isfinite(lo), f"NaN/inf samples in the block at index {first}")
            require(max(hi, -lo) <= MAX_FLOAT_SAMPLE, f"a sample of magnitude {max(hi, -lo):.3g} in the block at "
                                                      f"index {first} (no pressure is that large)")
        return SampleBlock(int(first), x)

    def _ping(self, body) -> PingBlock:
        require(self.header is not None, "a ping frame before any header")
        require(len(body) >= _PING.size, f"a ping frame of {len(body)} bytes (at least {_PING.size})")
        number, n, t, fs, fc, bw, dur = _PING.unpack_from(body)
        channels = self.header.channels
        require(1 <= n <= MAX_BLOCK_FRAMES, f"a ping of {n} samples per channel (1..{MAX_BLOCK_FRAMES})")
        require(len(body) == _PING.size + 8 * n * channels,
                f"ping {number}: {n} samples x {channels} channels x 8 bytes in a {len(body)}-byte body")
        require(all(math.isfinite(v) for v in (t, fs, fc, bw, dur)), f"ping {number}: a time, rate or pulse field "
                                                                      "is NaN/inf")
        require(MIN_RATE_HZ <= fs <= MAX_RATE_HZ and t >= 0 and dur > 0 and fc >= 0 and bw >= 0,
                f"ping {number}: rate {fs:g} Hz, transmit time {t:g} s, pulse {dur:g} s, carrier {fc:g} Hz, "
                f"bandwidth {bw:g} Hz: out of range")
        x = np.frombuffer(body[_PING.size:], "<c8", n * channels).reshape(channels, n).astype(np.complex64)
        require(bool(np.all(np.isfinite(x.view(np.float32)))), f"NaN/inf samples in ping {number}")
        return PingBlock(int(number), float(t), float(fc), float(bw), float(dur), float(fs), x)
