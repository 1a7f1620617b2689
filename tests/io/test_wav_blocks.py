"""Streaming WAV reader (io/wav_blocks.py): round trips against scipy, hand-written headers, refusals, memory."""

from __future__ import annotations

import struct
import tracemalloc

import numpy as np
import pytest
from scipy.io import wavfile

from sonartrack.core.errors import InputError
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info

FS = 4000


def _samples(dtype, frames=1000, channels=3, seed=0):
    rng = np.random.default_rng(seed)
    if np.dtype(dtype).kind == "f":
        return (0.5 * rng.standard_normal((frames, channels))).astype(dtype)
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, (frames, channels), endpoint=True).astype(dtype)


@pytest.mark.parametrize(("dtype", "name", "scale"), [(np.int16, "int16", 2.0**15), (np.int32, "int32", 2.0**31),
                                                      (np.float32, "float32", 1.0), (np.float64, "float64", 1.0)])
def test_round_trip_against_scipy(tmp_path, dtype, name, scale):
    data = _samples(dtype)
    path = tmp_path / "x.wav"
    wavfile.write(path, FS, data)
    info = read_wav_info(path)
    assert (info.channels, info.sample_rate_hz, info.frames, info.sample_format) == (3, FS, 1000, name)
    assert info.duration_s == pytest.approx(0.25)
    blocks = list(iter_wav_blocks(info, 300))
    assert len(blocks) == 3  # the partial last block (100 frames) is dropped
    got = np.concatenate(blocks, axis=1)
    assert got.dtype == np.float64 and got.shape == (3, 900)
    np.testing.assert_array_equal(got, data[:900].T.astype(np.float64) / scale)
    if name.startswith("int"):
        assert got.min() >= -1.0 and got.max() < 1.0


def test_start_and_stop_frames(tmp_path):
    data = _samples(np.int16)
    wavfile.write(tmp_path / "x.wav", FS, data)
    got = np.concatenate(list(iter_wav_blocks(tmp_path / "x.wav", 100, start_frame=250, stop_frame=560)), axis=1)
    np.testing.assert_array_equal(got, data[250:550].T / 32768.0)


def _riff(chunks: list[tuple[bytes, bytes]]) -> bytes:
    body = b"WAVE"
    for cid, payload in chunks:
        body += cid + struct.pack("<I", len(payload)) + payload + (b"\0" if len(payload) % 2 else b"")
    return b"RIFF" + struct.pack("<I", len(body)) + body


def _fmt(tag, channels, bits, extensible_sub=None) -> bytes:
    align = channels * bits // 8
    base = struct.pack("<HHIIHH", tag, channels, FS, FS * align, align, bits)
    if extensible_sub is None:
        return base
    guid = struct.pack("<H", extensible_sub) + bytes.fromhex("000000001000800000aa00389b71")
    return base + struct.pack("<HHI", 22, bits, 0) + guid


def test_extensible_header_and_list_chunk_with_odd_padding(tmp_path):
    data = _samples(np.float32, frames=64, channels=2)
    raw = _riff([(b"fmt ", _fmt(0xFFFE, 2, 32, extensible_sub=3)), (b"LIST", b"INFOabc"),
                 (b"data", data.tobytes())])
    (tmp_path / "ext.wav").write_bytes(raw)
    info = read_wav_info(tmp_path / "ext.wav")
    assert info.sample_format == "float32" and info.frames == 64
    np.testing.assert_array_equal(next(iter_wav_blocks(info, 64)), data.T.astype(float))
    pcm = _samples(np.int16, frames=64, channels=2)
    (tmp_path / "pcm.wav").write_bytes(_riff([(b"fmt ", _fmt(0xFFFE, 2, 16, extensible_sub=1)),
                                              (b"data", pcm.tobytes())]))
    np.testing.assert_array_equal(next(iter_wav_blocks(tmp_path / "pcm.wav", 64)), pcm.T / 32768.0)


def test_simulator_wav_reads_back_exactly(tmp_path):
    from sonartrack.io.wav_writer import wav_block_writer

    rng = np.random.default_rng(3)
    blocks = [rng.standard_normal((16, 400)) * 1e-3 for _ in range(3)]
    with wav_block_writer(tmp_path / "rec.wav", 16, 4000.0, "float32") as w:
        for b in blocks:
            w.write(b)
    got = list(iter_wav_blocks(tmp_path / "rec.wav", 400))
    assert len(got) == 3
    for g, b in zip(got, blocks, strict=True):
        np.testing.assert_array_equal(g, b.astype(np.float32).astype(float))


def _expect(path, *words):
    with pytest.raises(InputError) as e:
        read_wav_info(path)
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_refusals(tmp_path):
    _expect(tmp_path / "missing.wav", "not found")
    _expect(tmp_path, "directory")
    png = tmp_path / "pic.wav"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))
    _expect(png, "pic.wav", "not a RIFF/WAVE")
    short = tmp_path / "short.wav"
    short.write_bytes(_riff([(b"fmt ", _fmt(1, 2, 16))])[:30])
    _expect(short, "short.wav", "truncated")
    stub = tmp_path / "stub.wav"
    stub.write_bytes(b"RIFF\x10\x00")
    _expect(stub, "stub.wav", "truncated")
    for bits in (8,):  # 24-bit PCM is read (test_recording_formats.py)
        p = tmp_path / f"b{bits}.wav"
        p.write_bytes(_riff([(b"fmt ", _fmt(1, 2, bits)), (b"data", bytes(2 * bits // 8 * 10))]))
        _expect(p, f"{bits}-bit", "sox")
    empty = tmp_path / "empty.wav"
    empty.write_bytes(_riff([(b"fmt ", _fmt(1, 2, 16)), (b"data", b"")]))
    _expect(empty, "no samples")


def test_truncated_data_is_refused_not_read_short(tmp_path):
    path = tmp_path / "cut.wav"
    wavfile.write(path, FS, _samples(np.int16))
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) - 2000])
    _expect(path, "truncated", "1000 frames")


def test_nan_block_names_its_time(tmp_path):
    data = _samples(np.float32)
    data[650, 1] = np.nan
    wavfile.write(tmp_path / "nan.wav", FS, data)
    blocks = iter_wav_blocks(tmp_path / "nan.wav", 200)
    assert next(blocks).shape == (3, 200)
    next(blocks)
    next(blocks)
    with pytest.raises(InputError, match=r"NaN/inf.*0\.150 s"):
        next(blocks)


def test_memory_does_not_grow_with_the_file(tmp_path):
    """A 32 MB file read in 64 kB blocks: the traced peak stays near a few blocks, far under the file size."""
    path = tmp_path / "big.wav"
    frames, channels = 500_000, 16
    chunk = np.zeros((50_000, channels), dtype=np.float32)
    with open(path, "wb") as fh:
        n_data = frames * channels * 4
        fh.write(b"RIFF" + struct.pack("<I", 36 + n_data) + b"WAVE" + b"fmt " + struct.pack("<I", 16)
                 + _fmt(3, channels, 32) + b"data" + struct.pack("<I", n_data))
        for _ in range(frames // 50_000):
            fh.write(chunk.tobytes())
    size = path.stat().st_size
    tracemalloc.start()
    total = 0
    for block in iter_wav_blocks(path, 1000):
        total += block.shape[1]
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert total == frames
    assert peak < size / 50, (peak, size)
