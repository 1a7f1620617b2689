"""ReplaySampleSource: a finished recording given out as the stream's blocks, every sample once and in order, scaled
as the file reader scales, paced at the asked speed, and closed without a thread left behind."""

from __future__ import annotations

import threading
import time
from datetime import UTC, datetime

import numpy as np
import pytest
import soundfile as sf

from sonartrack.core.errors import InputError
from sonartrack.io.stream.replay import ReplaySampleSource
from sonartrack.io.stream.types import SampleBlock, StreamEvent

RATE = 1000


@pytest.fixture
def recording(tmp_path):
    """A 3-channel int16 WAV of 2.35 s (the last block short) whose name carries its start time."""
    t = np.arange(2350)
    x = np.stack([np.sin(t / 5.0), np.cos(t / 9.0), np.sin(t / 13.0) * 0.25], axis=1) * 0.5
    path = tmp_path / "rec_20240517_120000.wav"
    sf.write(path, x, RATE, subtype="PCM_16")
    return path, sf.read(path, dtype="float32")[0]


def test_replay_gives_every_sample_once_in_order(recording):
    path, truth = recording
    src = ReplaySampleSource(path, speed=float("inf"), block_s=0.1)
    assert (src.header.channels, src.header.rate_hz) == (3, RATE)
    assert src.header.start_utc == datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC)
    blocks = [b for b in src if isinstance(b, SampleBlock)]
    firsts = [b.first_index for b in blocks]
    assert firsts == sorted(firsts) and firsts[0] == 0
    assert all(b.first_index + len(b.samples) == n.first_index for b, n in zip(blocks, blocks[1:], strict=False))
    got = np.concatenate([b.samples for b in blocks])
    assert got.shape == truth.shape
    np.testing.assert_allclose(got, truth, atol=1e-6)


def test_replay_is_paced_and_closes(recording):
    path, _ = recording
    src = ReplaySampleSource(path, speed=10.0, block_s=0.1)  # 2.35 s of data in ~0.235 s
    t0 = time.monotonic()
    n = sum(isinstance(b, SampleBlock) for b in src)
    elapsed = time.monotonic() - t0
    assert n == 24
    assert elapsed >= 0.2  # not given out faster than 10x real time (a lower bound only: never an upper one)
    slow = ReplaySampleSource(path, speed=0.01, block_s=0.1)
    it = iter(slow)
    assert isinstance(next(it), SampleBlock)
    slow.close()
    assert not any(t.name == "sonartrack-replay-source" and t.is_alive() for t in threading.enumerate())


def test_replay_without_start_time_says_so(tmp_path):
    path = tmp_path / "plain.wav"
    sf.write(path, np.zeros((500, 2)), RATE, subtype="PCM_16")
    items = list(ReplaySampleSource(path, speed=float("inf")))
    assert isinstance(items[0], StreamEvent) and items[0].kind == "no_start_time"


def test_replay_refuses_bad_speed_and_missing_file(recording, tmp_path):
    path, _ = recording
    with pytest.raises(InputError, match="--speed"):
        ReplaySampleSource(path, speed=0.0)
    with pytest.raises(InputError, match="not found"):
        ReplaySampleSource(tmp_path / "nope.wav")
