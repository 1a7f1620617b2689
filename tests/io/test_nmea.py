"""NMEA 0183 logs, the local projection and the tow model (io/nmea.py): hand-made sentences with checksums
computed here by XOR, a known northbound track, bad sentences counted, the projection against the closed-form
meridian and parallel arcs of the WGS84 ellipsoid."""

from __future__ import annotations

import math
from datetime import UTC, date, datetime, timedelta

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.nmea import GeoTrack, LocalProjection, navigation_from_track, read_nmea

A, F = 6378137.0, 1 / 298.257223563  # WGS84
E2 = F * (2 - F)
LAT0, LON0 = 50.0, -4.0
T0 = datetime(2024, 5, 17, 23, 55, 0, tzinfo=UTC)


def meridian_radius(lat_deg):
    """M = a (1 - e^2) / (1 - e^2 sin^2 phi)^(3/2): metres of meridian per radian of latitude."""
    s = math.sin(math.radians(lat_deg))
    return A * (1 - E2) / (1 - E2 * s * s) ** 1.5


def normal_radius(lat_deg):
    s = math.sin(math.radians(lat_deg))
    return A / math.sqrt(1 - E2 * s * s)


def north_of(lat0, y_m):
    """Latitude (deg) y_m north of lat0 along the meridian: M at the mid latitude (error << 1 mm at 3 km)."""
    lat = lat0 + math.degrees(y_m / meridian_radius(lat0))
    return lat0 + math.degrees(y_m / meridian_radius(0.5 * (lat0 + lat)))


def sentence(body: str, checksum: int | None = None) -> str:
    c = 0
    for ch in body.encode():
        c ^= ch
    return f"${body}*{(c if checksum is None else checksum):02X}"


def _lat(deg):
    d = int(abs(deg))
    return f"{d:02d}{(abs(deg) - d) * 60:09.6f},{'N' if deg >= 0 else 'S'}"


def _lon(deg):
    d = int(abs(deg))
    return f"{d:03d}{(abs(deg) - d) * 60:09.6f},{'E' if deg >= 0 else 'W'}"


def rmc(when: datetime, lat, lon, course=0.0):
    return sentence(f"GPRMC,{when:%H%M%S}.00,A,{_lat(lat)},{_lon(lon)},9.7,{course:.1f},{when:%d%m%y},,,A")


def gga(when: datetime, lat, lon):
    return sentence(f"GPGGA,{when:%H%M%S}.00,{_lat(lat)},{_lon(lon)},1,08,0.9,10.0,M,50.0,M,,")


def _northbound_log(tmp_path, speed=5.0, n=61, dt=10.0):
    """RMC every 20 s and GGA in between, two HDT (359.5 and 000.5) after each fix; crosses midnight."""
    lines = []
    for k in range(n):
        when = T0 + timedelta(seconds=k * dt)
        lat = north_of(LAT0, speed * k * dt)
        lines.append(rmc(when, lat, LON0) if k % 2 == 0 else gga(when, lat, LON0))
        lines += [sentence("HEHDT,359.5,T"), sentence("HEHDT,000.5,T")]
    path = tmp_path / "nav.nmea"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_known_northbound_track(tmp_path):
    log = read_nmea(_northbound_log(tmp_path))
    tr = log.track
    assert log.counts.used == 183 and log.counts.bad_checksum == 0
    np.testing.assert_allclose(tr.time_unix_s - T0.timestamp(), np.arange(61) * 10.0)  # GGA after midnight dated
    assert tr.heading_source == "HDT"
    np.testing.assert_allclose(np.cos(np.deg2rad(tr.heading_deg)), 1.0, atol=1e-12)  # 359.5 & 0.5 average to 0
    start = T0 + timedelta(seconds=30)
    nav, proj = navigation_from_track(tr, start, tow_length_m=200.0)
    np.testing.assert_allclose(nav.time_s, np.arange(61) * 10.0 - 30.0)
    np.testing.assert_allclose(nav.y_m, 5.0 * np.arange(61) * 10.0, atol=0.01)
    np.testing.assert_allclose(nav.x_m, 0.0, atol=0.01)
    np.testing.assert_allclose(nav.heading_rad, 0.0, atol=1e-9)
    # the tow model: 200 m behind along the track (before 200 m run: back along the first heading)
    np.testing.assert_allclose(nav.array_y_m, nav.y_m - 200.0, atol=0.02)
    np.testing.assert_allclose(nav.array_x_m, 0.0, atol=0.01)
    np.testing.assert_allclose(nav.array_heading_rad, 0.0, atol=1e-9)
    assert (proj.lat0_deg, proj.lon0_deg) == (pytest.approx(LAT0), pytest.approx(LON0))


def test_bad_sentences_are_counted_and_skipped(tmp_path):
    good = [rmc(T0 + timedelta(seconds=k), north_of(LAT0, 3.0 * k), LON0) for k in range(5)]
    body = good[2][1:-3]
    wrong = sentence(body, checksum=int(good[2][-2:], 16) ^ 0x01)  # one bit off
    lines = [good[0], good[1], wrong, "$" + body, good[3], "garbage here", "2024-05-17 " + good[4],
             sentence("GPGSV,3,1,11,03,03,111,00,04,15,270,00,06,01,010,00,13,06,292,00"),
             sentence(f"GPRMC,{T0:%H%M%S}.00,V,,,,,,,{T0:%d%m%y},,,N")]
    (tmp_path / "bad.nmea").write_text("\n".join(lines) + "\n")
    log = read_nmea(tmp_path / "bad.nmea")
    c = log.counts
    assert (c.lines, c.used, c.bad_checksum, c.malformed, c.no_fix, c.other) == (9, 4, 2, 1, 1, 1)
    np.testing.assert_allclose(log.track.time_unix_s - T0.timestamp(), [0, 1, 3, 4])
    assert log.track.heading_source == "RMC"


