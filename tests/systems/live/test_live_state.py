"""The live chain keeps running: blocks -> windows through gaps and duplicates, bounded history, navigation
dropouts, checkpoints (issue 31 item 4)."""

from datetime import timedelta

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.navigation import read_navigation
from sonartrack.io.stream.types import NavFix, SampleBlock, StreamEvent, StreamHeader
from sonartrack.systems.live import LivePassive
from sonartrack.systems.live.navigation import LiveNavigation
from sonartrack.systems.live.windows import WindowAssembler
from sonartrack.systems.passive import PassiveSettings

from .conftest import START

SETTINGS = PassiveSettings(spacing_m=2.5, min_track_s=60.0)


def test_windows_are_the_streams_samples_cut_on_its_index():
    x = np.arange(2 * 50, dtype=np.float32).reshape(50, 2)
    asm = WindowAssembler(2, 8)
    out = asm.add(0, x[:5]) + asm.add(5, x[5:13]) + asm.add(10, x[10:20])  # 10..12 again: a duplicate overlap
    assert [k for k, _ in out] == [0, 1]
    np.testing.assert_array_equal(out[1][1], x[8:16].T)
    out = asm.gap(20, 3) + asm.add(23, x[23:41])  # window 2 (16..23) touched by the gap -> zeros (None)
    assert [(k, b is None) for k, b in out] == [(2, True), (3, False), (4, False)]
    np.testing.assert_array_equal(out[2][1], x[32:40].T)
    out = asm.add(45, x[45:50])  # 41..44 missing with no event: a gap all the same; window 5 (40..47) blank
    assert [(k, b is None) for k, b in out] == [(5, True)]


def test_a_stream_joined_late_starts_at_its_own_window():
    asm = WindowAssembler(1, 10)
    out = asm.add(25, np.ones((20, 1), np.float32))
    assert [(k, b is None) for k, b in out] == [(2, True), (3, False)]


def _noise_header(channels=16, fs=4000.0):
    return StreamHeader(channels, fs, "float32", START)


def test_history_is_bounded_and_a_gap_is_blank(scene):
    out, x, fs = scene
    live = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), history_s=40.0, nav=read_navigation(out / "nav.csv"))
    ups = live.push_block(SampleBlock(0, x[:200_000]))
    ups += live.note(StreamEvent("gap", "lost 3 s", 200_000, 12_000))
    ups += live.push_block(SampleBlock(212_000, x[212_000:400_000]))
    assert len(live.rows) == 40 and live.rows[0][0] == 60  # the last 40 windows only
    assert all(rows["time_s"][0] >= 60 for _, rows in live.scans)
    blank = [u for u in ups if u["type"] == "btr" and 50 <= u["t_s"] <= 54]
    assert [u["t_s"] for u in blank] == [50.5, 51.5, 52.5, 53.5]
    assert all(max(u["level_db"]) < 1e-9 for u in blank[:3])  # windows 50-52, touched by the gap: zeros
    assert max(blank[3]["level_db"]) > 4  # window 53 starts clean after it
    health = [u for u in ups if u["type"] == "health"]
    assert health[-1]["gaps"] == 1  # each event is in one health update only (the console logs it once)
    assert [e for h in health for e in h["events"]].count("gap: lost 3 s") == 1
    live.close()


def _fix(t_s, lat=54.0, lon=11.0, heading=0.0):
    return NavFix(START + timedelta(seconds=t_s), lat, lon, heading)


def test_navigation_waits_for_cover_and_coasts_in_a_dropout():
    nav = LiveNavigation(START, timeout_s=5.0)
    for t in range(10):
        nav.push(_fix(t, lat=54.0 + 1e-5 * t, heading=10.0 + t))
    assert nav.covers(8.5) and not nav.covers(9.5)
    assert nav.heading_deg(8.5) == pytest.approx(18.5)
    assert not nav.update(12.0) and nav.update(15.0)  # 6 s without a fix: coasting
    assert nav.heading_deg(15.0) == pytest.approx(19.0)  # held at the last fix
    nav.push(_fix(16, lat=54.0 + 1.6e-4, heading=26.0))
    assert not nav.update(16.5) and nav.dropouts == 1


