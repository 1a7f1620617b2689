"""A recording as a sequence of files (io/recording_sequence.py): windows stitched across file boundaries equal
those of the one-file recording; gaps and overlaps found from names or bext headers; refusals in one line."""

from __future__ import annotations

import struct
from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.recording_sequence import (
    check_no_gaps,
    iter_sequence_blocks,
    list_recording_files,
    name_start_utc,
    open_sequence,
    present_windows,
)
from sonartrack.io.recording_writer import recording_writer
from sonartrack.io.wav_blocks import iter_wav_blocks

FS = 1000
W = 400  # window frames: 0.4 s, so file boundaries fall inside windows


def _signal(seconds, channels=3, seed=0):
    return np.random.default_rng(seed).uniform(-0.9, 0.9, (channels, int(seconds * FS)))


def _write(path, x, fmt="float32"):
    with recording_writer(path, x.shape[0], FS, fmt) as w:
        w.write(x)
    return path


def _blocks(seq):
    got = list(iter_sequence_blocks(seq, W))
    return np.array([t for t, _ in got]), [b for _, b in got]


def test_consecutive_files_read_as_the_one_recording(tmp_path):
    """Three files of 2.5, 3.0 and 2.7 s, named to the second (the 0.5 s of the second name is inside the 1 s
    tolerance): the windows equal those of the same samples in one file, formats mixed."""
    x = _signal(8.2)
    _write(tmp_path / "whole.wav", x)
    cuts = [0, 2500, 5500, 8200]
    names = ["SM4_20240517_134500.wav", "SM4_20240517_134502.flac", "SM4_20240517_134505.wav"]
    fmts = ["float32", "int24", "float32"]
    folder = tmp_path / "rec"
    folder.mkdir()
    for name, fmt, a, b in zip(names, fmts, cuts, cuts[1:], strict=False):
        _write(folder / name, x[:, a:b], fmt)
    seq = open_sequence(folder)
    assert seq.time_source == "names" and not seq.gaps and not seq.overlaps
    assert seq.start_utc == datetime(2024, 5, 17, 13, 45, 0, tzinfo=UTC)
    assert [f.first_frame for f in seq.files] == cuts[:3] and seq.frames == 8200
    times, blocks = _blocks(seq)
    want = list(iter_wav_blocks(tmp_path / "whole.wav", W))
    assert len(blocks) == len(want) == 20
    np.testing.assert_allclose(times, np.arange(20) * W / FS)
    for got, ref in zip(blocks, want, strict=True):
        np.testing.assert_allclose(got, ref, rtol=0, atol=2.0**-24)  # the FLAC part: within half a 24-bit step
    assert present_windows(seq, W).all()


def test_a_gap_is_reported_and_its_windows_are_missing(tmp_path):
    """File 2 starts 10 s after file 1 (3.0 s long): a 7 s gap at 3.0..10.0 s; windows 7 (2.8-3.2 s) to 24
    (9.6-10.0 s) touch it; the windows after it hold file 2's samples at their times."""
    a, b = _signal(3.0, seed=1), _signal(2.0, seed=2)
    _write(tmp_path / "r_20240101_000000.wav", a)
    _write(tmp_path / "r_20240101_000010.wav", b)
    seq = open_sequence(tmp_path / "r_*.wav")
    assert len(seq.gaps) == 1 and not seq.overlaps
    gap = seq.gaps[0]
    assert (gap.kind, gap.start_s, gap.end_s) == ("gap", 3.0, 10.0)
    assert "gap of 7.000 s" in gap.describe()
    mask = present_windows(seq, W)
    assert mask.size == 30 and mask[:7].all() and not mask[7:25].any() and mask[25:].all()
    times, blocks = _blocks(seq)
    np.testing.assert_allclose(times, np.r_[np.arange(7), np.arange(25, 30)] * 0.4)
    np.testing.assert_array_equal(blocks[7], b[:, :W].astype(np.float32))
    np.testing.assert_array_equal(blocks[6], a[:, 2400:2800].astype(np.float32))
    with pytest.raises(InputError, match="1 gap"):
        check_no_gaps(seq)


