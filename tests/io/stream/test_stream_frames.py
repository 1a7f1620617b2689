"""The framing: round trips, a frame built by hand from the documented layout, and every hostile frame -> an event,
never a crash, and the decoder finds the next good frame."""

from __future__ import annotations

import struct
import zlib
from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.stream.frames import (
    MAX_BODY_BYTES,
    FrameDecoder,
    StreamEnd,
    encode_block,
    encode_end,
    encode_header,
)
from sonartrack.io.stream.reorder import BlockReorderer
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader

START = datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC)


def _header(fmt="float32", channels=3, rate=4000.0):
    return StreamHeader(channels, rate, fmt, START, None)


def _hand_frame(kind: int, body: bytes, version: int = 1, magic: bytes = b"SNTK") -> bytes:
    """A frame written from the module docstring's table, not by the encoder."""
    head = magic + bytes([version, kind, 0, 0]) + struct.pack("<I", len(body))
    return head + body + struct.pack("<I", zlib.crc32(head + body))


def _hand_header(channels=3, code=3, rate=4000.0, micros=None, fs=float("nan")) -> bytes:
    micros = int(START.timestamp() * 1e6) if micros is None else micros
    return _hand_frame(1, struct.pack("<HBBdqd", channels, code, 0, rate, micros, fs))


def _decode_all(data: bytes, step: int = 0) -> list:
    d = FrameDecoder("test")
    if not step:
        return d.feed(data) + d.flush()
    out = []
    for i in range(0, len(data), step):
        out += d.feed(data[i:i + step])
    return out + d.flush()


def _kinds(items):
    return [type(i).__name__ if not isinstance(i, StreamEvent) else i.kind for i in items]


@pytest.mark.parametrize("fmt,tol", [("float32", 0.0), ("int24", 2.0**-24), ("int16", 2.0**-16)])
def test_round_trip_in_pieces(fmt, tol):
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.99, 0.99, (50, 3)).astype(np.float32)
    data = encode_header(_header(fmt)) + encode_block(SampleBlock(7, x), fmt) + encode_end(57)
    items = _decode_all(data, step=5)  # fed 5 bytes at a time
    assert _kinds(items) == ["StreamHeader", "SampleBlock", "StreamEnd"]
    assert items[0].sample_format == fmt and items[0].channels == 3 and items[0].start_utc == START
    assert items[1].first_index == 7 and items[1].samples.dtype == np.float32
    assert np.max(np.abs(items[1].samples - x)) <= tol
    assert items[2] == StreamEnd(57)


def test_hand_built_frames_decode_to_the_documented_values():
    # int24: -1 is ff ff ff, 2^22 is 00 00 40: k / 2^23
    payload = bytes([0xFF, 0xFF, 0xFF, 0x00, 0x00, 0x40])
    data = _hand_header(channels=2, code=2) + _hand_frame(2, struct.pack("<QI", 1000, 1) + payload)
    items = _decode_all(data)
    assert _kinds(items) == ["StreamHeader", "SampleBlock"]
    assert items[1].first_index == 1000
    assert items[1].samples.tolist() == [[-(2.0**-23), 0.5]]


def test_int24_extremes_are_exact():
    x = np.array([[-1.0, 1.0 - 2.0**-23, 0.0]], np.float32)
    items = _decode_all(encode_header(_header("int24")) + encode_block(SampleBlock(0, x), "int24"))
    assert items[1].samples.tolist() == x.tolist()


def _good_block(first=0):
    return encode_block(SampleBlock(first, np.zeros((4, 3), np.float32)), "float32")


@pytest.mark.parametrize("bad", [
    "truncated", "bad_crc", "wrong_magic", "absurd_length", "channels_0", "rate_nan", "version", "nan_sample",
    "length_mismatch", "data_before_header",
])
def test_hostile_frame_is_an_event_and_the_next_frame_is_read(bad):
    good_header = encode_header(_header())
    frames = {
        "truncated": good_header + _good_block(0)[:-7],
        "bad_crc": good_header + _good_block(0)[:-1] + b"\x00",
        "wrong_magic": good_header + b"XXXX" + _good_block(0)[4:],
        "absurd_length": good_header + b"SNTK\x01\x02\x00\x00" + struct.pack("<I", 2**32 - 1) + b"\x00" * 8,
        "channels_0": _hand_header(channels=0) + good_header,
        "rate_nan": _hand_header(rate=float("nan")) + good_header,
        "version": good_header + _hand_frame(2, struct.pack("<QI", 0, 1) + b"\x00" * 12, version=9),
        "nan_sample": good_header + _hand_frame(2, struct.pack("<QI", 0, 1) + struct.pack("<3f", 0, np.nan, 0)),
        "length_mismatch": good_header + _hand_frame(2, struct.pack("<QI", 0, 5) + b"\x00" * 12),
        "data_before_header": _good_block(0) + good_header,
    }[bad]
    after = _good_block(4) if bad != "truncated" else b""
    items = _decode_all(frames + after)
    assert any(isinstance(i, StreamEvent) and i.kind == "bad_frame" for i in items), items
    assert isinstance(next(i for i in items if not isinstance(i, StreamEvent)), StreamHeader)
    if after:
        assert [i.first_index for i in items if isinstance(i, SampleBlock)] == [4]  # the good frame after it


def test_absurd_length_does_not_wait_for_the_body():
    d = FrameDecoder()
    items = d.feed(encode_header(_header()) + b"SNTK\x01\x02\x00\x00" + struct.pack("<I", MAX_BODY_BYTES + 1))
    assert _kinds(items) == ["StreamHeader", "bad_frame"]
    assert d.buffered_bytes < 16  # nothing held for the stated body