def test_a_dropout_is_a_visible_warning(scene):
    out, x, fs = scene
    live = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), nav_timeout_s=5.0)
    for t in range(0, 12):
        live.push_nav(_fix(t, lat=54.0 + 3e-5 * t))
    ups = live.push_block(SampleBlock(0, x[:40_000]))  # 10 s: nav covers the scans
    assert [u for u in ups if u["type"] == "health"][-1]["nav"] == "ok"
    ups = live.push_block(SampleBlock(40_000, x[40_000:100_000]))  # to 25 s: no fix after 11 s
    health = [u for u in ups if u["type"] == "health"][-1]
    assert health["nav"] == "coasting" and "coasting" in health["warning"]
    own = live.refresh()[-1]
    assert own["type"] == "ownship" and own["nav"] == "coasting" and own["warning"]
    assert not live.pending  # the scans went on, coasting
    live.close()


def test_checkpoint_restores_the_chain_and_its_display(scene, tmp_path):
    out, x, fs = scene
    nav = read_navigation(out / "nav.csv")
    whole = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), nav=nav)
    whole.push_block(SampleBlock(0, x))
    a = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), nav=nav)
    a.push_block(SampleBlock(0, x[:250_123]))
    a.checkpoint(tmp_path / "live.ckpt")
    a.close()
    b = LivePassive.restore(tmp_path / "live.ckpt")
    assert [u["t_s"] for u in b.history() if u["type"] == "btr"] == [k + 0.5 for k in range(62)]
    b.push_block(SampleBlock(250_123, x[250_123:]))
    ra, rb = whole.finish(), b.finish()
    np.testing.assert_array_equal(rb.tracks.track_id, ra.tracks.track_id)
    np.testing.assert_array_equal(rb.tracks.bearing_deg, ra.tracks.bearing_deg)  # the same windows, one at a time
    np.testing.assert_array_equal(rb.record.level, ra.record.level)
    assert np.array_equal(rb.lofar.statistic, ra.lofar.statistic)
    # the tonal lines survive the restore: the accumulators came back with it (the spectra ring did not), and they
    # find the ships' lines (the scene's 120 and 175 Hz) as the file chain's pass over the whole ring does
    tonal_a = sorted(tg.tonal.line_hz for tg in ra.targets if tg.tonal is not None)
    tonal_b = sorted(tg.tonal.line_hz for tg in rb.targets if tg.tonal is not None)
    assert b.spill.first_window > 0 and len(tonal_b) == len(tonal_a) >= 2
    np.testing.assert_allclose(tonal_b, tonal_a, atol=0.3)
    assert min(abs(np.array(tonal_b) - 120.0)) < 0.5 and min(abs(np.array(tonal_b) - 175.0)) < 0.5
    whole.close()
    b.close()


def test_a_refresh_reads_the_tonals_kept_as_the_windows_came(scene):
    """A refresh's tonal lines come from the per-track accumulators (no pass over the history): the ships' lines,
    as the final pass over the spectra ring finds them."""
    out, x, fs = scene
    live = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), nav=read_navigation(out / "nav.csv"))
    live.push_block(SampleBlock(0, x))
    reads = []
    windows = live.spill.windows
    live.spill.windows = lambda a, b: reads.append((a, b)) or windows(a, b)
    rows = live.refresh()[0]["rows"]
    assert all(b - a <= 1 for a, b in reads)  # one window at a time (the scans' own), never the history
    final = live.finish()
    assert any(b - a > 1 for a, b in reads)  # the final pass reads the ring
    live.close()
    by_track = {tg.track.track_id: tg.tonal.line_hz for tg in final.targets if tg.tonal is not None}
    got = {r["track"]: r["tonal_hz"] for r in rows if r["tonal_hz"] is not None}
    assert len(got) >= 2 and set(got) <= set(by_track)
    for track, hz in got.items():
        assert abs(hz - by_track[track]) < 0.3
        assert min(abs(hz - 120.0), abs(hz - 175.0)) < 0.5


