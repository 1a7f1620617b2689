"""Navigation logs: NMEA 0183 sentences to a UTC track, a local x/y projection, and the passive chain's
:class:`~sonartrack.io.navigation.Navigation`.

NMEA 0183 (parsed by ``pynmea2``): position from RMC (status A only; it carries the date) and GGA (fix quality
> 0; its time of day takes the date of the nearest RMC, rolling over at midnight), heading from HDT (true
heading), else the course over ground from VTG, else from RMC. HDT and VTG carry no time: each takes the time
of the last position sentence before it, and several between two fixes are averaged on the circle. Every
sentence's checksum (XOR of the bytes between ``$`` and ``*``) is verified: a sentence with a wrong or missing
checksum, or that does not parse, is counted and skipped; a log with no valid position is refused in one line
with the counts. Text before the ``$`` of a line (a logger's own time stamp) is ignored. A sentence whose checksum
is right but whose position is no position -- a hemisphere letter other than N/S or E/W, minutes of 60 or more,
a latitude beyond 90 deg or a longitude beyond 180 deg -- is refused with its line number (the logger wrote it
so: skipping it would hide a log that is wrong elsewhere too); so is a heading outside 0..360 deg.

Projection: latitude/longitude (WGS84) to x east / y north (m) on the azimuthal equidistant projection centred
on a chosen origin (default: the first fix), through ``pyproj`` (PROJ ``+proj=aeqd``, ellipsoidal). Distances
and azimuths from the origin are exact; the scale error elsewhere grows as (d / R)^2 / 6 + O(e^2 (d/R)^2), under
1e-6 (1 mm per km) within 15 km of the origin, far below a GNSS fix's metres.

Array position (:func:`navigation_from_track`): from an array sensor's track when there is one; otherwise the
tow model of ``sonartrack simulate`` (sim/platforms.py): the array centre lies ``tow_length_m`` behind the ship
along the ship's own track, at the point the ship passed when it had run ``tow_length_m`` less, and points
along the ship's heading then. For a steady speed v this is where the ship was L / v earlier, as the
simulator has it; before the log has run L metres the array is placed back along the first heading. A tow
length of 0 puts the array at the ship (a hull array), as io/navigation.py does without array columns; one
beyond :data:`MAX_TOW_LENGTH_M` is refused (:func:`check_tow_length`).

Writing (:func:`write_nmea`, for ``sonartrack simulate --nmea``): one RMC (time to the centisecond, position to
1e-6 minute, speed and course over ground, date) and one HDT (true heading) sentence per fix, CR LF line ends.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, field
from datetime import UTC, date, datetime, timedelta
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.navigation import Navigation

#: the longest distance (m) of an array centre behind its ship taken: a submarine's or frigate's thin-line array
#: streams 1-2.5 km of cable, a seismic streamer's centre lies up to about 6 km astern; beyond 10 km the value is
#: a unit slip (feet, centimetres) or garbage, and would put the array kilometres back along the first heading
MAX_TOW_LENGTH_M = 10_000.0


@dataclass(frozen=True, slots=True)
class GeoTrack:
    """A platform's UTC track: fix times (s since 1970-01-01 UTC), latitude and longitude (deg, WGS84), and
    heading samples (time, deg clockwise from true north) with where they came from (HDT, VTG, RMC, GPX or
    none: the heading is then the direction of motion)."""

    time_unix_s: np.ndarray
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    heading_time_unix_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    heading_deg: np.ndarray = field(default_factory=lambda: np.zeros(0))
    heading_source: str = "none"
    #: each fix's line in its log (1-based; NMEA only, empty otherwise), for the messages about a fix
    fix_line: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def start_utc(self) -> datetime:
        """The UTC time of the first fix (a timezone-aware datetime)."""
        return datetime.fromtimestamp(float(self.time_unix_s[0]), UTC)


@dataclass(frozen=True, slots=True)
class NmeaCounts:
    """Lines read, sentences used, and sentences skipped: bad or missing checksum, unparsable, no fix (RMC
    status V, GGA quality 0, empty position), and of types not used here."""

    lines: int = 0
    used: int = 0
    bad_checksum: int = 0
    malformed: int = 0
    no_fix: int = 0
    other: int = 0

    def describe(self) -> str:
        """One line of the counts for a log or an error message.

        Returns
        -------
        str
            "N lines: U used, B bad checksums, M unparsable, F without a fix, O of other types".
        """
        return (f"{self.lines} lines: {self.used} used, {self.bad_checksum} bad checksums, {self.malformed} "
                f"unparsable, {self.no_fix} without a fix, {self.other} of other types")


@dataclass(frozen=True, slots=True)
class NmeaLog:
    """What :func:`read_nmea` found: the track and the counts of sentences."""

    track: GeoTrack
    counts: NmeaCounts


def nmea_checksum(body: str) -> int:
    """XOR of the characters between ``$`` and ``*`` of a sentence (NMEA 0183).

    Parameters
    ----------
    body : str
        The characters between ``$`` and ``*`` (non-ASCII characters count as "?").

    Returns
    -------
    int
        The checksum, 0..255 (written as two hexadecimal digits after ``*``).
    """
    c = 0
    for ch in body.encode("ascii", "replace"):
        c ^= ch
    return c


@dataclass
class _Parsed:
    """Accumulated while reading: fixes (datetime or time of day, lat, lon), heading samples by source."""

    dated: list = field(default_factory=list)
    undated: list = field(default_factory=list)  # (index in the sentence order, time of day, lat, lon)
    rmc_dates: list = field(default_factory=list)  # (index, date, time of day)
    headings: dict = field(default_factory=lambda: defaultdict(list))  # source -> [(fix key, deg)]
    counts: dict = field(default_factory=lambda: defaultdict(int))
    last_fix: object = None
    path: object = "NMEA log"


def _has_position(msg) -> bool:
    return bool(getattr(msg, "lat", "")) and bool(getattr(msg, "lon", ""))


def _coordinate(text: str, letter: str, k: int, path, latitude: bool) -> float:
    """Signed degrees of an NMEA ``(d)ddmm.mm`` field and its hemisphere letter; InputError naming the line when
    the letter is not N/S (E/W), the minutes are 60 or more, or the value lies beyond 90 (180) deg."""
    what, letters, limit = ("latitude", "NS", 90.0) if latitude else ("longitude", "EW", 180.0)
    where = f"NMEA log {path} line {k + 1}"
    require(letter in (letters[0], letters[1]), f"{where}: {what} hemisphere {letter!r} is not {letters[0]} or "
                                                f"{letters[1]}: fix the letter, or delete the line")
    value = float(text)
    require(value >= 0, f"{where}: {what} {text} is negative (NMEA gives the sign by the letter {letters}): fix "
                        "the sentence, or delete the line")
    deg = math.floor(value / 100.0)
    minutes = value - 100.0 * deg
    require(minutes < 60.0, f"{where}: {what} {text} has {minutes:g} minutes ((d)ddmm.mm, minutes below 60): fix "
                            "the sentence, or delete the line")
    require(deg + minutes / 60.0 <= limit, f"{where}: {what} {text} is {deg + minutes / 60.0:g} deg, beyond {limit:g}: "
                                           "fix the sentence, or delete the line")
    return (deg + minutes / 60.0) * (1.0 if letter == letters[0] else -1.0)


def _lat_lon(msg, k: int, acc: _Parsed) -> tuple[float, float]:
    return (_coordinate(msg.lat, msg.lat_dir, k, acc.path, True),
            _coordinate(msg.lon, msg.lon_dir, k, acc.path, False))


def _take(msg, k: int, acc: _Parsed) -> str:
    """File one parsed sentence; the counter it falls in."""
    kind = getattr(msg, "sentence_type", None)
    if kind == "RMC":
        if msg.status != "A" or not _has_position(msg) or msg.datestamp is None or msg.timestamp is None:
            return "no_fix"
        when = msg.datetime.replace(tzinfo=UTC)
        acc.dated.append((when, *_lat_lon(msg, k, acc), k))
        acc.rmc_dates.append((k, msg.datestamp, msg.timestamp))
        acc.last_fix = ("dated", when)
        if msg.true_course is not None:
            acc.headings["RMC"].append((acc.last_fix, float(msg.true_course)))
        return "used"
    if kind == "GGA":
        if not msg.gps_qual or not _has_position(msg) or msg.timestamp is None:
            return "no_fix"
        acc.undated.append((k, msg.timestamp, *_lat_lon(msg, k, acc)))
        acc.last_fix = ("undated", k)
        return "used"
    if kind in ("HDT", "VTG"):
        value = msg.heading if kind == "HDT" else msg.true_track
        if value in (None, "") or acc.last_fix is None:
            return "no_fix"
        require(0.0 <= float(value) <= 360.0, f"NMEA log {acc.path} line {k + 1}: {kind} heading {value} is outside "
                                              "0..360 deg: fix the sentence, or delete the line")
        acc.headings[kind].append((acc.last_fix, float(value)))
        return "used"
    return "other"


def _parse_line(line: str, k: int, acc: _Parsed) -> str:
    import pynmea2

    start = line.find("$")
    if start < 0:
        return "malformed"
    try:
        msg = pynmea2.parse(line[start:].strip(), check=True)
    except pynmea2.ChecksumError:
        return "bad_checksum"
    except pynmea2.SentenceTypeError:
        return "other"
    except (pynmea2.ParseError, ValueError, TypeError, AttributeError):
        return "malformed"
    try:
        return _take(msg, k, acc)
    except InputError:  # a position that is no position (_coordinate): refused, not skipped
        raise
    except (ValueError, TypeError, AttributeError):
        return "malformed"


def _date_of(k: int, tod, rmc_dates: list, given: date | None) -> datetime:
    """A GGA time of day on the date of the nearest RMC (by sentence order), the day rolling over when the time
    of day and the RMC's differ by more than 12 h; or on the date given."""
    if given is not None:
        return datetime.combine(given, tod.replace(tzinfo=None), UTC)
    _, day, rtod = min(rmc_dates, key=lambda r: abs(r[0] - k))
    when = datetime.combine(day, tod.replace(tzinfo=None), UTC)
    ref = datetime.combine(day, rtod.replace(tzinfo=None), UTC)
    if (when - ref).total_seconds() > 43200:
        when -= timedelta(days=1)
    elif (ref - when).total_seconds() > 43200:
        when += timedelta(days=1)
    return when


