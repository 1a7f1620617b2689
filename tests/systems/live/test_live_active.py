"""Active pings live: a simulated active scene streamed as ping frames (simulate --kind active --stream), read by
the TCP source and run ping by ping by the live active chain.

- on the same pings and navigation the live run's tracks, contacts and B-scan ARE run_active's on the files
  simulate writes (one per-ping core, systems/active/run.py ``_Chain``);
- with the navigation as the ship's fixes arriving around the pings (the source and the array towed behind the
  ship), the growing fixes give the tracks the whole log gives, and the towed bodies stand where the scene's own
  platforms put them (nav.csv, the simulator's, not the live tow model);
- the active target rows stand where the scene's truth puts a target (or its mirror: the side undecided)."""

from __future__ import annotations

import threading
from datetime import timedelta

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.io.stream.tcp import TcpSampleSource
from sonartrack.io.stream.types import NavFix, PingBlock
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.live.active import LiveActive

SETTINGS = ActiveSettings(spacing_m=0.5)
SOURCE_TOW_M, ARRAY_TOW_M = 300.0, 450.0  # the scene's defaults (scene.toml [sonar])


@pytest.fixture(scope="module")
def active_scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("live_active")
    assert main(["simulate", "--kind", "active", "--duration-s", "300", "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def streamed(active_scene):
    """The scene's pings as the TCP source gives them, and its header."""
    import tomllib

    from sonartrack.sim.active_scene import ActiveSceneSettings
    from sonartrack.systems.simulate.stream import ActiveSceneStreamer

    scene = ActiveSceneSettings.model_validate(tomllib.loads((active_scene / "scene.toml").read_text()))
    assert (scene.sonar.source_tow_m, scene.sonar.array_tow_m) == (SOURCE_TOW_M, ARRAY_TOW_M)
    streamer = ActiveSceneStreamer(scene, speed=1000.0)
    thread = threading.Thread(target=streamer.serve, daemon=True)
    thread.start()
    source = TcpSampleSource("127.0.0.1", streamer.port)
    try:
        pings = [item for item in source if isinstance(item, PingBlock)]
    finally:
        source.close()
        thread.join(30)
    return pings, source.header


@pytest.fixture(scope="module")
def file_run(active_scene):
    from sonartrack.systems.active.run import run_active
    from sonartrack.systems.active.scene_files import iter_pings, read_active_nav, read_ping_table

    table = read_ping_table(active_scene / "ping_table.csv")
    return run_active(iter_pings(active_scene, table), table, read_active_nav(active_scene / "nav.csv"), SETTINGS)


def _fixes(active_scene, start_utc) -> list[NavFix]:
    """The ship's fixes, once a second, from nav.csv's ownship columns (lat/lon about the scene's origin)."""
    from sonartrack.io.nmea import LocalProjection
    from sonartrack.systems.simulate.recording_layout import ORIGIN_DEG

    nav = pd.read_csv(active_scene / "nav.csv")
    lat, lon = LocalProjection(*ORIGIN_DEG).latlon(nav.x_m.to_numpy(), nav.y_m.to_numpy())
    return [NavFix(start_utc + timedelta(seconds=float(t)), float(a), float(b), float(h))
            for t, a, b, h in zip(nav.time_s, lat, lon, nav.heading_deg, strict=True)]


def _assert_same_tracks(live, ref):
    a, b = live.tracks, ref.tracks
    assert len(b.tracks) > 20 and b.tracks.confirmed.any()
    for f in ("time_s", "track_id", "confirmed", "existence", "x"):
        np.testing.assert_array_equal(getattr(a.tracks, f), getattr(b.tracks, f), err_msg=f)
    np.testing.assert_array_equal(a.P, b.P)
    np.testing.assert_array_equal(live.contacts.xy, ref.contacts.xy)
    np.testing.assert_array_equal(live.gated_out, ref.gated_out)
    np.testing.assert_array_equal(a.sides.track_id, b.sides.track_id)
    np.testing.assert_array_equal(a.sides.log_lr, b.sides.log_lr)


def test_the_stream_carries_the_pings_simulate_writes(active_scene, streamed):
    from sonartrack.systems.active.scene_files import iter_pings, read_ping_table

    pings, _ = streamed
    table = read_ping_table(active_scene / "ping_table.csv")
    files = list(iter_pings(active_scene, table))
    assert [p.ping for p in pings] == [n for n, _, _ in files] == list(range(1, 11))
    for p, (_, t, x) in zip(pings, files, strict=True):
        assert p.transmit_time_s == t and p.kind == "lfm" and p.fs_hz == table.fs_hz[0]
        np.testing.assert_array_equal(p.samples, x)


@pytest.fixture(scope="module")
def live_known_nav(active_scene, streamed):
    """The live chain on the streamed pings with the file run's navigation; (result, updates)."""
    from sonartrack.systems.active.scene_files import read_active_nav

    pings, header = streamed
    live = LiveActive(SETTINGS, header, nav=read_active_nav(active_scene / "nav.csv"))
    updates = [u for p in pings for u in live.push_ping(p)]
    result, last = live.finish()
    return result, updates + last


def test_live_tracks_equal_the_file_runs(live_known_nav, file_run):
    live, _ = live_known_nav
    _assert_same_tracks(live, file_run)
    np.testing.assert_array_equal(live.mftd.statistic, file_run.mftd.statistic)
    np.testing.assert_array_equal(live.bscan.level, file_run.bscan.level)
    np.testing.assert_array_equal(live.ping_time_s, file_run.ping_time_s)


def test_each_pings_bscan_is_the_file_chains_and_shows_the_echo(active_scene, live_known_nav, file_run):
    _, updates = live_known_nav
    ref = file_run.bscan
    bscans = [u for u in updates if u["type"] == "bscan"]
    assert [u["t_s"] for u in bscans] == list(ref.time_s)  # the first ping's with the second's (the interval)
    for u, level in zip(bscans, ref.level, strict=True):
        np.testing.assert_allclose(np.array(u["level_db"]), 10 * np.log10(np.maximum(level, 1e-12)), atol=0.006)
        np.testing.assert_allclose(u["bearing_deg"], ref.cone_deg)
        np.testing.assert_allclose(u["range_m"], 750.0 * ref.travel_time_s)  # c tau / 2
    # the loudest echo of the scene (truth.csv, independent of the chain): at its beam and delay the B-scan stands
    # well above the noise (s has mean 1 in noise: 0 dB)
    truth = pd.read_csv(active_scene / "truth.csv")
    loud = truth[truth.in_window & ~truth.in_blast].sort_values("snr_db").iloc[-1]
    u = bscans[int(loud.ping) - 1]
    beam = int(np.argmin(np.abs(np.array(u["bearing_deg"]) - loud.cone_deg)))
    rng = int(np.argmin(np.abs(np.array(u["range_m"]) - 750.0 * loud.lfm_delay_s)))
    near = np.array(u["level_db"])[max(beam - 1, 0):beam + 2, max(rng - 1, 0):rng + 2]
    assert near.max() > 13.0 and np.median(u["level_db"]) < 6.0, (near.max(), np.median(u["level_db"]))
    assert u["detections"] >= 1


@pytest.fixture(scope="module")
def live_fixes(active_scene, streamed):
    """The live chain with the navigation as fixes: each ping first, then the fixes up to the end of its
    listening window (as they come over UDP beside the TCP pings); (chain, result, updates, whole-log geometry)."""
    from sonartrack.systems.live.active_geometry import LiveGeometry
    from sonartrack.systems.live.navigation import LiveNavigation

    pings, header = streamed
    fixes = _fixes(active_scene, header.start_utc)
    live = LiveActive(SETTINGS, header, source_tow_m=SOURCE_TOW_M, array_tow_m=ARRAY_TOW_M)
    updates, k = [], 0
    for p in pings:
        updates += live.push_ping(p)
        due = p.transmit_time_s + p.samples.shape[1] / p.fs_hz
        while k < len(fixes) and (fixes[k].utc - header.start_utc).total_seconds() <= due:
            updates += live.push_nav(fixes[k])
            k += 1
    result, last = live.finish()
    whole = LiveNavigation(header.start_utc)
    for f in fixes:
        whole.push(f)
    return live, result, updates + last, LiveGeometry(whole, SOURCE_TOW_M, ARRAY_TOW_M).current()


def test_growing_fixes_give_the_whole_logs_tracks(active_scene, streamed, live_fixes):
    from sonartrack.systems.active.run import run_active
    from sonartrack.systems.active.scene_files import iter_pings, read_ping_table

    _, result, updates, whole = live_fixes
    *health, end = [u for u in updates if u["type"] == "health"]
    assert len(health) == 10 and all(u["nav"] == "ok" and not u["events"] for u in health), health  # never late
    assert "ended" in end["events"][0]
    table = read_ping_table(active_scene / "ping_table.csv")
    _assert_same_tracks(result, run_active(iter_pings(active_scene, table), table, whole, SETTINGS))


def test_the_towed_bodies_stand_where_the_scene_puts_them(active_scene, live_fixes):
    """The tow model on the ship's fixes against the simulator's platforms (nav.csv: its own towed geometry)."""
    _, _, _, whole = live_fixes
    nav = pd.read_csv(active_scene / "nav.csv")
    t = nav.time_s.to_numpy()[5:-5]
    sim_tx = nav[["source_x_m", "source_y_m"]].to_numpy()[5:-5]
    sim_rx = nav[["array_x_m", "array_y_m"]].to_numpy()[5:-5]
    assert np.abs(whole.tx_at(t) - sim_tx).max() < 1.0 and np.abs(whole.rx_at(t) - sim_rx).max() < 1.0
    heading = np.rad2deg(whole.heading_at(t))
    err = (heading - nav.array_heading_deg.to_numpy()[5:-5] + 180.0) % 360.0 - 180.0
    assert np.abs(err).max() < 0.1


def test_the_active_targets_stand_at_a_scene_target(active_scene, live_fixes):
    """The last target table: each row is a target of the truth (or its mirror, while the side is undecided),
    its range sd a fraction of its range; the B-scan shows the scan's tracks."""
    _, _, updates, _ = live_fixes
    last = [u for u in updates if u["type"] == "active_targets"][-1]
    assert last["rows"], "no active target"
    truth = pd.read_csv(active_scene / "truth.csv")
    now = truth[truth.time_s == last["t_s"]][["x_m", "y_m"]].to_numpy()
    for row in last["rows"]:
        assert row["side"] in ("starboard", "port", "undecided")
        places = [(row["x_m"], row["y_m"])] + ([(row["mirror"]["x_m"], row["mirror"]["y_m"])] if row["mirror"] else [])
        miss = min(np.hypot(*(now - np.array(p)).T).min() for p in places)
        assert miss < 500.0, (row, miss)
        assert 0 < row["range_sd_m"] < 0.1 * row["range_m"] and len(row["ellipse"]) > 10
    scan = [u for u in updates if u["type"] == "bscan"][-1]
    confirmed = [t for t in scan["tracks"] if t["status"] == "confirmed"]
    assert {t["id"] for t in confirmed} >= {row["track"] for row in last["rows"]}
    assert all(0 <= t["cone_deg"] <= 180 for t in scan["tracks"])


def test_run_live_tracks_a_streams_pings_with_the_navigations_fixes(active_scene, streamed, live_fixes):
    """A stream of pings alone with an NMEA source: run_live builds no passive chain (the stream's rate is a
    baseband's), runs the pings with the fixes, and returns the active chain's result (the fixes come first here:
    the pings wait for them, so the run is the whole log's)."""
    from sonartrack.systems.live import run_live
    from sonartrack.systems.passive import PassiveSettings

    pings, header = streamed
    _, reference, _, _ = live_fixes
    fixes, sent = _fixes(active_scene, header.start_utc), threading.Event()

    def navigation():
        yield from fixes
        sent.set()

    class Pings:
        def __init__(self):
            self.header = header

        def __iter__(self):
            sent.wait(30)
            yield from pings

    out = []
    result = run_live(Pings(), navigation(), PassiveSettings(spacing_m=0.5), out.append, warm=False,
                      active_settings=SETTINGS,
                      active_options={"source_tow_m": SOURCE_TOW_M, "array_tow_m": ARRAY_TOW_M})
    _assert_same_tracks(result, reference)
    kinds = {u["type"] for u in out}
    assert {"bscan", "active_targets", "ownship"} <= kinds and "btr" not in kinds


def test_pings_without_navigation_are_shown_not_tracked(streamed):
    from sonartrack.systems.live import run_live
    from sonartrack.systems.passive import PassiveSettings

    pings, header = streamed

    class Pings:
        def __init__(self):
            self.header = header

        def __iter__(self):
            yield from pings[:3]

    out = []
    assert run_live(Pings(), None, PassiveSettings(spacing_m=0.5), out.append, warm=False,
                    active_settings=SETTINGS) is None
    assert [u["type"] for u in out if u["type"] != "health"] == ["bscan"] * 3
    said = [e for u in out if u["type"] == "health" for e in u["events"]]
    assert len(said) == 2 and "not tracked" in said[0] and "ended" in said[1], said


def test_a_ping_the_fixes_do_not_reach_runs_when_the_next_comes_and_says_so(active_scene, streamed):
    """Fixes up to just past ping 2's transmit (short of the 1 s its velocities need): ping 1 runs when ping 2
    comes (the interval), ping 2 waits; ping 3 comes with no newer fix: ping 2 runs on the last fixes with a
    "navigation late" warning (coasting), ping 3 waits."""
    pings, header = streamed
    fixes = _fixes(active_scene, header.start_utc)
    live = LiveActive(SETTINGS, header, source_tow_m=SOURCE_TOW_M, array_tow_m=ARRAY_TOW_M)
    early = [f for f in fixes if (f.utc - header.start_utc).total_seconds() <= pings[1].transmit_time_s + 0.5]
    assert [u for f in early for u in live.push_nav(f)] + live.push_ping(pings[0]) == []
    out = live.push_ping(pings[1])
    assert [u["type"] for u in out] == ["ownship", "bscan", "active_targets", "health"]
    assert out[1]["ping"] == 1 and out[-1]["nav"] == "ok" and [p.ping for p in live.pending] == [2]
    out = live.push_ping(pings[2])
    assert [u["type"] for u in out] == ["ownship", "bscan", "active_targets", "health"]
    assert out[1]["ping"] == 2 and out[-1]["nav"] == "coasting" and "late" in out[-1]["events"][0]
    assert [p.ping for p in live.pending] == [3]


def test_a_checkpoint_and_resume_give_one_runs_tracks(active_scene, streamed, live_fixes, tmp_path):
    """Ping by ping with the fixes (the geometry rebuilt from them on restore): 4 pings, a checkpoint, a new chain
    read from it, the other 6 pings = the uninterrupted live run (itself the whole log's file run); the restored
    chain's display history is the B-scan rows and the target table sent before the checkpoint."""
    pings, header = streamed
    fixes = _fixes(active_scene, header.start_utc)
    live = LiveActive(SETTINGS, header, source_tow_m=SOURCE_TOW_M, array_tow_m=ARRAY_TOW_M)
    k, sent, path = 0, [], tmp_path / "active.ckpt"
    for i, p in enumerate(pings):
        if i == 4:
            live.checkpoint(path)
            live = LiveActive.restore(path)
            before = [u for u in sent if u["type"] in ("bscan", "active_targets")]
            assert live.history() == [u for u in before if u["type"] == "bscan"] + [
                [u for u in before if u["type"] == "active_targets"][-1]]
        sent += live.push_ping(p)
        due = p.transmit_time_s + p.samples.shape[1] / p.fs_hz
        while k < len(fixes) and (fixes[k].utc - header.start_utc).total_seconds() <= due:
            sent += live.push_nav(fixes[k])
            k += 1
    result, _ = live.finish()
    _assert_same_tracks(result, live_fixes[1])
    np.testing.assert_array_equal(result.bscan.level, live_fixes[1].bscan.level)


def test_a_checkpoint_of_another_kind_is_refused(streamed, tmp_path):
    from sonartrack.core.errors import InputError

    path = tmp_path / "x.ckpt"
    path.write_bytes(b"not a pickle")
    with pytest.raises(InputError, match="unreadable"):
        LiveActive.restore(path)
    with pytest.raises(InputError, match="not found"):
        LiveActive.restore(tmp_path / "missing.ckpt")


def test_run_live_ctrl_c_checkpoints_the_pings_and_the_same_command_resumes(active_scene, streamed, file_run,
                                                                             tmp_path):
    """Ctrl-C at the 5th ping of a stream of pings (with the run's navigation) writes FILE.active; the same command
    on the stream replayed from its start publishes the B-scan rows and targets kept, skips the 4 pings it holds,
    runs the other 6: the file run's tracks."""
    from sonartrack.systems.active.scene_files import read_active_nav
    from sonartrack.systems.live import run_live
    from sonartrack.systems.passive import PassiveSettings

    pings, header = streamed

    class Pings:
        def __init__(self, stop_at=None):
            self.header, self.stop_at = header, stop_at

        def __iter__(self):
            for i, p in enumerate(pings):
                if i == self.stop_at:
                    raise KeyboardInterrupt
                yield p

    path, options = tmp_path / "live.ckpt", {"nav": read_active_nav(active_scene / "nav.csv")}
    first, again = [], []
    with pytest.raises(KeyboardInterrupt):
        run_live(Pings(4), None, PassiveSettings(spacing_m=0.5), first.append, warm=False, active_settings=SETTINGS,
                 active_options=options, checkpoint=path)
    assert (tmp_path / "live.ckpt.active").is_file() and not path.exists()
    result = run_live(Pings(), None, PassiveSettings(spacing_m=0.5), again.append, warm=False,
                      active_settings=SETTINGS, active_options=options, checkpoint=path)
    _assert_same_tracks(result, file_run)
    shown = [u["ping"] for u in first if u["type"] == "bscan"]
    assert shown == [1, 2, 3, 4] and [u["ping"] for u in again if u["type"] == "bscan"] == list(range(1, 11))
    said = [e for u in again if u["type"] == "health" for e in u["events"]]
    assert any("skipped" in e for e in said), said
