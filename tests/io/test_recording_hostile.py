"""Hostile recordings (io/wav_blocks.py, io/riff_header.py, io/flac_header.py, io/recording_sequence.py, io/wav.py):
headers are checked against the data, not believed, and a damaged file is one line naming where it breaks.

Each file is made here from a valid one by byte edits: flipped bytes in a FLAC, an RF64 ds64 or WAV data size of
half the data, a FLAC STREAMINFO stating half the frames, 8 kHz on 4 kHz frames, or an unknown length (0, which
the format allows), a wrong block align or byte rate; NaN in every float container."""

from __future__ import annotations

import struct

import numpy as np
import pytest
import soundfile as sf

from sonartrack.core.errors import InputError
from sonartrack.io.flac_header import parse_frame_header, read_streaminfo
from sonartrack.io.recording_sequence import iter_sequence_blocks, open_sequence
from sonartrack.io.wav import read_two_channel_wav
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info

FS = 4000
FRAMES = 40000


def _signal(channels=4, frames=FRAMES, seed=0):
    return np.clip(0.2 * np.random.default_rng(seed).standard_normal((frames, channels)), -0.99, 0.99)


def _flac(path, x=None):
    sf.write(path, _signal() if x is None else x, FS, subtype="PCM_16", format="FLAC")
    return path