def _circular_mean_deg(values) -> float:
    r = np.deg2rad(np.asarray(values, float))
    return float(np.rad2deg(np.arctan2(np.sin(r).mean(), np.cos(r).mean())) % 360.0)


def _assemble(acc: _Parsed, path, given: date | None) -> GeoTrack:
    """Fixes sorted by time (a time given twice, by RMC and GGA, kept once) and the best heading source."""
    if acc.undated:
        require(acc.rmc_dates or given is not None, f"NMEA log {path} has GGA fixes but no RMC sentence to date "
                                                    "them: give the date of the log (UTC)")
    undated_time = {k: _date_of(k, tod, acc.rmc_dates, given) for k, tod, _, _ in acc.undated}
    fixes = acc.dated + [(undated_time[k], lat, lon, k) for k, _, lat, lon in acc.undated]
    by_time: dict[datetime, tuple[float, float, int]] = {}
    for when, lat, lon, k in sorted(fixes, key=lambda f: f[0]):
        by_time.setdefault(when, (lat, lon, k + 1))
    times = sorted(by_time)
    t = np.array([w.timestamp() for w in times])
    lat, lon, line = (np.array([by_time[w][i] for w in times]) for i in range(3))
    for source in ("HDT", "VTG", "RMC"):
        if acc.headings.get(source):
            groups: dict[float, list[float]] = defaultdict(list)
            for (kind, key), deg in acc.headings[source]:
                when = key if kind == "dated" else undated_time[key]
                groups[when.timestamp()].append(deg)
            ht = np.array(sorted(groups))
            return GeoTrack(t, lat, lon, ht, np.array([_circular_mean_deg(groups[s]) for s in ht]), source,
                            line.astype(int))
    return GeoTrack(t, lat, lon, fix_line=line.astype(int))


