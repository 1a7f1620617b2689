"""GPX tracks (io/gpx.py): a round trip through the writer, a hand-written GPX 1.0 file with courses, refusals."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.gpx import read_gpx, write_gpx
from sonartrack.io.nmea import GeoTrack, navigation_from_track

T0 = datetime(2024, 5, 17, 13, 45, 0, tzinfo=UTC).timestamp()


def test_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    t = T0 + np.cumsum(rng.uniform(1.0, 10.0, 20)).round()
    track = GeoTrack(t, 50.0 + rng.uniform(-0.01, 0.01, 20), -4.0 + rng.uniform(-0.01, 0.01, 20))
    back = read_gpx(write_gpx(tmp_path / "t.gpx", track))
    np.testing.assert_array_equal(back.time_unix_s, t)
    np.testing.assert_allclose(back.lat_deg, track.lat_deg, atol=1e-9)  # 1e-9 deg = 0.1 mm
    np.testing.assert_allclose(back.lon_deg, track.lon_deg, atol=1e-9)
    assert back.heading_source == "none"


HAND = """<?xml version="1.0" encoding="UTF-8"?>
<gpx version="1.0" creator="hand" xmlns="http://www.topografix.com/GPX/1/0">
 <trk><name>leg</name>
  <trkseg>
   <trkpt lat="50.001" lon="-4.0"><time>2024-05-17T13:45:10Z</time><course>90.0</course></trkpt>
   <trkpt lat="50.000" lon="-4.0"><time>2024-05-17T13:45:00Z</time><course>90.0</course></trkpt>
  </trkseg>
  <trkseg>
   <trkpt lat="50.002" lon="-4.0"><time>2024-05-17T15:45:20+02:00</time><course>92.0</course></trkpt>
  </trkseg>
 </trk>
 <wpt lat="10" lon="10"><time>2024-05-17T00:00:00Z</time></wpt>
</gpx>
"""


def test_hand_written_gpx_10_with_courses_and_zones(tmp_path):
    """Points out of order, a second segment, a time in +02:00; the waypoint is ignored; courses are headings."""
    (tmp_path / "h.gpx").write_text(HAND)
    tr = read_gpx(tmp_path / "h.gpx")
    np.testing.assert_array_equal(tr.time_unix_s - T0, [0.0, 10.0, 20.0])
    np.testing.assert_array_equal(tr.lat_deg, [50.0, 50.001, 50.002])
    assert tr.heading_source == "GPX"
    np.testing.assert_array_equal(tr.heading_deg, [90.0, 90.0, 92.0])
    nav, _ = navigation_from_track(tr, datetime.fromtimestamp(T0, UTC))
    np.testing.assert_allclose(nav.heading_rad, np.deg2rad([90.0, 90.0, 92.0]))
    # 0.001 deg of latitude at 50 deg: M pi / 180e3 = 111.23 m (WGS84 meridian radius 6373 km there)
    np.testing.assert_allclose(np.diff(nav.y_m), 111.23, atol=0.01)


def _refused(tmp_path, text, *words):
    (tmp_path / "r.gpx").write_text(text)
    with pytest.raises(InputError) as e:
        read_gpx(tmp_path / "r.gpx")
    assert "\n" not in str(e.value)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_refusals(tmp_path):
    _refused(tmp_path, "<kml></kml>", "not a readable GPX")
    _refused(tmp_path, "this is not xml", "not a readable GPX")
    _refused(tmp_path, HAND.replace("<time>2024-05-17T13:45:00Z</time>", ""), "1 of 3 track points have no time")
    _refused(tmp_path, '<gpx version="1.1" creator="x" xmlns="http://www.topografix.com/GPX/1/1"><wpt lat="1" '
                       'lon="1"/></gpx>', "no track points")
    with pytest.raises(InputError, match="not found"):
        read_gpx(tmp_path / "missing.gpx")
