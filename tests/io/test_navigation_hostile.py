"""Navigation taken on trust (issue 33): hostile NMEA logs and GPX tracks made here from a known turning track with
the project's own writer (io/nmea.py ``nmea_lines``, checksums recomputed after each edit), and what each gives:
a one-line refusal naming the line, a dropped and reported fix, or a gap judged from the ship's own motion."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.nav_checks import check_logged_heading, drop_position_jumps, navigation_gaps
from sonartrack.io.navigation import Navigation
from sonartrack.io.nmea import (
    LocalProjection,
    check_tow_length,
    navigation_from_track,
    nmea_checksum,
    nmea_lines,
    read_nmea,
)

START = datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC)
LAT0, LON0 = 50.0, -4.0
SPEED = 3.0


def turning_track(n: int = 400, turn_start_s: float = 100.0, rate_deg_s: float = -0.5, turn_deg: float = -45.0):
    """1 Hz: north at 3 m/s, then a steady turn of ``turn_deg`` at ``rate_deg_s``, then straight (x east, y north)."""
    t = np.arange(n, dtype=float)
    heading = np.clip((t - turn_start_s) * rate_deg_s, min(turn_deg, 0), max(turn_deg, 0))
    h = np.deg2rad(heading)
    x = np.concatenate([[0.0], np.cumsum(SPEED * np.sin(0.5 * (h[1:] + h[:-1])))])
    y = np.concatenate([[0.0], np.cumsum(SPEED * np.cos(0.5 * (h[1:] + h[:-1])))])
    return t, x, y, heading % 360.0


def log_lines(n: int = 400):
    """The turning track as RMC + HDT lines (two a fix: the RMC of fix k is line 2k + 1)."""
    t, x, y, heading = turning_track(n)
    lat, lon = LocalProjection(LAT0, LON0).latlon(x, y)
    return nmea_lines(START.timestamp() + t, lat, lon, heading, np.full(n, SPEED / 0.514444), heading)


def edit(line: str, field: int, value: str) -> str:
    """A sentence with one comma-separated field replaced and its checksum recomputed (a logger that wrote it)."""
    parts = line[1:line.index("*")].split(",")
    parts[field] = value
    body = ",".join(parts)
    return f"${body}*{nmea_checksum(body):02X}"


def write(tmp_path, lines, name="nav.nmea"):
    (tmp_path / name).write_text("\r\n".join(lines) + "\r\n")
    return tmp_path / name


def refused(fn, *words):
    with pytest.raises(InputError) as e:
        fn()
    msg = str(e.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


# ------------------------------------------------------------------ sentences that hold no position: by line


@pytest.mark.parametrize("field, value, words", [
    (4, "X", ["line 201", "latitude hemisphere 'X' is not N or S"]),  # pynmea2 makes latitude 0 of it
    (6, "", ["line 201", "longitude hemisphere '' is not E or W"]),
    (3, "5075.000000", ["line 201", "75 minutes"]),  # pynmea2 reads 51.25 deg
    (3, "9100.000000", ["line 201", "91 deg, beyond 90"]),  # ended in a message about sensor_xy_m
    (5, "18100.000000", ["line 201", "181 deg, beyond 180"]),
])
def test_a_position_that_is_no_position_is_refused_by_its_line(tmp_path, field, value, words):
    lines = log_lines(200)
    lines[200] = edit(lines[200], field, value)  # the RMC of fix 100, line 201
    refused(lambda: read_nmea(write(tmp_path, lines)), *words, "fix the", "nav.nmea")


def test_a_heading_outside_the_circle_is_refused_by_its_line(tmp_path):
    lines = log_lines(50)
    lines[21] = edit(lines[21], 1, "400.00")  # an HDT
    refused(lambda: read_nmea(write(tmp_path, lines)), "line 22", "HDT heading 400.00 is outside 0..360")


# ------------------------------------------------------------------ fixes that jump


def _ship(lines, tmp_path):
    track = read_nmea(write(tmp_path, lines)).track
    return track


def test_one_fix_in_the_wrong_hemisphere_is_dropped_and_named(tmp_path):
    clean = _ship(log_lines(), tmp_path)
    lines = log_lines()
    lines[200] = edit(lines[200], 4, "S")  # fix 100 in the southern hemisphere: 11 000 km away and back
    track, warnings = drop_position_jumps(_ship(lines, tmp_path), "nav.nmea")
    assert len(warnings) == 1 and "1 fix(es) dropped" in warnings[0] and "line 201 (12:01:40 UTC)" in warnings[0]
    assert track.time_unix_s.size == clean.time_unix_s.size - 1
    assert START.timestamp() + 100.0 not in track.time_unix_s
    nav, _ = navigation_from_track(track, START, tow_length_m=200.0)
    ref, _ = navigation_from_track(clean, START, tow_length_m=200.0)
    t = ref.time_s
    np.testing.assert_allclose(np.interp(t, nav.time_s, nav.array_x_m), ref.array_x_m, atol=0.05)
    np.testing.assert_allclose(np.interp(t, nav.time_s, nav.array_y_m), ref.array_y_m, atol=0.05)


def test_the_first_fix_off_the_track_is_dropped(tmp_path):
    lines = log_lines(100)
    lines[0] = edit(lines[0], 6, "E")
    track, warnings = drop_position_jumps(_ship(lines, tmp_path), "nav.nmea")
    assert track.time_unix_s[0] == START.timestamp() + 1.0 and "line 1 " in warnings[0]


def test_a_track_that_jumps_and_stays_is_refused(tmp_path):
    lines = log_lines(100)
    for k in range(100, 200, 2):  # every fix from 50 on 1 deg of latitude north
        lines[k] = edit(lines[k], 3, "51" + lines[k].split(",")[3][2:])
    refused(lambda: drop_position_jumps(_ship(lines, tmp_path), "nav.nmea"), "line 99 ", "line 101 ",
            "does not come back", "60 kn")


def test_speed_over_60_kn_is_refused_and_30_kn_kept(tmp_path):
    """A fast leg: fixes 2 s apart that are 70 kn apart are refused; at 30 kn the track is kept as it is."""
    def leg(kn):
        t = np.arange(50) * 2.0
        lat, lon = LocalProjection(LAT0, LON0).latlon(np.zeros(50), kn * 0.514444 * t)
        return nmea_lines(START.timestamp() + t, lat, lon, np.zeros(50), np.full(50, kn), np.zeros(50))
    refused(lambda: drop_position_jumps(_ship(leg(70.0), tmp_path), "nav.nmea"), "moves at 70 kn", "line 1 ")
    track = _ship(leg(30.0), tmp_path)
    assert drop_position_jumps(track, "nav.nmea") == (track, [])


# ------------------------------------------------------------------ headings against the course made good


def _nav(lines, tmp_path):
    track = _ship(lines, tmp_path)
    return navigation_from_track(track, START)[0], track.heading_source


def test_headings_in_radians_are_refused(tmp_path):
    """HDT in radians (0..5.5 over a 45 deg turn): 0.17 km for a 3.79 km target before; now refused."""
    lines = log_lines()
    for k in range(1, len(lines), 2):
        lines[k] = edit(lines[k], 1, f"{np.deg2rad(float(lines[k].split(',')[1])):.4f}")
    nav, source = _nav(lines, tmp_path)
    refused(lambda: check_logged_heading(nav, source, "nav.nmea"), "the HDT heading", "only when read as radians",
            "log the heading in degrees")


@pytest.mark.parametrize("field, letter, turn_deg", [(4, "S", -45.0), (6, "E", 80.0)])
def test_a_hemisphere_wrong_on_every_fix_is_refused(tmp_path, field, letter, turn_deg):
    """Consistent in itself, but the fixes' course is the heading mirrored (N/S: c -> 180 - c, E/W: c -> -c). A
    course near east-west mirrors into itself under N/S (near north-south under E/W), and the wrong letter then
    changes the geometry little: the tracks here run north, then north-west (N/S) or east (E/W)."""
    n = 400
    t, x, y, heading = turning_track(n, turn_start_s=50.0, rate_deg_s=np.sign(turn_deg), turn_deg=turn_deg)
    lat, lon = LocalProjection(LAT0, LON0).latlon(x, y)
    lines = nmea_lines(START.timestamp() + t, lat, lon, heading, np.full(n, 6.0), heading)
    nav, source = _nav(lines, tmp_path)
    check_logged_heading(nav, source, "nav.nmea")  # the log as it is passes
    lines = [edit(ln, field, letter) if ln.startswith("$GPRMC") else ln for ln in lines]
    nav, source = _nav(lines, tmp_path)
    refused(lambda: check_logged_heading(nav, source, "nav.nmea"), "off the HDT heading",
            "a hemisphere letter (N/S, E/W) wrong on the fixes")


# ------------------------------------------------------------------ tow length, GPX


@pytest.mark.parametrize("tow", [1e9, -5.0, float("nan"), 10_001.0])
def test_implausible_tow_length_is_refused(tow):
    refused(lambda: check_tow_length(tow), "tow length", "0..10000 m", "--tow-length")
    check_tow_length(200.0)
    check_tow_length(0.0)


def test_gpx_latitude_91_is_refused(tmp_path):
    from sonartrack.io.gpx import read_gpx

    (tmp_path / "t.gpx").write_text(
        '<?xml version="1.0"?><gpx version="1.1" creator="x" xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>'
        '<trkpt lat="50.0" lon="-4.0"><time>2024-05-17T12:00:00Z</time></trkpt>'
        '<trkpt lat="91.0" lon="-4.0"><time>2024-05-17T12:00:01Z</time></trkpt></trkseg></trk></gpx>')
    refused(lambda: read_gpx(tmp_path / "t.gpx"), "track point 2 (12:00:01 UTC)", "latitude 91.0")


# ------------------------------------------------------------------ gaps


def _table_nav(t, x, y, heading_deg) -> Navigation:
    h = np.unwrap(np.deg2rad(heading_deg))
    return Navigation(t, x, y, h, x, y, h)


def _gaps(keep, **track):
    t, x, y, heading = turning_track(**track)
    nav = _table_nav(t[keep], x[keep], y[keep], heading[keep])
    return navigation_gaps(nav.time_s, nav, 0.0, float(t[-1]))


def test_a_gap_over_the_turn_is_a_turn_and_one_on_the_straight_is_not():
    keep = np.ones(400, bool)
    keep[120:220] = False  # 100 s over the turn (100..190 s)
    (g,) = _gaps(keep)
    assert (g.start_s, g.end_s) == (119.0, 220.0) and not g.kept_course and "heading changes 36 deg" in g.why
    assert g.reason() == "navigation gap 119-220 s during the track, the ship turned in it"
    keep = np.ones(400, bool)
    keep[250:350] = False  # 100 s on the straight after the turn
    (g,) = _gaps(keep)
    assert g.kept_course and "kept its course" in g.describe()
    keep = np.ones(400, bool)
    keep[30:38] = False  # 9 s: no gap at 1 Hz (> 5 intervals but not > 10 s)
    assert _gaps(keep) == []


def test_a_short_gap_in_a_steady_turn_is_a_turn():
    keep = np.ones(400, bool)
    keep[150:166] = False
    (g,) = _gaps(keep)
    assert not g.kept_course and "heading changes 8 deg" in g.why


def test_a_stop_in_a_gap_with_the_same_heading_is_not_kept_course():
    """Heading the same either side, but the ship made good half its speed across the gap (it stopped in it)."""
    t, x, y, heading = turning_track(400, turn_start_s=1e9)
    y = np.where(t > 200, y - 150.0, y)  # 50 s of the gap 160-260 s spent stopped
    keep = (t <= 160) | (t >= 260)
    nav = _table_nav(t[keep], x[keep], y[keep], heading[keep])
    (g,) = navigation_gaps(nav.time_s, nav, 0.0, 400.0)
    assert not g.kept_course and "1.50 m/s made good across it, 3.00 m/s either side" in g.why


def test_gaps_outside_the_recording_and_a_slow_log():
    keep = np.ones(400, bool)
    keep[300:350] = False
    t, x, y, heading = turning_track()
    nav = _table_nav(t[keep], x[keep], y[keep], heading[keep])
    assert navigation_gaps(nav.time_s, nav, 0.0, 290.0) == []  # the recording ends before it
    every = np.arange(0, 400, 10)  # a 10 s log: a 40 s interval is no gap (< 5 x 10 s), a 60 s one is
    nav = _table_nav(t[every], x[every], y[every], heading[every])
    assert navigation_gaps(np.delete(nav.time_s, [5, 6, 7]), nav, 0.0, 400.0) == []
    assert len(navigation_gaps(np.delete(nav.time_s, [5, 6, 7, 8, 9]), nav, 0.0, 400.0)) == 1