def test_a_foreign_or_old_checkpoint_is_refused(tmp_path):
    import pickle

    (tmp_path / "x.ckpt").write_bytes(pickle.dumps({"format": "sonartrack-live-passive", "version": 0}))
    with pytest.raises(InputError, match="version 0"):
        LivePassive.restore(tmp_path / "x.ckpt")
    (tmp_path / "y.ckpt").write_bytes(b"not a pickle")
    with pytest.raises(InputError, match="unreadable"):
        LivePassive.restore(tmp_path / "y.ckpt")
    with pytest.raises(InputError, match="not found"):
        LivePassive.restore(tmp_path / "none.ckpt")


def test_live_navigation_is_the_file_chains_on_the_same_fixes():
    """The fixes' Navigation equals io/nmea.py navigation_from_track's on the same log (a turn through north and a
    tow), and its heading stays continuous when the oldest fixes are dropped."""
    from sonartrack.io.nmea import GeoTrack, navigation_from_track

    nav = LiveNavigation(START, tow_length_m=300.0, keep_s=1e9)
    heading = (300.0 + 2.0 * np.arange(60)) % 360.0  # 300 -> 58 deg through north
    a = np.deg2rad(heading)
    lat = 54.0 + np.cumsum(3.0 * np.cos(a)) / 111_320.0
    lon = 11.0 + np.cumsum(3.0 * np.sin(a)) / (111_320.0 * np.cos(np.deg2rad(54.0)))
    for t in range(60):
        nav.push(_fix(t, lat=lat[t], lon=lon[t], heading=heading[t]))
    unix = np.array([START.timestamp() + t for t in range(60)], float)
    ref, _ = navigation_from_track(GeoTrack(unix, lat, lon, unix, heading, "HDT"), START, tow_length_m=300.0,
                                   projection=nav.projection)
    got = nav.navigation()
    for name in ("time_s", "x_m", "y_m", "heading_rad", "array_x_m", "array_y_m", "array_heading_rad"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name), err_msg=name)
    short = LiveNavigation(START, keep_s=20.0)
    for t in range(60):
        short.push(_fix(t, lat=lat[t], lon=lon[t], heading=heading[t]))
    assert len(short.fixes) == 21
    np.testing.assert_allclose(short.navigation().heading_rad, ref.heading_rad[-21:], rtol=0, atol=1e-12)


def test_the_streams_full_scale_and_the_calibration_make_pascals(scene):
    """p = x V_fs 1e-6 / 10^((S + G) / 20) (io/calibration.py), V_fs from the stream's header: a hand-worked case,
    the conflicts refused, and the chain's LOFAR power scaled by the square of it."""
    from dataclasses import replace

    from sonartrack.io.calibration import Calibration
    from sonartrack.systems.live.passive import stream_scale

    out, x, fs = scene
    header = replace(_noise_header(x.shape[1], fs), full_scale_v=2.5)
    cal = Calibration(np.array([-170.0]), np.array([20.0]), np.array([1.0]))
    scale, note = stream_scale(header, cal)
    np.testing.assert_allclose(scale, 2.5e-6 / 10 ** (-150.0 / 20.0), rtol=1e-12)  # 79.06 Pa per unit
    assert note is None
    volts, note = stream_scale(header, None)
    assert np.all(volts == 2.5) and "volts, not pascals" in note
    assert stream_scale(_noise_header(x.shape[1], fs), None) == (None, None)
    with pytest.raises(InputError, match="differs from the stream's"):
        stream_scale(header, Calibration(np.array([-170.0]), np.array([20.0]), np.array([5.0])))
    plain = LivePassive(SETTINGS, _noise_header(x.shape[1], fs), nav=read_navigation(out / "nav.csv"))
    cal_live = LivePassive(SETTINGS, header, nav=read_navigation(out / "nav.csv"), calibration=cal)
    n = 40 * int(fs)
    plain.push_block(SampleBlock(0, x[:n]))
    cal_live.push_block(SampleBlock(0, x[:n]))
    assert len(plain.periods) >= 1
    np.testing.assert_allclose(cal_live.periods[0][1], plain.periods[0][1] * scale[0] ** 2, rtol=1e-4)
    plain.close()
    cal_live.close()
