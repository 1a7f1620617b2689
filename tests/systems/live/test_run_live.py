"""run_live: a source in, updates published, the result at the end; a restart from its checkpoint resumes."""

import numpy as np

from sonartrack.io.navigation import read_navigation
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader
from sonartrack.systems.live import run_live
from sonartrack.systems.passive import PassiveSettings

from .conftest import START

SETTINGS = PassiveSettings(spacing_m=2.5, min_track_s=60.0)


class Source:
    """A sample source as io/stream's: ``header`` and an iterator of blocks (5000 samples) and events."""

    def __init__(self, x, fs, first=0, stop=None):
        self.header = StreamHeader(x.shape[1], fs, "float32", START, source="test")
        self.x, self.first, self.stop = x, first, len(x) if stop is None else stop

    def __iter__(self):
        yield StreamEvent("connected", "test source")
        for i in range(self.first, self.stop, 5000):
            yield SampleBlock(i, self.x[i:min(i + 5000, self.stop)])


def test_run_live_publishes_and_resumes_from_its_checkpoint(scene, tmp_path):
    out, x, fs = scene
    nav = read_navigation(out / "nav.csv")
    ckpt = tmp_path / "live.ckpt"
    first: list[dict] = []
    r1 = run_live(Source(x, fs, stop=300_000), nav, SETTINGS, first.append, checkpoint=ckpt)
    assert r1 is not None and r1.duration_s == 75.0 and ckpt.is_file()
    assert sum(u["type"] == "btr" for u in first) == 75
    assert first[-3]["type"] == "targets"  # the final refresh, then its ownship, then the end said in the health
    assert first[-1]["type"] == "health" and any(e.startswith("end:") for e in first[-1]["events"])
    again: list[dict] = []
    chosen = []
    r2 = run_live(Source(x, fs, first=300_000), nav, SETTINGS, again.append, checkpoint=ckpt,
                  ready=chosen.append)
    assert len(chosen) == 1
    history = [u["t_s"] for u in again[:80] if u["type"] == "btr"]
    assert history[:75] == [k + 0.5 for k in range(75)]  # the display's history back first
    assert r2.duration_s == 150.0
    assert np.all(np.diff(r2.record.time_s) == 1.0) and r2.record.time_s[0] == 0.5
    assert {u["type"] for u in again} >= {"btr", "tracks", "health", "targets", "ownship"}
