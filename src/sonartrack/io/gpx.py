"""GPX tracks (parsed and written by ``gpxpy``): track points to a UTC :class:`~sonartrack.io.nmea.GeoTrack`.

Read: every track point (``trk/trkseg/trkpt``) of every track and segment, in time order, a time given twice
kept once; each point needs a time (UTC; GPX times carry a zone, one without is taken as UTC) and a latitude,
longitude (and course) within -90..90, -180..180 (0..360) deg, else it is refused by its number. A point's
``course`` (GPX 1.0, deg from true north) becomes the heading when every point has one; otherwise the heading
is the direction of motion (io/nmea.py ``navigation_from_track``). Routes and waypoints are not tracks and are
ignored. Write: one track of one segment, GPX 1.1, written atomically. Projection and tow model: io/nmea.py.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import write_text
from sonartrack.io.nmea import GeoTrack


def _root_tag(p: Path) -> str:
    """The root element's name without its namespace (gpxpy 1.6 parses any XML root as a GPX)."""
    _, element = next(ET.iterparse(p, events=("start",)))
    return element.tag.rsplit("}", 1)[-1]


def _points(gpx) -> list:
    return [pt for trk in gpx.tracks for seg in trk.segments for pt in seg.points]


def _check_point(pt, k: int, p: Path) -> None:
    """Refuse a track point whose latitude, longitude or course is none (GPX: -90..90, -180..180, 0..360 deg)."""
    where = f"{p}: track point {k + 1} ({pt.time:%H:%M:%S} UTC)" if pt.time is not None else f"{p}: track point {k + 1}"
    require(-90.0 <= float(pt.latitude) <= 90.0, f"{where} has latitude {pt.latitude}, beyond 90 deg: fix the point")
    require(-180.0 <= float(pt.longitude) <= 180.0,
            f"{where} has longitude {pt.longitude}, beyond 180 deg: fix the point")
    course = getattr(pt, "course", None)
    require(course is None or 0.0 <= float(course) <= 360.0,
            f"{where} has course {course}, outside 0..360 deg: give courses in degrees from true north")


def read_gpx(path) -> GeoTrack:
    """Read the track points of a GPX file (module doc).

    Parameters
    ----------
    path : str or Path
        A GPX 1.0 or 1.1 file.

    Returns
    -------
    GeoTrack
        Times (s since 1970 UTC), latitudes and longitudes (deg); headings from ``course`` when every point has
        one.
    """
    import gpxpy
    import gpxpy.gpx

    p = Path(path)
    require(p.is_file(), f"GPX file not found: {p}: give the navigation log (.gpx)")
    try:
        require(_root_tag(p) == "gpx", f"{p} is not a readable GPX file (its root element is <{_root_tag(p)}>, not "
                                       "<gpx>): give a GPX track exported by the logger")
        gpx = gpxpy.parse(p.read_text(encoding="utf-8"))
    except (gpxpy.gpx.GPXException, ET.ParseError, ValueError) as e:
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise InputError(f"{p} is not a readable GPX file ({msg}): give a GPX track exported by the logger") from None
    points = _points(gpx)
    require(points, f"{p} holds no track points (trk/trkseg/trkpt): give a GPX track, not only routes or "
                    "waypoints")
    untimed = sum(pt.time is None for pt in points)
    require(untimed == 0, f"{p}: {untimed} of {len(points)} track points have no time: give a track logged with "
                          "UTC times")
    for k, pt in enumerate(points):
        _check_point(pt, k, p)
    rows: dict[float, tuple] = {}
    for pt in points:
        when = pt.time if pt.time.tzinfo is not None else pt.time.replace(tzinfo=UTC)
        rows.setdefault(when.timestamp(), (pt.latitude, pt.longitude, getattr(pt, "course", None)))
    t = np.array(sorted(rows))
    lat, lon, course = (np.array([rows[s][i] for s in t], dtype=float if i < 2 else object) for i in range(3))
    if all(c is not None for c in course):
        return GeoTrack(t, lat, lon, t.copy(), course.astype(float), "GPX")
    return GeoTrack(t, lat, lon)


def write_gpx(path, track: GeoTrack, name: str = "sonartrack") -> Path:
    """Write ``track``'s points as one GPX 1.1 track (atomically).

    Parameters
    ----------
    path : str or Path
        The .gpx file.
    track : GeoTrack
        Times, latitudes and longitudes (headings are not written: GPX 1.1 has no course element).
    name : str
        The track's name.

    Returns
    -------
    Path
        The file written.
    """
    import gpxpy.gpx

    gpx = gpxpy.gpx.GPX()
    trk = gpxpy.gpx.GPXTrack(name=name)
    seg = gpxpy.gpx.GPXTrackSegment()
    for t, lat, lon in zip(track.time_unix_s, track.lat_deg, track.lon_deg, strict=True):
        seg.points.append(gpxpy.gpx.GPXTrackPoint(float(lat), float(lon),
                                                  time=datetime.fromtimestamp(float(t), UTC)))
    trk.segments.append(seg)
    gpx.tracks.append(trk)
    return write_text(path, gpx.to_xml(version="1.1"))
