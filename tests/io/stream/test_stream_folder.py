"""FolderSampleSource on a folder written during the test: a WAV whose header states no length, written in chunks
(its header itself in two pieces), then a second file that follows it, then one after a gap."""

from __future__ import annotations

import struct
import threading
import time
from pathlib import Path

import numpy as np

from sonartrack.io.stream.folder import FolderSampleSource
from sonartrack.io.stream.types import SampleBlock, StreamEvent

RATE, CHANNELS = 1000, 2


def _wav_header(fmt_tag: int, bits: int) -> bytes:
    """A RIFF/WAVE header written as a recorder starts a file: sizes 0 (unknown yet), written by hand."""
    align = CHANNELS * bits // 8
    fmt = struct.pack("<HHIIHH", fmt_tag, CHANNELS, RATE, RATE * align, align, bits)
    return b"RIFF" + struct.pack("<I", 0) + b"WAVE" + b"fmt " + struct.pack("<I", 16) + fmt + b"data" + b"\0\0\0\0"


def _samples(first: int, n: int) -> np.ndarray:
    t = np.arange(first, first + n)
    return np.stack([np.sin(t / 7.0), np.cos(t / 11.0)], axis=1) * 0.5


def _writer(folder: Path, fmt: str):
    """Writes rec_..._120000 in chunks (header split), rec_..._120001 (follows it), rec_..._120005 (after a gap)."""
    def pcm(x):
        return (np.round(x * 32768).astype("<i2").tobytes() if fmt == "int16" else x.astype("<f4").tobytes())

    tag, bits = (1, 16) if fmt == "int16" else (3, 32)
    first = folder / "rec_20240517_120000.wav"
    head = _wav_header(tag, bits)
    with open(first, "wb") as fh:
        fh.write(head[:20])
        fh.flush()
        time.sleep(0.05)
        fh.write(head[20:])
        x = _samples(0, 1000)
        for a in range(0, 1000, 130):  # chunks that are no whole number of blocks
            fh.write(pcm(x[a:a + 130]))
            fh.flush()
            time.sleep(0.02)
    for name, first_index in (("rec_20240517_120001.wav", 1000), ("rec_20240517_120005.wav", 5000)):
        time.sleep(0.05)
        (folder / name).write_bytes(head + pcm(_samples(first_index, 500)))


def _run(tmp_path: Path, fmt: str):
    w = threading.Thread(target=_writer, args=(tmp_path, fmt))
    w.start()
    time.sleep(0.01)
    with FolderSampleSource(tmp_path, block_s=0.1, poll_s=0.01, idle_end_s=0.4) as source:
        items = list(source)
    w.join()
    assert not source.alive
    return source, items


def test_growing_file_then_a_following_file_then_a_gap(tmp_path):
    source, items = _run(tmp_path, "float32")
    assert source.header.channels == CHANNELS and source.header.rate_hz == RATE
    assert source.header.start_utc.isoformat() == "2024-05-17T12:00:00+00:00"
    events = [(i.kind, i.first_index, i.count) for i in items if isinstance(i, StreamEvent)]
    assert events == [("gap", 1500, 3500)]
    blocks = [i for i in items if isinstance(i, SampleBlock)]
    firsts = [b.first_index for b in blocks]
    assert firsts == list(range(0, 1500, 100)) + list(range(5000, 5500, 100))  # the same blocks whatever the timing
    x = np.concatenate([b.samples for b in blocks])
    expected = np.concatenate([_samples(0, 1500), _samples(5000, 500)]).astype(np.float32)
    assert np.array_equal(x, expected)


def test_int16_is_scaled_as_the_file_reader_scales(tmp_path):
    _, items = _run(tmp_path, "int16")
    x = np.concatenate([i.samples for i in items if isinstance(i, SampleBlock)])
    expected = np.concatenate([_samples(0, 1500), _samples(5000, 500)])
    assert np.max(np.abs(x - expected)) <= 2.0**-16 + 1e-7


def test_a_file_of_other_channels_is_refused_and_skipped(tmp_path):
    head = _wav_header(3, 32)
    (tmp_path / "rec_20240517_120000.wav").write_bytes(head + _samples(0, 300).astype("<f4").tobytes())
    mono = head.replace(struct.pack("<HH", 3, CHANNELS), struct.pack("<HH", 3, 1), 1)
    mono = mono[:28] + struct.pack("<IH", RATE * 4, 4) + mono[34:]  # byte rate and block align of one channel
    (tmp_path / "rec_20240517_120001.wav").write_bytes(mono + b"\0" * 400)
    with FolderSampleSource(tmp_path, poll_s=0.01, idle_end_s=0.2) as source:
        items = list(source)
    refused = [i for i in items if isinstance(i, StreamEvent)]
    assert [i.kind for i in refused] == ["refused"] and "1 channels" in refused[0].detail
    assert sum(i.samples.shape[0] for i in items if isinstance(i, SampleBlock)) == 300