def test_an_overlap_is_reported_and_the_later_copy_dropped(tmp_path):
    """File 2 holds the samples from 2.5 s but is named 2 s, before file 1 (4 s) ends: the names rule, so its first
    2 s (stated 2..4 s) are dropped and the rest follows file 1 at 4 s."""
    x = _signal(6.5)
    _write(tmp_path / "r_20240101_000000.wav", x[:, :4000])
    _write(tmp_path / "r_20240101_000002T.wav", x[:, 2500:])  # 2.5 s: the pattern still finds 000002
    seq = open_sequence(tmp_path, name_pattern="r_%Y%m%d_%H%M%S")
    assert seq.gaps == () and len(seq.overlaps) == 1
    o = seq.overlaps[0]
    assert (o.start_s, o.end_s) == (2.0, 4.0)  # stated at 2.0 s: 2 s (2000 frames) dropped
    assert seq.files[1].skip_frames == 2000 and seq.files[1].first_frame == 4000


def test_header_times_take_precedence_over_names(tmp_path):
    def bwf(path, start_time, frames):
        bext = bytes(320) + b"2024-05-17" + start_time.encode() + struct.pack("<Q", 0) + bytes(322)
        fmt = struct.pack("<HHIIHH", 1, 2, FS, FS * 4, 4, 16)
        data = np.zeros((frames, 2), np.int16).tobytes()
        body = b"WAVE" + b"bext" + struct.pack("<I", len(bext)) + bext + b"fmt " + struct.pack("<I", 16) + fmt
        body += b"data" + struct.pack("<I", len(data)) + data
        path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)

    bwf(tmp_path / "a_20000101_000000.wav", "10:00:00", 1000)
    bwf(tmp_path / "b_20000101_000001.wav", "10:00:03", 1000)
    seq = open_sequence(tmp_path)
    assert seq.time_source == "header" and seq.start_utc == datetime(2024, 5, 17, 10, tzinfo=UTC)
    assert [(g.start_s, g.end_s) for g in seq.gaps] == [(1.0, 3.0)]
    names = open_sequence(tmp_path, time_source="names")
    assert names.gaps == () and names.start_utc == datetime(2000, 1, 1, tzinfo=UTC)


def test_name_patterns():
    assert name_start_utc("AMAR.20240517T134507Z.wav") == datetime(2024, 5, 17, 13, 45, 7, tzinfo=UTC)
    assert name_start_utc("5783.240517134507.wav", ".%y%m%d%H%M%S") == datetime(2024, 5, 17, 13, 45, 7, tzinfo=UTC)
    assert name_start_utc("x_20240517_134507_250.wav", "*_%Y%m%d_%H%M%S_%f*") == datetime(2024, 5, 17, 13, 45, 7,
                                                                                          250000, tzinfo=UTC)
    assert name_start_utc("take3.wav") is None
    assert name_start_utc("r_20241399_000000.wav") is None  # month 13: no date
    with pytest.raises(InputError, match="unsupported directive %z"):
        name_start_utc("a.wav", "%Y%z")


def _one_line(fn, *words):
    with pytest.raises(InputError) as e:
        fn()
    assert "\n" not in str(e.value)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_refusals(tmp_path):
    _write(tmp_path / "r_20240101_000000.wav", _signal(1.0, channels=3))
    _write(tmp_path / "r_20240101_000001.wav", _signal(1.0, channels=2))
    _one_line(lambda: open_sequence(tmp_path), "r_20240101_000001.wav has 2 channels", "3")
    other = tmp_path / "rate"
    other.mkdir()
    _write(other / "a_20240101_000000.wav", _signal(1.0))
    with recording_writer(other / "a_20240101_000001.wav", 3, 2000, "float32") as w:
        w.write(_signal(1.0))
    _one_line(lambda: open_sequence(other), "2000 Hz", "1000 Hz")
    empty = tmp_path / "empty"
    empty.mkdir()
    _one_line(lambda: list_recording_files(empty), "holds no recording")
    _one_line(lambda: list_recording_files(tmp_path / "nothing_*.wav"), "no file matches")
    untimed = tmp_path / "untimed"
    untimed.mkdir()
    for k in range(2):
        _write(untimed / f"take{k}.wav", _signal(1.0, seed=k))
    _one_line(lambda: open_sequence(untimed), "cannot place the 2 files in time", "contiguous")
    _one_line(lambda: open_sequence(untimed, time_source="names"), "no start time in the file name take0.wav")
    seq = open_sequence(untimed, time_source="contiguous")
    assert [f.first_frame for f in seq.files] == [0, 1000] and seq.start_utc is None


