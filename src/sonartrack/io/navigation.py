"""Navigation of a towed-array platform: the ownship and the array centre against time (``sonartrack passive``).

File (CSV or Parquet), one row per time, SI units, headings in degrees clockwise from north::

    time_s, x_m, y_m, heading_deg[, array_x_m, array_y_m, array_heading_deg]

x is east, y north. The array columns give the towed array's centre and axis (the sensor of the bearings);
without them the array is taken to be at the ship, along its heading (a hull or short array). ``sonartrack
simulate`` writes this file (nav.csv).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.tables import (
    MAX_POSITION_M,
    MAX_TIME_S,
    check_columns,
    check_not_radians,
    check_platform_speed,
    check_sorted,
    numeric_column,
    read_table,
)
from sonartrack.tma.records import OwnshipTrack

NAV_COLUMNS = ["time_s", "x_m", "y_m", "heading_deg"]
ARRAY_COLUMNS = ["array_x_m", "array_y_m", "array_heading_deg"]


@dataclass(frozen=True, slots=True)
class Navigation:
    """Ownship and array-centre positions (m) and headings (rad, clockwise from north, unwrapped) against time."""

    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray
    array_x_m: np.ndarray
    array_y_m: np.ndarray
    array_heading_rad: np.ndarray

    def array_at(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Array centre (n, 2) m and axis heading (n,) rad at times ``t_s``, interpolated linearly (headings
        are unwrapped, so a turn through north interpolates the short way)."""
        t = np.asarray(t_s, float)
        xy = np.stack([np.interp(t, self.time_s, self.array_x_m), np.interp(t, self.time_s, self.array_y_m)], -1)
        return xy, np.interp(t, self.time_s, self.array_heading_rad)

    def array_track(self) -> OwnshipTrack:
        """The array centre as the sensor track of bearings-only TMA."""
        return OwnshipTrack(time_s=self.time_s, x_m=self.array_x_m, y_m=self.array_y_m)

    def ship_track(self) -> OwnshipTrack:
        return OwnshipTrack(time_s=self.time_s, x_m=self.x_m, y_m=self.y_m)


def _heading_rad(df, col: str, path) -> np.ndarray:
    deg = numeric_column(df, col, "navigation", path, lo=-720.0, hi=720.0,
                         fix="give headings in degrees clockwise from north")
    check_not_radians(deg, col, "navigation", path)
    return np.unwrap(np.deg2rad(deg))


def read_navigation(path) -> Navigation:
    """Read and check a navigation file (module docstring) into a :class:`Navigation`."""
    what = "navigation"
    df = read_table(path, what)
    check_columns(df, NAV_COLUMNS, what, path)
    t = numeric_column(df, "time_s", what, path, lo=-MAX_TIME_S, hi=MAX_TIME_S)
    check_sorted(t, what, path, strict=True)
    require(len(t) >= 2, f"{what} file {path} has one row: give at least two times")
    x, y = (numeric_column(df, c, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M) for c in ("x_m", "y_m"))
    check_platform_speed(t, x, y, what, path)
    heading = _heading_rad(df, "heading_deg", path)
    have = [c for c in ARRAY_COLUMNS if c in df.columns]
    if have and len(have) < len(ARRAY_COLUMNS):
        raise InputError(f"{what} file {path} has {', '.join(have)} but not all of {', '.join(ARRAY_COLUMNS)}: give "
                         "all three array columns or none (the array is then taken at the ship)")
    if not have:
        return Navigation(t, x, y, heading, x, y, heading)
    ax, ay = (numeric_column(df, c, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M) for c in ("array_x_m",
                                                                                                  "array_y_m"))
    check_platform_speed(t, ax, ay, what, path, "array")
    return Navigation(t, x, y, heading, ax, ay, _heading_rad(df, "array_heading_deg", path))


def check_navigation_covers(nav: Navigation, start_s: float, end_s: float, path="navigation") -> None:
    """The navigation must span the recording [start_s, end_s] (positions are not extrapolated)."""
    t0, t1 = float(nav.time_s[0]), float(nav.time_s[-1])
    if t0 > start_s or t1 < end_s:
        raise InputError(f"{path} covers {t0:g}..{t1:g} s but the recording runs {start_s:g}..{end_s:g} s: give "
                         "navigation for the whole recording (times in seconds from the recording's start)")
