"""The live chain's navigation: fixes as they arrive -> the chain's Navigation, the array's heading at a scan, and
coasting through a dropout.

The fixes (lat, lon, heading, UTC) are projected as the file chain projects an NMEA log (io/nmea.py
``navigation_from_track``: azimuthal equidistant about the first fix, the array ``tow_length_m`` behind the ship
along its track), so the same fixes give the same Navigation. A scan waits for the navigation to cover its time
(:meth:`LiveNavigation.covers`: a fix at or after it, and one more where the heading comes from the direction of
motion, a central difference), so that its heading is the one the file chain reads. When no fix has come for
``timeout_s`` of stream time the ownship COASTS: the array's heading is held at its last value (no turn is
predicted) and the health and ownship updates say "coasting" until fixes return; the scans stepped while coasting
may then differ from a file run on the complete log (which interpolates across the hole).

Cost: each fix is projected once, as it comes, and its logged heading unwrapped against the one before (np.unwrap's
steps, the same floats); the Navigation a scan reads is rebuilt from these columns (numpy over the fixes kept, a
fraction of a millisecond for an hour of fixes a second) -- not reprojected from every fix each window, which cost
~5 ms a window with an hour of fixes and grew with the history. Across the fixes dropped the headings stay
continuous (a re-unwrap from the oldest fix kept would jump by 2 pi after a turn through north).

Memory: fixes older than ``keep_s`` before the newest are dropped (the tow model needs the last tow length of track,
a few minutes; the TMA the tracks' history: the live chain keeps ``history_s`` plus a margin).
"""

from __future__ import annotations

import math
from collections import deque
from datetime import datetime

import numpy as np

from sonartrack.io.navigation import Navigation
from sonartrack.io.stream.types import NavFix


