"""Navigation sentences to fixes one at a time, each checked as it comes: a bad sentence or an impossible fix is an
event, never a crash; a silence is a "nav_dropout".

NMEA 0183 is parsed by io/nmea.py's own line parser (checksum, RMC status A, GGA quality > 0, hemisphere letters,
minutes below 60, latitude and longitude in range, HDT heading in 0..360): what it would count as skipped or
refuse in a log is here a ``StreamEvent("bad_sentence")`` with its reason. A GGA takes the date of the last RMC
(io/nmea.py's rule, midnight roll-over included), else ``log_date``, else today's UTC date. The fixes of one time
(RMC and GGA of the same second) are one fix; it goes out when its HDT arrives (the true heading), when a fix of
a later time arrives, or :data:`PENDING_S` after it came (its heading NaN: a course over ground is no heading).

Checks per fix (io/nav_checks.py's limits): a fix whose time is not after the last one's is dropped
("nav_out_of_order"); one that would move the ship faster than ``MAX_LOG_SPEED_KN`` from the last fix is dropped
("nav_jump") unless ``MAX_DROPPED_RUN`` fixes in a row did so (then the track has moved and is taken again); a
fix more than ``dropout_s`` after the last one follows a "nav_dropout" in the log's own time. The source's clock
reports a dropout too: no fix for ``dropout_s`` seconds of wall time (:meth:`NmeaFixer.tick`), and
"nav_resumed" when fixes come back.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from datetime import UTC, date, datetime, timedelta

from sonartrack.core.errors import InputError
from sonartrack.core.units import KNOT_MPS
from sonartrack.io.nav_checks import MAX_DROPPED_RUN, MAX_LOG_SPEED_KN
from sonartrack.io.nmea import _date_of, _parse_line, _Parsed
from sonartrack.io.stream.types import NavFix, StreamEvent

#: longest wait (s, wall clock) for a fix's HDT before it goes out without a heading
PENDING_S = 0.5
#: a navigation silence longer than this (s) is a dropout
DROPOUT_S = 5.0
_WHY = {"bad_checksum": "wrong or missing checksum", "malformed": "does not parse"}


class NmeaFixer:
    """NMEA sentences in, :class:`NavFix` and :class:`StreamEvent` out (module doc)."""

    def __init__(self, source: str, *, dropout_s: float = DROPOUT_S, log_date: date | None = None,
                 clock=time.monotonic):
        self.source, self.dropout_s, self.log_date = source, float(dropout_s), log_date
        self._acc = _Parsed(path=source)
        self._pending: NavFix | None = None
        self._pending_at = 0.0
        self._last: NavFix | None = None
        self._jumps = 0
        self._clock = clock
        self._heard = clock()
        self._silent = False
        self.lines = 0

    def line(self, text: str) -> list:
        """One line (a sentence, with or without its CR LF); the fixes and events it completed.

        Parameters
        ----------
        text : str
            The line.

        Returns
        -------
        list
            NavFix | StreamEvent.
        """
        if not text.strip():
            return []
        acc, k = self._acc, self.lines
        self.lines += 1
        try:
            kind = _parse_line(text, k, acc)
        except InputError as exc:
            return [StreamEvent("bad_sentence", f"{self.source}: {exc}")]
        if kind in _WHY:
            return [StreamEvent("bad_sentence", f"{self.source}: sentence {text.strip()[:60]!r}: {_WHY[kind]}: "
                                                "skipped")]
        out = []
        if acc.dated:
            when, lat, lon, _ = acc.dated.pop()
            out += self._position(when, lat, lon, _rmc_speed_mps(text))
            del acc.rmc_dates[:-1]
        if acc.undated:
            _, tod, lat, lon = acc.undated.pop()
            out += self._position(self._gga_time(k, tod), lat, lon, math.nan)
        hdt = acc.headings.pop("HDT", None)
        acc.headings.clear()
        if hdt and self._pending is not None:
            out += self._emit(replace(self._pending, heading_deg=float(hdt[-1][1])))
            self._pending = None
        return out

    def _gga_time(self, k: int, tod) -> datetime:
        if self._acc.rmc_dates or self.log_date is not None:
            return _date_of(k, tod, self._acc.rmc_dates, self.log_date)
        return datetime.combine(datetime.now(UTC).date(), tod.replace(tzinfo=None), UTC)

    def _position(self, when: datetime, lat: float, lon: float, speed: float) -> list:
        p = self._pending
        if p is not None and p.utc == when:
            if math.isnan(p.speed_mps):
                self._pending = replace(p, speed_mps=speed)
            return []
        if self._last is not None and self._last.utc == when:
            return []  # the other sentence of a fix already given out
        out = self._emit(p) if p is not None else []
        self._pending, self._pending_at = NavFix(when, lat, lon, math.nan, speed), self._clock()
        return out

    def tick(self) -> list:
        """Now and then (the source's reader does it): a fix waiting too long for its heading goes out, and a
        silence of ``dropout_s`` is reported.

        Returns
        -------
        list
            NavFix | StreamEvent.
        """
        out = []
        now = self._clock()
        if self._pending is not None and now - self._pending_at >= PENDING_S:
            out += self._emit(self._pending)
            self._pending = None
        if not self._silent and now - self._heard > self.dropout_s:
            self._silent = True
            out.append(StreamEvent("nav_dropout", f"{self.source}: no navigation fix for {self.dropout_s:g} s: the "
                                                  "ship's position is coasting"))
        return out

    def flush(self) -> list:
        """The end of the input: the fix waiting for its heading goes out.

        Returns
        -------
        list
            NavFix | StreamEvent.
        """
        p, self._pending = self._pending, None
        return self._emit(p) if p is not None else []

    def take(self, fix: NavFix) -> list:
        """A complete fix from another kind of log (a CSV row): the same checks, then the fix.

        Parameters
        ----------
        fix : NavFix
            The fix.

        Returns
        -------
        list
            NavFix | StreamEvent.
        """
        return self._emit(fix)

    def _emit(self, fix: NavFix) -> list:
        """The checks of the module doc, then the fix."""
        last, out = self._last, []
        if last is not None:
            dt = (fix.utc - last.utc).total_seconds()
            if dt <= 0:
                return [StreamEvent("nav_out_of_order", f"{self.source}: fix of {fix.utc:%H:%M:%S.%f} is not after "
                                                        f"the last one ({last.utc:%H:%M:%S.%f}): dropped")]
            kn = _distance_m(last, fix) / dt / KNOT_MPS
            if kn > MAX_LOG_SPEED_KN and self._jumps < MAX_DROPPED_RUN:
                self._jumps += 1
                return [StreamEvent("nav_jump", f"{self.source}: fix of {fix.utc:%H:%M:%S} is {kn:.0f} kn away from "
                                                f"the last one (no towing ship makes {MAX_LOG_SPEED_KN:g} kn): "
                                                "dropped")]
            if dt > self.dropout_s and not self._silent:
                out.append(StreamEvent("nav_dropout", f"{self.source}: no fix between {last.utc:%H:%M:%S} and "
                                                      f"{fix.utc:%H:%M:%S} ({dt:.1f} s)"))
        if self._silent:
            out.append(StreamEvent("nav_resumed", f"{self.source}: navigation fixes again"))
        self._jumps, self._silent, self._heard, self._last = 0, False, self._clock(), fix
        return [*out, fix]


def _rmc_speed_mps(text: str) -> float:
    """Speed over ground of an RMC sentence (field 7, knots) in m/s; NaN when absent."""
    fields = text[text.find("$"):].split(",")
    if not fields[0].endswith("RMC") or len(fields) < 8:
        return math.nan
    try:
        return float(fields[7]) * KNOT_MPS
    except ValueError:
        return math.nan


_GEOD = []


def _distance_m(a: NavFix, b: NavFix) -> float:
    if not _GEOD:
        from pyproj import Geod

        _GEOD.append(Geod(ellps="WGS84"))
    return float(_GEOD[0].inv(a.lon_deg, a.lat_deg, b.lon_deg, b.lat_deg)[2])


def utc_of(time_unix_s: float) -> datetime:
    """A UTC datetime from seconds since 1970 (the CSV logs' time column).

    Parameters
    ----------
    time_unix_s : float
        Seconds since 1970-01-01 UTC.

    Returns
    -------
    datetime
        Timezone-aware.
    """
    return datetime(1970, 1, 1, tzinfo=UTC) + timedelta(seconds=float(time_unix_s))
