"""Recorder formats (io/wav_blocks.py reader, io/recording_writer.py writer): the same samples from float32 WAV,
24-bit WAV, FLAC, RF64 and W64; hand-written headers; truncated files refused; bext start times; the choice of
WAV or RF64 by size; the beamforming front end sees the same peaks whatever the container."""

from __future__ import annotations

import struct
from datetime import UTC, datetime

import numpy as np
import pytest
import soundfile as sf
from scipy.io import wavfile

from sonartrack.core.errors import InputError
from sonartrack.io.recording_writer import WAV_LIMIT_BYTES, choose_container, recording_writer
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info

FS = 4000


def _signal(channels=6, frames=3000, seed=0):
    rng = np.random.default_rng(seed)
    return np.clip(0.3 * rng.standard_normal((channels, frames)), -0.99, 0.99)


def _write(path, x, sample_format, **kw):
    with recording_writer(path, x.shape[0], FS, sample_format, **kw) as w:
        for i in range(0, x.shape[1], 700):  # blocks that do not divide the length
            w.write(x[:, i:i + 700])
    return path


def _read_all(path, block=500):
    return np.concatenate(list(iter_wav_blocks(path, block)), axis=1)


@pytest.mark.parametrize(("name", "fmt", "container", "tol"), [
    ("f.wav", "float32", "WAV", 0.0), ("r.rf64", "float32", "RF64", 0.0), ("w.w64", "float32", "W64", 0.0),
    ("p24.wav", "int24", "WAV", 2.0**-23), ("p.flac", "int24", "FLAC", 2.0**-23),
    ("p16.flac", "int16", "FLAC", 2.0**-15),
    ("p16.wav", "int16", "WAV", 2.0**-15), ("p32.wav", "int32", "WAV", 2.0**-31), ("d.wav", "float64", "WAV", 0.0)])
def test_the_same_samples_from_every_format(tmp_path, name, fmt, container, tol):
    x = _signal()
    _write(tmp_path / name, x, fmt, expected_frames=x.shape[1])
    info = read_wav_info(tmp_path / name)
    assert (info.channels, info.sample_rate_hz, info.frames, info.container) == (6, FS, 3000, container)
    assert info.sample_format == fmt and info.start_utc is None
    got = _read_all(tmp_path / name)
    assert got.shape == (6, 3000)
    # each block a (channels, frames) view of a frames x channels array: the file's own layout
    assert all(b.T.flags.c_contiguous for b in iter_wav_blocks(tmp_path / name, 500))
    want = x.astype(np.float32).astype(float) if fmt == "float32" else x
    # integers (step tol = 2^-(b-1)): round(x 2^(b-1)) read back as k / 2^(b-1), within half a step
    np.testing.assert_allclose(got, want, rtol=0, atol=tol / 2 * 1.000001 if tol else 0.0)