class LiveNavigation:
    """Navigation fixes as they come (module doc).

    Parameters
    ----------
    start_utc : datetime
        UTC time of the stream's sample 0 (times are seconds after it).
    tow_length_m : float
        Array centre behind the ship (m); 0: at the ship.
    timeout_s : float
        No fix for this long (stream time) -> coasting.
    keep_s : float
        Fixes this much older than the newest are dropped.
    """

    def __init__(self, start_utc: datetime, *, tow_length_m: float = 0.0, timeout_s: float = 5.0,
                 keep_s: float = 4200.0):
        self.start_utc, self.tow_length_m = start_utc, float(tow_length_m)
        self.timeout_s, self.keep_s = float(timeout_s), float(keep_s)
        self.fixes: deque[tuple[float, float, float, float]] = deque()  # (unix s, lat, lon, heading deg or NaN)
        #: per fix: projected x, y (m) and the heading unwrapped against the previous logged one (rad, NaN: none)
        self._cols: deque[tuple[float, float, float]] = deque()
        self._last_heading_rad: float | None = None  # the raw previous logged heading (rad)
        self._correction = 0.0  # np.unwrap's running sum of corrections (rad)
        self._n_headings = 0  # logged headings among the fixes kept
        self.projection = None
        self._nav: Navigation | None = None
        self.coasting = False
        self.dropouts = 0
        self.version = 0  # fixes taken so far (the geometries built on them are rebuilt when it changes)

    def push(self, fix: NavFix) -> None:
        """Take a fix (a fix not after the newest is ignored: NMEA repeats); projected once, here."""
        t = fix.utc.timestamp()
        if self.fixes and t <= self.fixes[-1][0]:
            return
        if not (math.isfinite(fix.lat_deg) and math.isfinite(fix.lon_deg)):
            return
        if self.projection is None:
            from sonartrack.io.nmea import LocalProjection

            self.projection = LocalProjection(float(fix.lat_deg), float(fix.lon_deg))
        x, y = self.projection.xy(float(fix.lat_deg), float(fix.lon_deg))
        self.fixes.append((t, float(fix.lat_deg), float(fix.lon_deg), float(fix.heading_deg)))
        self._cols.append((float(x), float(y), self._unwrapped(float(fix.heading_deg))))
        self._n_headings += math.isfinite(fix.heading_deg)
        while self.fixes[-1][0] - self.fixes[0][0] > self.keep_s:
            self.fixes.popleft()
            self._n_headings -= math.isfinite(self._cols.popleft()[2])
        self._nav = None
        self.version += 1

    def _unwrapped(self, heading_deg: float) -> float:
        """The logged heading (rad) unwrapped against the previous logged one, step by step as np.unwrap does it
        (the same float operations: io/nmea.py unwraps the whole log so), and continued across the fixes dropped
        (no 2 pi jump when the oldest fix kept changes); NaN without one."""
        if not math.isfinite(heading_deg):
            return math.nan
        p = float(np.deg2rad(heading_deg))
        if self._last_heading_rad is not None:
            dd = p - self._last_heading_rad
            ddmod = (dd + math.pi) % (2.0 * math.pi) - math.pi
            if ddmod == -math.pi and dd > 0:
                ddmod = math.pi
            self._correction += 0.0 if abs(dd) < math.pi else ddmod - dd
        self._last_heading_rad = p
        return p + self._correction

    def _seconds(self, unix_s: float) -> float:
        return unix_s - self.start_utc.timestamp()

    def last_time_s(self) -> float:
        """Time (s after the start) of the newest fix (-inf without one)."""
        return self._seconds(self.fixes[-1][0]) if self.fixes else -math.inf

    def covers(self, time_s: float) -> bool:
        """Whether the fixes fix the array's heading at ``time_s`` as the whole log would (module doc)."""
        t0 = self.start_utc.timestamp()
        after = 0
        for f in reversed(self.fixes):  # the newest first: a scan asks about the last second or two
            if f[0] - t0 < time_s or after >= 2:
                break
            after += 1
        if len(self.fixes) < 2 or not after:
            return False
        return after >= 2 or self._headed()

    def _headed(self) -> bool:
        """Two logged headings or more among the fixes kept."""
        return self._n_headings >= 2

    def update(self, stream_time_s: float) -> bool:
        """Note the stream's time (s): whether the ownship is coasting now (no fix for ``timeout_s``); a dropout
        begins when it starts to coast."""
        coasting = stream_time_s - self.last_time_s() > self.timeout_s
        if coasting and not self.coasting:
            self.dropouts += 1
        self.coasting = coasting
        return coasting

    def navigation(self) -> Navigation | None:
        """The Navigation of the fixes kept (None with fewer than two): io/nmea.py ``navigation_from_track`` on
        them, from the positions projected as each fix came (module doc)."""
        if self._nav is None and len(self.fixes) >= 2:
            t, x, y, h = self.ship()
            ax, ay, ah = self.towed(self.tow_length_m, (t, x, y, h))
            self._nav = Navigation(t - self.start_utc.timestamp(), x, y, h, ax, ay, ah)
        return self._nav

    def ship(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The ship's columns of the fixes kept: (UTC unix times (s), x, y (m), heading (rad, unwrapped)), the
        heading interpolated between logged ones, or the direction of motion when none is logged (io/nmea.py)."""
        t = np.array([f[0] for f in self.fixes])
        x, y, uw = (np.array(c) for c in zip(*self._cols, strict=True))
        has = np.isfinite(uw)
        if has.sum() >= 2:
            h = np.interp(t, t[has], uw[has])
        elif has.sum() == 1:
            h = np.full(t.shape, uw[has][0])
        else:  # no heading logged: the direction of motion (io/nmea.py)
            h = np.unwrap(np.arctan2(np.gradient(x, t), np.gradient(y, t)))
        return t, x, y, h

    def towed(self, tow_length_m: float, ship=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A body towed ``tow_length_m`` behind the ship along its track at the fixes' times: (x, y (m), heading
        (rad)), the file chain's tow model (io/nmea.py); ``ship`` the columns of :meth:`ship` when at hand."""
        from sonartrack.io.nmea import _towed as tow_model  # the file chain's tow model, the same floats
        from sonartrack.io.nmea import check_tow_length

        t, x, y, h = self.ship() if ship is None else ship
        check_tow_length(tow_length_m)
        return tow_model(t, x, y, h, float(tow_length_m))

    def heading_deg(self, time_s: float) -> float | None:
        """The array's heading (deg, unwrapped) at ``time_s`` (held at the last fix when coasting), or None without
        navigation."""
        nav = self.navigation()
        if nav is None:
            return None
        return float(np.rad2deg(nav.array_at(np.array([min(time_s, nav.time_s[-1])]))[1])[0])

    def state(self) -> dict:
        """What a checkpoint keeps."""
        origin = None if self.projection is None else (self.projection.lat0_deg, self.projection.lon0_deg)
        return {"fixes": list(self.fixes), "cols": list(self._cols), "coasting": self.coasting,
                "dropouts": self.dropouts, "origin": origin,
                "unwrap": (self._last_heading_rad, self._correction)}

    def restore(self, state: dict) -> None:
        """Back to a checkpoint's :meth:`state`."""
        from sonartrack.io.nmea import LocalProjection

        self.fixes = deque(tuple(f) for f in state["fixes"])
        self._cols = deque(tuple(c) for c in state["cols"])
        self._n_headings = sum(math.isfinite(c[2]) for c in self._cols)
        self._last_heading_rad, self._correction = state["unwrap"]
        self.coasting, self.dropouts = bool(state["coasting"]), int(state["dropouts"])
        origin = state["origin"]
        self.projection = None if origin is None else LocalProjection(*origin)
        self._nav = None
        self.version += 1