def _one_line(fn, *words):
    with pytest.raises(InputError) as e:
        fn()
    msg = str(e.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


def _read_all(path, block=1000):
    return np.concatenate(list(iter_wav_blocks(path, block)), axis=1)


# ---------------------------------------------------------------- 1. a damaged FLAC: one line, where it breaks


def _flipped(tmp_path, where: float):
    """A FLAC with 16 bytes inverted at fraction ``where`` of its frames' bytes; and the first sample of the
    frame holding the damage (its header the last one before the flipped bytes)."""
    raw = bytearray(_flac(tmp_path / "good.flac").read_bytes())
    with open(tmp_path / "good.flac", "rb") as fh:
        audio = read_streaminfo(fh, tmp_path / "good.flac").audio_offset
    at = audio + 200 + int((len(raw) - audio - 400) * where)
    header = next(h for i in range(at, audio - 1, -1) if (h := parse_frame_header(bytes(raw), i)))
    for k in range(at, at + 16):
        raw[k] ^= 0xFF
    (tmp_path / "bad.flac").write_bytes(raw)
    return tmp_path / "bad.flac", header.number * header.block_frames


def test_a_flac_damaged_in_its_first_frame_is_one_line_when_seeking(tmp_path):
    """libsndfile's seek into a damaged frame failed ("Internal psf_fseek() failed"), which reached the user as an
    internal error: passive's first pass seeks to excerpts of the recording, the first at its start."""
    bad, first = _flipped(tmp_path, 0.0)
    assert first == 0
    seq = open_sequence(bad)
    msg = _one_line(lambda: list(iter_sequence_blocks(seq, 1000)), "bad.flac", "damaged",
                    "export the recording again", "cut it before")
    assert "between frames 0 and 4096" in msg
    _one_line(lambda: list(iter_wav_blocks(bad, 100, start_frame=100)), "bad.flac", "damaged")


def test_a_flac_damaged_in_the_middle_names_where_it_breaks(tmp_path):
    bad, frame_start = _flipped(tmp_path, 0.5)
    msg = _one_line(lambda: _read_all(bad), "bad.flac", "damaged")
    good = int(msg.split("between frames ")[1].split(" ")[0])
    # the first undecodable read (4096 frames) holds the damaged frame's first sample, or follows it (the decoder
    # may lose sync a frame late): the break is named within a read of the damage
    assert frame_start - 4096 <= good <= frame_start + 4096, (good, frame_start)


# ---------------------------------------------------------------- 2. stated lengths compared with the data


def _rf64_half(tmp_path):
    sf.write(tmp_path / "r.rf64", _signal().astype(np.float32), FS, subtype="FLOAT", format="RF64")
    raw = bytearray((tmp_path / "r.rf64").read_bytes())
    i = raw.find(b"ds64")
    data_bytes = struct.unpack("<Q", raw[i + 16: i + 24])[0]
    raw[i + 16: i + 24] = struct.pack("<Q", data_bytes // 2)
    (tmp_path / "half.rf64").write_bytes(raw)
    return tmp_path / "half.rf64"


def test_an_rf64_whose_ds64_states_half_the_data_is_refused(tmp_path):
    """libsndfile read the 20000 frames the ds64 chunk states and said nothing of the other 20000."""
    half = _rf64_half(tmp_path)
    _one_line(lambda: read_wav_info(half), "half.rf64", "ds64 data size", f"{FRAMES // 2} frames", f"{FRAMES} frames",
              "ignore_length")
    _one_line(lambda: open_sequence(half), "half.rf64", "ds64 data size")


def _wav(path, x, subtype="FLOAT", chunks_after=b""):
    sf.write(path, x, FS, subtype=subtype, format="WAV")
    raw = path.read_bytes() + chunks_after
    path.write_bytes(raw[:4] + struct.pack("<I", len(raw) - 8) + raw[8:])
    return path


def test_a_wav_data_size_of_half_is_refused_but_trailing_chunks_and_padding_are_not(tmp_path):
    x = _signal().astype(np.float32)
    raw = bytearray(_wav(tmp_path / "w.wav", x).read_bytes())
    i = raw.find(b"data")
    raw[i + 4: i + 8] = struct.pack("<I", struct.unpack("<I", raw[i + 4: i + 8])[0] // 2)
    (tmp_path / "half.wav").write_bytes(raw)
    _one_line(lambda: read_wav_info(tmp_path / "half.wav"), "half.wav", "data chunk size", f"{FRAMES} frames")
    # what may follow a data chunk is read as before: a LIST chunk, or a recorder's zero padding
    listed = _wav(tmp_path / "list.wav", x, chunks_after=b"LIST" + struct.pack("<I", 12) + b"INFOISFT\0\0\0\0")
    padded = _wav(tmp_path / "pad.wav", x, chunks_after=bytes(4096))
    for p in (listed, padded):
        assert read_wav_info(p).frames == FRAMES
        np.testing.assert_array_equal(_read_all(p), x.T.astype(float))


def _streaminfo_edit(src, dst, rate=None, total=None):
    """A copy of the FLAC ``src`` with STREAMINFO's sample rate (20 bits) or total samples (36 bits) replaced."""
    raw = bytearray(src.read_bytes())
    packed = int.from_bytes(raw[18:26], "big")
    if rate is not None:
        packed = (packed & (2**44 - 1)) | (rate << 44)
    if total is not None:
        packed = (packed & ~(2**36 - 1)) | total
    raw[18:26] = packed.to_bytes(8, "big")
    dst.write_bytes(raw)
    return dst


def test_a_flac_whose_streaminfo_states_half_the_frames_is_refused(tmp_path):
    """libsndfile stops at the STREAMINFO total: it read 5 s of a 10 s file without a word."""
    good = _flac(tmp_path / "good.flac")
    half = _streaminfo_edit(good, tmp_path / "half.flac", total=FRAMES // 2)
    _one_line(lambda: read_wav_info(half), "half.flac", "STREAMINFO", f"{FRAMES // 2} frames", f"{FRAMES}",
              "cut the recording short")


def test_a_flac_stating_8_khz_on_4_khz_frames_is_refused_naming_both(tmp_path):
    """At 4 kHz the frame headers carry the rate themselves (code 12, kHz): STREAMINFO's 8 kHz contradicts them."""
    good = _flac(tmp_path / "good.flac")
    wrong = _streaminfo_edit(good, tmp_path / "r8k.flac", rate=8000)
    assert sf.info(str(wrong)).samplerate == 8000  # what libsndfile believed
    _one_line(lambda: read_wav_info(wrong), "r8k.flac", "sample rate", "8000 Hz", "4000 Hz")


def test_a_flac_of_unstated_length_is_read_whole(tmp_path):
    """STREAMINFO total 0 means "unknown" (RFC 9639 8.2): a stream. It was refused as truncated."""
    x = _signal()
    good = _flac(tmp_path / "good.flac", x)
    unknown = _streaminfo_edit(good, tmp_path / "u.flac", total=0)
    info = read_wav_info(unknown)
    assert (info.frames, info.length_unstated) == (FRAMES, True)
    want = np.round(x.T * 2**15) / 2**15
    np.testing.assert_array_equal(_read_all(unknown), want)  # every block, the last ending at the end of the file
    seq = open_sequence(unknown)
    got = np.concatenate([b for _, b in iter_sequence_blocks(seq, 1000, start_frame=13000)], axis=1)
    np.testing.assert_array_equal(got, want[:, 13000:])
    # cut short, it is still refused (its last frame header stays, its data does not)
    raw = unknown.read_bytes()
    (tmp_path / "cut.flac").write_bytes(raw[: len(raw) - 300])
    _one_line(lambda: read_wav_info(tmp_path / "cut.flac"), "cut.flac", "truncated")


# ---------------------------------------------------------------- 2. fmt fields checked against each other


def _fmt_edit(src, dst, offset, value):
    raw = bytearray(src.read_bytes())
    i = raw.find(b"fmt ")
    raw[i + 8 + offset: i + 8 + offset + (2 if offset == 12 else 4)] = struct.pack(
        "<H" if offset == 12 else "<I", value)
    dst.write_bytes(raw)
    return dst


@pytest.mark.parametrize(("subtype", "align"), [("DOUBLE", 9), ("FLOAT", 16), ("FLOAT", 1), ("PCM_16", 3)])
def test_a_wrong_block_align_is_named_in_both_readers(tmp_path, subtype, align):
    """scipy (``bearings``) read float64 samples of a 9-byte block align as float32 and blamed "NaN/inf samples";
    a 16-byte align on 2 x float32 read half the frames as noise; libsndfile (``passive``) took it silently."""
    good = _wav(tmp_path / "g.wav", _signal(channels=2), subtype=subtype)
    bad = _fmt_edit(good, tmp_path / "a.wav", 12, align)
    bytes_per = {"DOUBLE": 8, "FLOAT": 4, "PCM_16": 2}[subtype]
    words = ("a.wav", f"block align is {align} for 2 channels of {8 * bytes_per} bits", f"expected {2 * bytes_per}")
    _one_line(lambda: read_wav_info(bad), *words)
    msg = _one_line(lambda: read_two_channel_wav(bad), *words)
    assert "NaN" not in msg


def test_a_sample_rate_that_contradicts_the_byte_rate_is_refused(tmp_path):
    good = _wav(tmp_path / "g.wav", _signal(channels=2).astype(np.float32))
    bad = _fmt_edit(good, tmp_path / "r.wav", 4, 2 * FS)
    _one_line(lambda: read_wav_info(bad), "r.wav", "byte rate", f"{2 * FS} Hz")


# ---------------------------------------------------------------- 4. NaN/inf refused in every float container


@pytest.mark.parametrize(("name", "container", "subtype", "bad"), [
    ("f.wav", "WAV", "FLOAT", np.nan), ("d.wav", "WAV", "DOUBLE", np.inf), ("r.rf64", "RF64", "FLOAT", -np.inf),
    ("w.w64", "W64", "FLOAT", np.nan), ("x.wav", "WAVEX", "FLOAT", np.nan)])
def test_non_finite_samples_are_refused_in_every_float_container(tmp_path, name, container, subtype, bad):
    x = _signal()
    x[25000, 2] = bad
    sf.write(tmp_path / name, x, FS, subtype=subtype, format=container)
    seq = open_sequence(tmp_path / name)
    _one_line(lambda: list(iter_sequence_blocks(seq, 1000, compact=True)), name, "NaN/inf", "6.250 s")