def test_24_bit_integers_match_an_independent_reader(tmp_path):
    """scipy's RIFF reader returns 24-bit samples left-justified in int32: k * 256 with k = round(x 2^23)."""
    x = _signal(channels=3, frames=400)
    _write(tmp_path / "p24.wav", x, "int24")
    _, data = wavfile.read(tmp_path / "p24.wav")
    np.testing.assert_array_equal(data.T.astype(np.int64) // 256, np.round(x * 2**23).astype(np.int64))


def _riff(chunks, magic=b"RIFF"):
    body = b"WAVE"
    for cid, payload in chunks:
        body += cid + struct.pack("<I", len(payload)) + payload + (b"\0" if len(payload) % 2 else b"")
    return magic + struct.pack("<I", len(body)) + body


def _fmt(tag, channels, bits):
    align = channels * bits // 8
    return struct.pack("<HHIIHH", tag, channels, FS, FS * align, align, bits)


def test_hand_written_24_bit_pcm(tmp_path):
    """Little-endian 3-byte two's complement: -2^23, 2^23 - 1, 1, -1 read as k / 2^23."""
    ks = np.array([[-(2**23), 2**23 - 1], [1, -1]])
    raw = b"".join(int(k).to_bytes(3, "little", signed=True) for k in ks.ravel())
    (tmp_path / "h.wav").write_bytes(_riff([(b"fmt ", _fmt(1, 2, 24)), (b"data", raw)]))
    info = read_wav_info(tmp_path / "h.wav")
    assert (info.sample_format, info.frames) == ("int24", 2)
    np.testing.assert_array_equal(next(iter_wav_blocks(info, 2)), ks.T / 2.0**23)


def _bext(date: str, time: str, time_ref: int) -> bytes:
    """EBU Tech 3285 bext: description 256, originator 32, reference 32, date 10, time 8, TimeReference u64."""
    return bytes(256 + 32 + 32) + date.encode() + time.encode() + struct.pack("<Q", time_ref) + bytes(256 + 2 + 64)


@pytest.mark.parametrize(("time_ref", "want"), [
    (0, datetime(2024, 5, 17, 13, 45, 7, tzinfo=UTC)),
    ((13 * 3600 + 45 * 60 + 7) * FS + 1000, datetime(2024, 5, 17, 13, 45, 7, 250000, tzinfo=UTC)),
    (5 * FS, datetime(2024, 5, 17, 13, 45, 7, tzinfo=UTC))])  # TimeReference disagrees: OriginationTime rules
def test_bext_start_time(tmp_path, time_ref, want):
    x = np.zeros((8, 2), np.int16)
    (tmp_path / "b.wav").write_bytes(_riff([(b"bext", _bext("2024-05-17", "13:45:07", time_ref)),
                                            (b"fmt ", _fmt(1, 2, 16)), (b"data", x.tobytes())]))
    assert read_wav_info(tmp_path / "b.wav").start_utc == want


def _expect(path, *words):
    with pytest.raises(InputError) as e:
        read_wav_info(path)
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize(("name", "fmt"), [("r.rf64", "float32"), ("p.flac", "int24"), ("w.w64", "int24"),
                                           ("p24.wav", "int24"), ("f.wav", "float32")])
def test_truncated_files_are_refused_not_shortened(tmp_path, name, fmt):
    x = _signal(frames=8000)
    raw = _write(tmp_path / name, x, fmt).read_bytes()
    cut = tmp_path / f"cut_{name}"
    cut.write_bytes(raw[: len(raw) * 2 // 3])
    _expect(cut, "truncated", cut.name)
    assert read_wav_info(tmp_path / name).frames == 8000


def test_refusals(tmp_path):
    x = (0.1 * np.ones((100, 2))).astype(np.float32)
    sf.write(tmp_path / "v.ogg", x, FS, format="OGG", subtype="VORBIS")
    _expect(tmp_path / "v.ogg", "v.ogg", "give WAV, RF64, W64 or FLAC")
    (tmp_path / "u8.wav").write_bytes(_riff([(b"fmt ", _fmt(1, 2, 8)), (b"data", bytes(20))]))
    _expect(tmp_path / "u8.wav", "8-bit PCM", "sox")
    (tmp_path / "text.flac").write_text("not audio at all")
    _expect(tmp_path / "text.flac", "not a RIFF/WAVE, RF64, W64 or FLAC")


def test_nan_in_an_rf64_block_names_its_time(tmp_path):
    x = _signal(frames=2000)
    x[2, 1234] = np.nan
    _write(tmp_path / "n.rf64", x, "float32")
    with pytest.raises(InputError, match=r"NaN/inf.*0\.250 s"):
        list(iter_wav_blocks(tmp_path / "n.rf64", 250))


def test_wav_or_rf64_by_expected_size():
    """4 GiB of data = 2^32 / (16 ch x 4 B x 4000 Hz) s = 4.66 h of 16 channels of float32 at 4 kHz."""
    per_hour = 3600 * 4000
    assert choose_container("r.wav", 16, "float32", int(4.6 * per_hour)) == "WAV"
    assert choose_container("r.wav", 16, "float32", int(4.7 * per_hour)) == "RF64"
    assert choose_container("r.wav", 16, "int16", int(9.3 * per_hour)) == "WAV"  # half the bytes: twice as long
    assert choose_container("r.wav", 16, "int16", int(9.4 * per_hour)) == "RF64"
    assert choose_container("r.wav", 16, "float32", None) == "WAV"
    assert choose_container("r.flac", 8, "int24", int(100 * per_hour)) == "FLAC"
    with pytest.raises(InputError, match="at most 8 channels"):
        choose_container("r.flac", 16, "int24", 10)
    assert WAV_LIMIT_BYTES < 2**32
    with pytest.raises(InputError, match="FLAC holds 16- or 24-bit"):
        choose_container("r.flac", 8, "float32", 10)


def test_writer_switches_to_rf64_above_the_limit_and_refuses_to_overrun_a_wav(tmp_path):
    x = _signal(channels=2, frames=1000)
    small = _write(tmp_path / "small.wav", x, "float32", expected_frames=1000, wav_limit_bytes=8000)
    big = _write(tmp_path / "big.wav", x, "float32", expected_frames=1000, wav_limit_bytes=7999)
    assert small.read_bytes()[:4] == b"RIFF" and big.read_bytes()[:4] == b"RF64"
    np.testing.assert_array_equal(_read_all(big), _read_all(small))
    with pytest.raises(InputError, match="4 GiB limit"):
        _write(tmp_path / "over.wav", x, "float32", wav_limit_bytes=7999)
    assert not list(tmp_path.glob("*over*"))  # nothing half-written


def test_front_end_sees_the_same_peaks_in_wav_and_rf64(tmp_path):
    from sonartrack.acoustics.beamforming import BeamformerSettings, bearing_time_record
    from sonartrack.acoustics.line_array import LineArray

    n, d, c, cone = 16, 2.5, 1500.0, 60.0
    rng = np.random.default_rng(5)
    samples = 4 * FS
    f = np.fft.rfftfreq(samples, 1 / FS)
    spec = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * ((f >= 150) & (f < 300))
    tau = -((n - 1) / 2 - np.arange(n)) * d * np.cos(np.deg2rad(cone)) / c
    x = np.fft.irfft(spec[None] * np.exp(-2j * np.pi * f[None] * tau[:, None]), samples, axis=1)
    x = 0.1 * x / x.std() + 0.05 * rng.standard_normal(x.shape)
    s = BeamformerSettings()
    records = []
    for name in ("a.wav", "a.rf64"):
        _write(tmp_path / name, x, "float32")
        info = read_wav_info(tmp_path / name)
        records.append(bearing_time_record(iter_wav_blocks(info, FS), FS, LineArray(n, d, c), s))
    a, b = records
    for field in ("time_s", "bearing_deg", "amplitude"):
        np.testing.assert_array_equal(getattr(a.peaks, field), getattr(b.peaks, field))
    np.testing.assert_array_equal(a.level, b.level)
    strongest = [bearings[np.argmax(amps)] for _, bearings, amps in a.peaks.by_scan()]
    assert len(strongest) == 4 and np.all(np.abs(np.array(strongest) - cone) < 1.0), strongest


@pytest.mark.parametrize(("name", "fmt", "compact_type"), [
    ("f.wav", "float32", np.float32), ("p24.wav", "int24", np.float32), ("p16.flac", "int16", np.float32),
    ("p32.wav", "int32", np.float64), ("d.wav", "float64", np.float64)])
def test_compact_blocks_hold_the_float64_values_exactly(tmp_path, name, fmt, compact_type):
    """float32 blocks only where every sample is a float32 (24 significant bits at most): the same values to the
    last bit, and the same (channels, frames) view of a frames x channels layout."""
    x = _signal()
    _write(tmp_path / name, x, fmt, expected_frames=x.shape[1])
    wide = list(iter_wav_blocks(tmp_path / name, 500))
    compact = list(iter_wav_blocks(tmp_path / name, 500, compact=True))
    assert len(compact) == len(wide) == 6
    for c, w in zip(compact, wide, strict=True):
        assert c.dtype == compact_type and w.dtype == np.float64 and c.T.flags.c_contiguous
        np.testing.assert_array_equal(c.astype(np.float64), w)