def test_junk_between_frames_is_one_event():
    items = _decode_all(encode_header(_header()) + b"junk" * 100 + _good_block(0))
    assert _kinds(items) == ["StreamHeader", "bad_frame", "SampleBlock"]


def test_encoder_refuses_what_a_stream_cannot_carry():
    with pytest.raises(InputError, match="channels"):
        encode_header(_header(channels=0))
    with pytest.raises(InputError, match="sample rate"):
        encode_header(_header(rate=float("nan")))
    with pytest.raises(InputError, match="block"):
        encode_block(SampleBlock(0, np.zeros((0, 3), np.float32)), "float32")


def _blk(first, n=10):
    return SampleBlock(first, np.full((n, 1), first, np.float32))


def _feed(r: BlockReorderer, firsts):
    out = []
    for f in firsts:
        out += r.push(_blk(f))
    return out + r.drain()


def test_reorder_out_of_order_within_the_window():
    out = _feed(BlockReorderer(window_blocks=4), [0, 20, 10, 30])
    assert [o.first_index for o in out] == [0, 10, 20, 30]


def test_reorder_duplicate_dropped():
    out = _feed(BlockReorderer(window_blocks=4), [0, 10, 10, 20, 20])
    assert [o.first_index for o in out if isinstance(o, SampleBlock)] == [0, 10, 20]
    assert [o.kind for o in out if isinstance(o, StreamEvent)] == ["duplicate", "duplicate"]


def test_reorder_gap_then_late_block():
    out = _feed(BlockReorderer(window_blocks=2), [0, 20, 30, 40, 10])
    kinds = [(o.kind, o.first_index, o.count) if isinstance(o, StreamEvent) else o.first_index for o in out]
    assert kinds == [0, ("gap", 10, 10), 20, 30, 40, ("late", 10, 10)]


def test_reorder_gap_after_the_wait():
    now = [0.0]
    r = BlockReorderer(window_blocks=100, window_s=1.0, clock=lambda: now[0])
    assert [b.first_index for b in r.push(_blk(0))] == [0]
    assert r.push(_blk(20)) == []
    assert r.expire() == []
    now[0] = 1.5
    out = r.expire()
    assert [(o.kind, o.first_index, o.count) for o in out[:1]] == [("gap", 10, 10)] and out[1].first_index == 20


def test_reorder_overlap_keeps_the_new_tail():
    r = BlockReorderer()
    out = r.push(_blk(0, 10)) + r.push(SampleBlock(5, np.arange(10, dtype=np.float32)[:, None]))
    assert out[1].kind == "overlap" and out[2].first_index == 10
    assert out[2].samples[:, 0].tolist() == [5, 6, 7, 8, 9]


def _ping_by_hand(number, t, fs, fc, bw, dur, x):
    """A ping frame built from the module doc's layout, not by encode_ping."""
    body = struct.pack("<IIddddd", number, x.shape[1], t, fs, fc, bw, dur) + x.astype("<c8").tobytes()
    head = b"SNTK" + bytes([1, 4, 0, 0]) + struct.pack("<I", len(body))
    return head + body + struct.pack("<I", zlib.crc32(head + body))


def test_a_ping_frame_round_trips_and_matches_the_documented_layout():
    from sonartrack.io.stream.frames import encode_ping
    from sonartrack.io.stream.types import PingBlock

    rng = np.random.default_rng(3)
    x = (rng.standard_normal((3, 50)) + 1j * rng.standard_normal((3, 50))).astype(np.complex64)
    ping = PingBlock(7, 210.0, 1500.0, 300.0, 0.5, 2000.0, x)
    frame = encode_ping(ping)
    assert frame == _ping_by_hand(7, 210.0, 2000.0, 1500.0, 300.0, 0.5, x)
    dec = FrameDecoder()
    out = dec.feed(encode_header(_header()) + frame[:40])
    out += dec.feed(frame[40:])
    got = out[-1]
    assert isinstance(got, PingBlock) and got.ping == 7 and got.kind == "lfm" and got.transmit_time_s == 210.0
    np.testing.assert_array_equal(got.samples, x)


@pytest.mark.parametrize("why, frame", [
    ("2 channels", lambda x: _ping_by_hand(1, 0.0, 2000.0, 1500.0, 0.0, 0.5, x[:2])),  # the header says 3
    ("out of range", lambda x: _ping_by_hand(1, -5.0, 2000.0, 1500.0, 0.0, 0.5, x)),
    ("NaN/inf", lambda x: _ping_by_hand(1, 0.0, float("nan"), 1500.0, 0.0, 0.5, x)),
    ("NaN/inf samples", lambda x: _ping_by_hand(1, 0.0, 2000.0, 1500.0, 0.0, 0.5, np.full_like(x, np.inf))),
])
def test_a_bad_ping_is_an_event_and_the_next_frame_is_read(why, frame):
    x = np.ones((3, 20), np.complex64)
    dec = FrameDecoder()
    out = dec.feed(encode_header(_header()) + frame(x) + encode_end(0))
    bad = [e for e in out if isinstance(e, StreamEvent)]
    assert len(bad) == 1 and bad[0].kind == "bad_frame" and ("bytes" in bad[0].detail or "range" in bad[0].detail
                                                             or "NaN" in bad[0].detail), (why, bad)
    assert isinstance(out[-1], StreamEnd)