def test_a_single_untimed_file_and_nan_naming_the_file(tmp_path):
    x = _signal(2.0)
    x[1, 1500] = np.nan
    _write(tmp_path / "take.wav", x)
    seq = open_sequence(tmp_path / "take.wav")
    assert seq.time_source == "none" and seq.frames == 2000
    blocks = iter_sequence_blocks(seq, W)
    for _ in range(3):
        next(blocks)
    with pytest.raises(InputError, match=r"take\.wav holds NaN/inf.*1\.200 s"):
        next(blocks)


def test_memory_does_not_grow_with_the_sequence(tmp_path):
    """Four 24-bit files of 6 MB (16 channels, 30 s at 4 kHz each) read in 1000-frame windows: the traced peak
    stays near a few windows, far under one file."""
    import tracemalloc

    rng = np.random.default_rng(0)
    for k in range(4):
        with recording_writer(tmp_path / f"r_20240101_00{k // 2:02d}{30 * (k % 2):02d}.wav", 16, 4000,
                              "int24") as w:
            for _ in range(30):
                w.write(rng.uniform(-0.5, 0.5, (16, 4000)))
    seq = open_sequence(tmp_path)
    assert seq.gaps == () and seq.frames == 480_000
    tracemalloc.start()
    n = 0
    for _, block in iter_sequence_blocks(seq, 1000):
        n += block.shape[1]
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert n == 480_000
    assert peak < (tmp_path / "r_20240101_000000.wav").stat().st_size / 10, peak


def test_one_file_gives_the_single_file_readers_blocks_and_layout(tmp_path):
    """The same values and the same memory layout (a (channels, frames) view of a frames x channels array) as
    io/wav_blocks.py, so that the front end sums in the same order; an excerpt reads only its own windows."""
    x = _signal(4.1)
    path = _write(tmp_path / "one.wav", x)
    seq = open_sequence(path)
    ref = list(iter_wav_blocks(path, W))
    got = [b for _, b in iter_sequence_blocks(seq, W)]
    assert len(got) == len(ref) == 10
    for a, b in zip(got, ref, strict=True):
        np.testing.assert_array_equal(a, b)
        assert a.T.flags.c_contiguous and b.T.flags.c_contiguous
    part = list(iter_sequence_blocks(seq, W, start_frame=W + 1, stop_frame=5 * W))  # windows 2, 3, 4
    assert [t for t, _ in part] == [2 * W / FS, 3 * W / FS, 4 * W / FS]
    np.testing.assert_array_equal(part[0][1], ref[2])


@pytest.mark.parametrize(("formats", "compact_type"), [(("int24", "float32"), np.float32),
                                                       (("int24", "int32"), np.float64)])
def test_compact_windows_stitched_across_formats_keep_every_value(tmp_path, formats, compact_type):
    """Windows spanning a 24-bit file and the next are float32 only when every file of the run is exact in
    float32 (a 32-bit PCM file keeps them float64); the values are the float64 windows' to the last bit."""
    x = _signal(4.0)
    # 1.8 s then 2.2 s: the second file's name (1 s resolution) lies within the join tolerance of the first's end
    _write(tmp_path / "r_20240101_000000.wav", x[:, :1800], formats[0])
    _write(tmp_path / "r_20240101_000002.wav", x[:, 1800:], formats[1])
    seq = open_sequence(tmp_path)
    assert not seq.gaps and len(seq.files) == 2
    wide = [b for _, b in iter_sequence_blocks(seq, W)]
    compact = [b for _, b in iter_sequence_blocks(seq, W, compact=True)]
    assert len(compact) == len(wide) == 10  # window 4 (frames 1600..2000) lies across the join
    for c, w in zip(compact, wide, strict=True):
        assert c.dtype == compact_type and c.T.flags.c_contiguous
        np.testing.assert_array_equal(c.astype(np.float64), w)