def read_nmea(path, *, log_date: date | None = None) -> NmeaLog:
    """Read an NMEA 0183 log (module doc) into a UTC track.

    Parameters
    ----------
    path : str or Path
        A text file of sentences, one a line.
    log_date : date, optional
        UTC date of GGA fixes when the log has no RMC sentence.

    Returns
    -------
    NmeaLog
        The track (at least one position) and the counts of used and skipped sentences.
    """
    p = Path(path)
    require(p.is_file(), f"NMEA log not found: {p}: give the navigation log (a text file of $..RMC/GGA/HDT lines)")
    acc = _Parsed(path=p)
    n = 0
    with open(p, encoding="ascii", errors="replace") as fh:
        for k, line in enumerate(fh):
            if line.strip():
                n += 1
                acc.counts[_parse_line(line, k, acc)] += 1
    counts = NmeaCounts(n, acc.counts["used"], acc.counts["bad_checksum"], acc.counts["malformed"],
                        acc.counts["no_fix"], acc.counts["other"])
    if not acc.dated and not acc.undated:
        raise InputError(f"NMEA log {p} holds no valid position ({counts.describe()}): give a log with RMC or GGA "
                         "sentences whose checksums are right")
    return NmeaLog(_assemble(acc, p, log_date), counts)


class LocalProjection:
    """Azimuthal equidistant projection (WGS84) about ``(lat0_deg, lon0_deg)``: x east, y north (m)."""

    def __init__(self, lat0_deg: float, lon0_deg: float):
        from pyproj import CRS, Transformer

        require(-90 <= lat0_deg <= 90 and -180 <= lon0_deg <= 360, f"projection origin ({lat0_deg:g}, "
                                                                   f"{lon0_deg:g}) deg is no latitude/longitude")
        self.lat0_deg, self.lon0_deg = float(lat0_deg), float(lon0_deg)
        local = CRS.from_proj4(f"+proj=aeqd +lat_0={lat0_deg!r} +lon_0={lon0_deg!r} +datum=WGS84 +units=m "
                               "+no_defs")
        self._fwd = Transformer.from_crs(CRS.from_epsg(4326), local, always_xy=True)

    def xy(self, lat_deg, lon_deg) -> tuple[np.ndarray, np.ndarray]:
        """x east and y north (m) of latitudes and longitudes (deg).

        Parameters
        ----------
        lat_deg, lon_deg : float or array_like
            Latitudes and longitudes (deg, WGS84).

        Returns
        -------
        x, y : ndarray
            Local coordinates (m; x east, y north).
        """
        x, y = self._fwd.transform(np.asarray(lon_deg, float), np.asarray(lat_deg, float))
        return np.asarray(x, float), np.asarray(y, float)

    def latlon(self, x_m, y_m) -> tuple[np.ndarray, np.ndarray]:
        """Latitude and longitude (deg) of local x east, y north (m).

        Parameters
        ----------
        x_m, y_m : float or array_like
            Local coordinates (m; x east, y north).

        Returns
        -------
        lat, lon : ndarray
            Latitudes and longitudes (deg, WGS84).
        """
        lon, lat = self._fwd.transform(np.asarray(x_m, float), np.asarray(y_m, float), direction="INVERSE")
        return np.asarray(lat, float), np.asarray(lon, float)