def test_all_bad_is_one_line(tmp_path):
    body = rmc(T0, LAT0, LON0)[1:-3]
    (tmp_path / "x.nmea").write_text(f"${body}*00\n${body}*01\nnot nmea\n")
    with pytest.raises(InputError) as e:
        read_nmea(tmp_path / "x.nmea")
    msg = str(e.value)
    assert "\n" not in msg and "no valid position" in msg and "2 bad checksums" in msg and "1 unparsable" in msg


def test_gga_only_needs_a_date(tmp_path):
    (tmp_path / "g.nmea").write_text("\n".join(gga(T0 + timedelta(seconds=k), LAT0, LON0) for k in range(3)))
    with pytest.raises(InputError, match="give the date"):
        read_nmea(tmp_path / "g.nmea")
    tr = read_nmea(tmp_path / "g.nmea", log_date=date(2024, 5, 17)).track
    np.testing.assert_allclose(tr.time_unix_s, T0.timestamp() + np.arange(3))


@pytest.mark.parametrize("lat0", [0.0, 48.0, 80.0])
def test_projection_against_the_meridian_and_parallel_arcs(lat0):
    """1 arcminute of latitude is M pi / 10800 (1842.9 m at the equator .. 1861.6 m at the poles, the 1852 m
    nautical mile their mean, within 0.6 %); 1 arcminute of longitude is N cos(phi) pi / 10800 along the
    parallel, whose chord the projection's x equals to < 1 mm, with y = x^2 tan(phi) / (2 N) north of it."""
    proj = LocalProjection(lat0, 10.0)
    x, y = proj.xy(lat0 + 1 / 60, 10.0)
    arc = meridian_radius(lat0 + 1 / 120) * math.pi / 10800
    assert float(y) == pytest.approx(arc, abs=1e-3) and abs(float(x)) < 1e-6
    assert float(y) == pytest.approx(1852.0, rel=0.006)
    x, y = proj.xy(lat0, 10.0 + 1 / 60)
    par = normal_radius(lat0) * math.cos(math.radians(lat0)) * math.pi / 10800
    assert float(x) == pytest.approx(par, abs=1e-3)
    assert float(y) == pytest.approx(par**2 * math.tan(math.radians(lat0)) / (2 * normal_radius(lat0)), abs=1e-3)
    lat, lon = proj.latlon(np.array([1234.5]), np.array([-987.6]))
    np.testing.assert_allclose(proj.xy(lat, lon), [[1234.5], [-987.6]], atol=1e-6)


def test_heading_from_motion_and_an_array_sensor():
    """No heading logged: the direction of motion (north-east at 45 deg); an array sensor's own track is used
    as given (here 100 m south-west of the ship)."""
    t = T0.timestamp() + np.arange(5) * 10.0
    proj = LocalProjection(LAT0, LON0)
    d = np.arange(5) * 50.0
    lat, lon = proj.latlon(d / math.sqrt(2), d / math.sqrt(2))
    ship = GeoTrack(t, lat, lon)
    alat, alon = proj.latlon(d / math.sqrt(2) - 70.7107, d / math.sqrt(2) - 70.7107)
    nav, _ = navigation_from_track(ship, T0, array_track=GeoTrack(t, alat, alon), projection=proj)
    np.testing.assert_allclose(nav.heading_rad, math.pi / 4, atol=1e-6)
    np.testing.assert_allclose(np.hypot(nav.x_m - nav.array_x_m, nav.y_m - nav.array_y_m), 100.0, atol=1e-3)
    np.testing.assert_allclose(nav.array_heading_rad, math.pi / 4, atol=1e-6)


def test_written_log_reads_back_with_valid_checksums(tmp_path):
    """write_nmea: pynmea2 (an independent parser) verifies every checksum; positions 1 km north and east of the
    origin come back through the projection to a millimetre, times to the centisecond, headings as written."""
    import pynmea2

    from sonartrack.io.nmea import write_nmea

    t = T0.timestamp() + np.array([0.0, 1.0, 2.5, 400.0])  # across midnight: the date of each RMC is its own
    lat = np.array([LAT0, north_of(LAT0, 1000.0), LAT0 - 0.01, LAT0])
    lon = np.array([LON0, LON0, LON0 + 0.02, LON0 - 0.3])
    heading = np.array([0.0, 359.99, 90.5, 270.25])
    path = write_nmea(tmp_path / "w.nmea", t, lat, lon, heading, np.full(4, 6.0), heading)
    lines = path.read_text().splitlines()
    assert len(lines) == 8 and path.read_bytes().endswith(b"\r\n")
    for line in lines:
        body, check = line[1:].split("*")
        c = 0
        for ch in body.encode():
            c ^= ch
        assert int(check, 16) == c
        pynmea2.parse(line, check=True)
    log = read_nmea(path)
    assert log.counts.used == 8 and log.counts.bad_checksum == 0 and log.track.heading_source == "HDT"
    np.testing.assert_allclose(log.track.time_unix_s, t, atol=0.005)
    np.testing.assert_allclose(log.track.heading_deg, heading, atol=0.005)
    np.testing.assert_allclose(log.track.lat_deg, lat, atol=1e-8)  # 1e-6 minute = 2 mm
    x, y = LocalProjection(LAT0, LON0).xy(log.track.lat_deg[:2], log.track.lon_deg[:2])
    np.testing.assert_allclose([x[1], y[1]], [0.0, 1000.0], atol=0.005)
    assert lines[6].startswith("$GPRMC,000140.00,A,") and ",180524," in lines[6]  # 23:55 + 400 s: the next day
