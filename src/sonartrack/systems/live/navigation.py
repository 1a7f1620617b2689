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

Memory: fixes older than ``keep_s`` before the newest are dropped (the tow model needs the last tow length of track,
a few minutes; the TMA the tracks' history: the live chain keeps ``history_s`` plus a margin).
"""

from __future__ import annotations

import math
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
        self.fixes: list[tuple[float, float, float, float]] = []  # (unix s, lat, lon, heading deg or NaN)
        self.projection = None
        self._nav: Navigation | None = None
        self.coasting = False
        self.dropouts = 0

    def push(self, fix: NavFix) -> None:
        """Take a fix (a fix not after the newest is ignored: NMEA repeats)."""
        t = fix.utc.timestamp()
        if self.fixes and t <= self.fixes[-1][0]:
            return
        if not (math.isfinite(fix.lat_deg) and math.isfinite(fix.lon_deg)):
            return
        if self.projection is None:
            from sonartrack.io.nmea import LocalProjection

            self.projection = LocalProjection(float(fix.lat_deg), float(fix.lon_deg))
        self.fixes.append((t, float(fix.lat_deg), float(fix.lon_deg), float(fix.heading_deg)))
        while self.fixes and self.fixes[-1][0] - self.fixes[0][0] > self.keep_s:
            self.fixes.pop(0)
        self._nav = None

    def _seconds(self, unix_s: float) -> float:
        return unix_s - self.start_utc.timestamp()

    def last_time_s(self) -> float:
        """Time (s after the start) of the newest fix (-inf without one)."""
        return self._seconds(self.fixes[-1][0]) if self.fixes else -math.inf

    def covers(self, time_s: float) -> bool:
        """Whether the fixes fix the array's heading at ``time_s`` as the whole log would (module doc)."""
        t = np.array([f[0] for f in self.fixes]) - self.start_utc.timestamp()
        after = np.flatnonzero(t >= time_s)
        if len(self.fixes) < 2 or not after.size:
            return False
        headed = np.isfinite([f[3] for f in self.fixes]).sum() >= 2
        return headed or after.size >= 2

    def update(self, stream_time_s: float) -> bool:
        """Note the stream's time (s): whether the ownship is coasting now (no fix for ``timeout_s``); a dropout
        begins when it starts to coast."""
        coasting = stream_time_s - self.last_time_s() > self.timeout_s
        if coasting and not self.coasting:
            self.dropouts += 1
        self.coasting = coasting
        return coasting

    def navigation(self) -> Navigation | None:
        """The Navigation of the fixes kept (None with fewer than two)."""
        if self._nav is None and len(self.fixes) >= 2:
            from sonartrack.io.nmea import GeoTrack, navigation_from_track

            f = np.array(self.fixes)
            has = np.isfinite(f[:, 3])
            track = GeoTrack(f[:, 0], f[:, 1], f[:, 2], f[has, 0], f[has, 3], "HDT" if has.sum() else "none")
            self._nav = navigation_from_track(track, self.start_utc, tow_length_m=self.tow_length_m,
                                              projection=self.projection)[0]
        return self._nav

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
        return {"fixes": list(self.fixes), "coasting": self.coasting, "dropouts": self.dropouts, "origin": origin}

    def restore(self, state: dict) -> None:
        """Back to a checkpoint's :meth:`state`."""
        from sonartrack.io.nmea import LocalProjection

        self.fixes = [tuple(f) for f in state["fixes"]]
        self.coasting, self.dropouts = bool(state["coasting"]), int(state["dropouts"])
        origin = state["origin"]
        self.projection = None if origin is None else LocalProjection(*origin)
        self._nav = None
