"""Active pings live: a simulated active scene streamed as ping frames (simulate --kind active --stream), read by
the TCP source and run ping by ping by the live active chain: each ping's B-scan row is the file chain's (run_active
on the files simulate writes for the same scene), and its loudest echo stands where the scene's truth puts it."""

from __future__ import annotations

import threading

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.io.stream.tcp import TcpSampleSource
from sonartrack.io.stream.types import PingBlock
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.live.active import LiveActive


@pytest.fixture(scope="module")
def active_scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("live_active")
    assert main(["simulate", "--kind", "active", "--duration-s", "60", "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def streamed(active_scene):
    """The scene's pings as the TCP source gives them, and the live chain's updates."""
    import tomllib

    from sonartrack.sim.active_scene import ActiveSceneSettings
    from sonartrack.systems.simulate.stream import ActiveSceneStreamer

    scene = ActiveSceneSettings.model_validate(tomllib.loads((active_scene / "scene.toml").read_text()))
    streamer = ActiveSceneStreamer(scene, speed=1000.0)
    thread = threading.Thread(target=streamer.serve, daemon=True)
    thread.start()
    source = TcpSampleSource("127.0.0.1", streamer.port)
    pings, updates, live = [], [], None
    try:
        for item in source:
            if isinstance(item, PingBlock):
                live = live or LiveActive(ActiveSettings(spacing_m=0.5), source.header)
                pings.append(item)
                updates += live.push_ping(item)
    finally:
        source.close()
        thread.join(30)
    return pings, updates


def test_the_stream_carries_the_pings_simulate_writes(active_scene, streamed):
    from sonartrack.systems.active.scene_files import iter_pings, read_ping_table

    pings, _ = streamed
    table = read_ping_table(active_scene / "ping_table.csv")
    files = list(iter_pings(active_scene, table))
    assert [p.ping for p in pings] == [n for n, _, _ in files] == [1, 2]
    for p, (_, t, x) in zip(pings, files, strict=True):
        assert p.transmit_time_s == t and p.kind == "lfm" and p.fs_hz == table.fs_hz[0]
        np.testing.assert_array_equal(p.samples, x)


def test_each_pings_bscan_is_the_file_chains_and_shows_the_echo(active_scene, streamed):
    from sonartrack.systems.active.run import run_active
    from sonartrack.systems.active.scene_files import iter_pings, read_active_nav, read_ping_table

    _, updates = streamed
    table = read_ping_table(active_scene / "ping_table.csv")
    ref = run_active(iter_pings(active_scene, table), table, read_active_nav(active_scene / "nav.csv"),
                     ActiveSettings(spacing_m=0.5)).bscan
    assert [u["type"] for u in updates] == ["bscan"] * 2 and [u["t_s"] for u in updates] == list(ref.time_s)
    for u, level in zip(updates, ref.level, strict=True):
        np.testing.assert_allclose(np.array(u["level_db"]), 10 * np.log10(np.maximum(level, 1e-12)), atol=0.006)
        np.testing.assert_allclose(u["bearing_deg"], ref.cone_deg)
        np.testing.assert_allclose(u["range_m"], 750.0 * ref.travel_time_s)  # c tau / 2
    # the loudest echo of the scene (truth.csv, independent of the chain): at its beam and delay the B-scan stands
    # well above the noise (s has mean 1 in noise: 0 dB)
    truth = pd.read_csv(active_scene / "truth.csv")
    loud = truth[truth.in_window & ~truth.in_blast].sort_values("snr_db").iloc[-1]
    u = updates[int(loud.ping) - 1]
    beam = int(np.argmin(np.abs(np.array(u["bearing_deg"]) - loud.cone_deg)))
    rng = int(np.argmin(np.abs(np.array(u["range_m"]) - 750.0 * loud.lfm_delay_s)))
    near = np.array(u["level_db"])[max(beam - 1, 0):beam + 2, max(rng - 1, 0):rng + 2]
    assert near.max() > 13.0 and np.median(u["level_db"]) < 6.0, (near.max(), np.median(u["level_db"]))
    assert u["detections"] >= 1


def test_run_live_sends_a_streams_pings_to_the_active_chain(streamed):
    """A stream of pings alone: run_live publishes a B-scan per ping and builds no passive chain (the stream's rate
    is a baseband's, no passive band fits it); the end is said."""
    from datetime import UTC, datetime

    from sonartrack.io.stream.types import StreamEvent, StreamHeader
    from sonartrack.systems.live import run_live
    from sonartrack.systems.passive import PassiveSettings

    pings, updates = streamed

    class Pings:
        header = StreamHeader(16, pings[0].fs_hz, "float32", datetime(2026, 12, 7, tzinfo=UTC))

        def __iter__(self):
            yield StreamEvent("connected", "test")
            yield from pings

    out = []
    result = run_live(Pings(), None, PassiveSettings(spacing_m=0.5), out.append, warm=False,
                      active_settings=ActiveSettings(spacing_m=0.5))
    assert result is None
    assert [u for u in out if u["type"] == "bscan"] == updates