def _headings_rad(track: GeoTrack, t: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Unwrapped headings (rad) at the fix times: the logged ones interpolated, else the direction of motion."""
    if track.heading_deg.size >= 2:
        h = np.unwrap(np.deg2rad(track.heading_deg))
        return np.interp(t, track.heading_time_unix_s, h)
    if track.heading_deg.size == 1:
        return np.full(t.shape, math.radians(float(track.heading_deg[0])))
    require(t.size >= 2, "one fix and no heading: the log cannot give the platform's heading")
    return np.unwrap(np.arctan2(np.gradient(x, t), np.gradient(y, t)))


def _towed(t, x, y, heading, tow_length_m: float):
    """The tow model (module doc): array centre and heading behind the ship along its own track."""
    if tow_length_m <= 0:
        return x, y, heading
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    s_back = s - tow_length_m
    moving = np.concatenate([[True], np.diff(s) > 1e-9])  # a stop adds no distance: keep the first time of it
    t_back = np.interp(s_back, s[moving], t[moving])
    ax, ay, ah = np.interp(t_back, t, x), np.interp(t_back, t, y), np.interp(t_back, t, heading)
    before = s_back < 0  # not yet run the tow length: back along the first heading
    ax = np.where(before, x[0] + s_back * np.sin(heading[0]), ax)
    ay = np.where(before, y[0] + s_back * np.cos(heading[0]), ay)
    return ax, ay, np.where(before, heading[0], ah)


def navigation_from_track(track: GeoTrack, start_utc: datetime, *, tow_length_m: float = 0.0,
                          array_track: GeoTrack | None = None,
                          projection: LocalProjection | None = None) -> tuple[Navigation, LocalProjection]:
    """The passive chain's Navigation from a UTC ship track (module doc: projection and tow model).

    Parameters
    ----------
    track : GeoTrack
        The ship's track (NMEA or GPX).
    start_utc : datetime
        UTC time of the recording's first sample: Navigation times are seconds after it.
    tow_length_m : float
        Distance of the array centre behind the ship along its track (m); 0: the array is at the ship. Unused
        when ``array_track`` is given.
    array_track : GeoTrack, optional
        The array's own track (an array position sensor); its headings, or else its direction of motion.
    projection : LocalProjection, optional
        Default: centred on the ship's first fix.

    Returns
    -------
    (Navigation, LocalProjection)
        Positions (m), headings (rad, unwrapped), times (s after ``start_utc``); and the projection used.
    """
    require(start_utc.tzinfo is not None, "the recording's start time must be time-zone aware (UTC)")
    require(track.time_unix_s.size >= 2, "the navigation log has one fix: give a log covering the recording")
    check_tow_length(tow_length_m)
    proj = projection or LocalProjection(float(track.lat_deg[0]), float(track.lon_deg[0]))
    t0 = start_utc.timestamp()
    x, y = proj.xy(track.lat_deg, track.lon_deg)
    h = _headings_rad(track, track.time_unix_s, x, y)
    if array_track is None:
        ax, ay, ah = _towed(track.time_unix_s, x, y, h, float(tow_length_m))
    else:
        bx, by = proj.xy(array_track.lat_deg, array_track.lon_deg)
        bh = _headings_rad(array_track, array_track.time_unix_s, bx, by)
        ax, ay, ah = (np.interp(track.time_unix_s, array_track.time_unix_s, v) for v in (bx, by, bh))
    return Navigation(track.time_unix_s - t0, x, y, h, ax, ay, ah), proj


def check_tow_length(tow_length_m: float) -> None:
    """Refuse a tow length that is no towed array's (:data:`MAX_TOW_LENGTH_M`).

    Parameters
    ----------
    tow_length_m : float
        Distance of the array centre behind the ship (m).

    Raises
    ------
    InputError
        Unless 0 <= tow_length_m <= MAX_TOW_LENGTH_M.
    """
    t = float(tow_length_m)
    require(0.0 <= t <= MAX_TOW_LENGTH_M,
            f"tow length {t:g} m (--tow-length, or tow_length_m of a survey) is outside 0..{MAX_TOW_LENGTH_M:g} m, "
            "the range of towed arrays (a thin-line array streams 1-2.5 km): give the distance of the array centre "
            "behind the ship in metres (0 for a hull array)")


def _sentence(body: str) -> str:
    """``$body*hh`` with the checksum of :func:`nmea_checksum` (two upper-case hex digits)."""
    return f"${body}*{nmea_checksum(body):02X}"


def _degrees_minutes(deg: float, width: int, hemispheres: str) -> str:
    """NMEA ``(d)ddmm.mmmmmm,H``: whole degrees, minutes to 1e-6 (2 mm), hemisphere letter."""
    a = abs(float(deg))
    d = int(a)
    minutes = round((a - d) * 60.0, 6)
    if minutes >= 60.0:  # rounding carried into the next degree
        d, minutes = d + 1, 0.0
    return f"{d:0{width}d}{minutes:09.6f},{hemispheres[0] if deg >= 0 else hemispheres[1]}"


def nmea_lines(time_unix_s, lat_deg, lon_deg, heading_deg, speed_kn, course_deg) -> list[str]:
    """RMC (position, speed and course over ground, date) and HDT (true heading) sentences, one pair per fix.

    Parameters
    ----------
    time_unix_s : array_like
        Fix times (s since 1970-01-01 UTC), written to the centisecond.
    lat_deg, lon_deg : array_like
        Positions (deg, WGS84).
    heading_deg : array_like
        True heading (deg clockwise from north), the HDT sentence.
    speed_kn, course_deg : array_like
        Speed (kn) and course (deg) over ground, RMC's fields.

    Returns
    -------
    list of str
        ``$GPRMC,...*hh`` and ``$HEHDT,...*hh`` lines, checksums by :func:`nmea_checksum`.
    """
    lines = []
    for t, la, lo, h, v, c in zip(*(np.asarray(a, float) for a in (time_unix_s, lat_deg, lon_deg, heading_deg,
                                                                    speed_kn, course_deg)), strict=True):
        cs = int(round(float(t) * 100.0))
        w = datetime.fromtimestamp(cs // 100, UTC)
        lines.append(_sentence(f"GPRMC,{w:%H%M%S}.{cs % 100:02d},A,{_degrees_minutes(la, 2, 'NS')},"
                               f"{_degrees_minutes(lo, 3, 'EW')},{v:.2f},{c % 360.0:.2f},{w:%d%m%y},,,A"))
        lines.append(_sentence(f"HEHDT,{h % 360.0:.2f},T"))
    return lines


def write_nmea(path, time_unix_s, lat_deg, lon_deg, heading_deg, speed_kn, course_deg) -> Path:
    """Write an NMEA 0183 log of RMC + HDT sentences (:func:`nmea_lines`), atomically; :func:`read_nmea` reads it.

    Parameters
    ----------
    path : str or Path
        The log to write (.nmea).
    time_unix_s, lat_deg, lon_deg, heading_deg, speed_kn, course_deg : array_like
        As :func:`nmea_lines` (s since 1970 UTC, deg, deg, deg, kn, deg).

    Returns
    -------
    Path
        The file written.
    """
    from sonartrack.io.atomic import write_text

    return write_text(path, "\r\n".join(nmea_lines(time_unix_s, lat_deg, lon_deg, heading_deg, speed_kn,
                                                    course_deg)) + "\r\n")
