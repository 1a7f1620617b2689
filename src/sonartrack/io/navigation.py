"""Navigation of a towed-array platform: the ownship and the array centre against time (``sonartrack passive``).

File (CSV or Parquet), one row per time, SI units, headings in degrees clockwise from north::

    time_s, x_m, y_m, heading_deg[, array_x_m, array_y_m, array_heading_deg]

x is east, y north. The array columns give the towed array's centre and axis (the sensor of the bearings);
without them the array is taken to be at the ship, along its heading (a hull or short array): stated in a warning,
and refused when the ship turns (:func:`check_array_fallback`). A heading column is judged against the course made
good between the positions (:func:`heading_unit`), so radians are caught on a straight course too. ``sonartrack
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
    read_numeric_table,
)
from sonartrack.tma.records import OwnshipTrack

NAV_COLUMNS = ["time_s", "x_m", "y_m", "heading_deg"]
ARRAY_COLUMNS = ["array_x_m", "array_y_m", "array_heading_deg"]
#: a step between rows at this speed or more has a course made good to judge the heading's unit by (1 kn)
MIN_COURSE_SPEED_MPS = 0.5
#: ... and this many such steps are needed
MIN_COURSE_SEGMENTS = 5
#: without array columns, a ship that turns more than this leaves the towed array's heading unknown where the side
#: decision needs it (course keeping wanders by a few degrees)
MAX_FALLBACK_TURN_DEG = 10.0


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
    #: False when the file had no array columns and the array was taken at the ship (:func:`check_array_fallback`)
    array_given: bool = True

    def array_at(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Array centre and axis heading at times ``t_s``, interpolated linearly.

        Headings are unwrapped, so a turn through north interpolates the short way; times outside the record
        take the end values (no extrapolation).

        Parameters
        ----------
        t_s : float or array_like, shape (n,)
            Times (s).

        Returns
        -------
        xy : ndarray, shape (n, 2)
            Array centre [x east, y north] (m).
        heading : ndarray, shape (n,)
            Axis heading (rad, clockwise from north, unwrapped).
        """
        t = np.asarray(t_s, float)
        xy = np.stack([np.interp(t, self.time_s, self.array_x_m), np.interp(t, self.time_s, self.array_y_m)], -1)
        return xy, np.interp(t, self.time_s, self.array_heading_rad)

    def array_track(self) -> OwnshipTrack:
        """The array centre as the sensor track of bearings-only TMA.

        Returns
        -------
        OwnshipTrack
            Times (s) and array-centre positions (m).
        """
        return OwnshipTrack(time_s=self.time_s, x_m=self.array_x_m, y_m=self.array_y_m)

    def ship_track(self) -> OwnshipTrack:
        """The ownship's own positions as a track.

        Returns
        -------
        OwnshipTrack
            Times (s) and ship positions (m).
        """
        return OwnshipTrack(time_s=self.time_s, x_m=self.x_m, y_m=self.y_m)


def _heading_rad(df, col: str, path, track: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    deg = numeric_column(df, col, "navigation", path, lo=-720.0, hi=720.0,
                         fix="give headings in degrees clockwise from north")
    if heading_unit(deg, *track, col=col, path=path) != "degrees":
        check_not_radians(deg, col, "navigation", path)
    return np.unwrap(np.deg2rad(deg))


def _median_misfit_deg(heading_deg: np.ndarray, course_deg: np.ndarray) -> float:
    """Median |heading - course| (deg, wrapped to [0, 180])."""
    return float(np.median(np.abs((heading_deg - course_deg + 180.0) % 360.0 - 180.0)))


def heading_unit(heading, time_s, x_m, y_m, *, col: str = "heading_deg", path="navigation",
                 fix: str = "multiply the column by 180/pi") -> str:
    """Which unit a heading column is in, judged against the course made good between the rows' positions.

    A moving platform's heading follows its course made good, atan2(dx, dy), within its drift angle. A column
    whose values all lie within +-2 pi can be read both ways; the reading whose median misfit to the course is
    at least three times smaller wins, when the other misfits by more than 2 deg. A straight course in radians
    (1.05 for 60 deg) is caught so, while the spread of the values alone (:func:`check_not_radians`) sees none.

    Parameters
    ----------
    heading : ndarray (n,)
        The column's values (deg, as the file claims).
    time_s, x_m, y_m : ndarray (n,)
        Times (s) and positions (m) of the same rows.
    col : str
        The column's name (for the message).
    path : str or path-like
        The file (for the message).
    fix : str
        The message's fix.

    Returns
    -------
    str
        "degrees" when the course confirms degrees; "unknown" when the platform hardly moves (fewer than
        :data:`MIN_COURSE_SEGMENTS` steps of at least :data:`MIN_COURSE_SPEED_MPS`) or both readings fit alike.
        Raises InputError when the course confirms radians.
    """
    h = np.asarray(heading, float)
    dx, dy, dt = np.diff(x_m), np.diff(y_m), np.diff(time_s)
    moving = np.hypot(dx, dy) >= MIN_COURSE_SPEED_MPS * dt
    if moving.sum() < MIN_COURSE_SEGMENTS:
        return "unknown"
    course = np.rad2deg(np.arctan2(dx, dy))[moving]
    as_deg = np.unwrap(h, period=360.0)
    as_rad = np.rad2deg(np.unwrap(h, period=2.0 * np.pi))
    misfit_deg = _median_misfit_deg(0.5 * (as_deg[1:] + as_deg[:-1])[moving], course)
    misfit_rad = _median_misfit_deg(0.5 * (as_rad[1:] + as_rad[:-1])[moving], course)
    if np.all(np.abs(h) <= 2.0 * np.pi) and misfit_deg > 2.0 and 3.0 * misfit_rad < misfit_deg:
        raise InputError(f"navigation file {path}: {col} fits the course made good between the positions only when "
                         f"read as radians (median misfit {misfit_rad:.1f} deg as radians, {misfit_deg:.1f} deg as "
                         f"degrees): {fix}")
    return "degrees" if 3.0 * misfit_deg < misfit_rad else "unknown"


def read_navigation(path) -> Navigation:
    """Read and check a navigation file (module docstring).

    Parameters
    ----------
    path : str or path-like
        CSV or Parquet file with ``time_s, x_m, y_m, heading_deg[, array_x_m, array_y_m, array_heading_deg]``.

    Returns
    -------
    Navigation
        Positions (m) and unwrapped headings (rad, clockwise from north); without array columns the array
        is at the ship, along its heading.

    Raises
    ------
    InputError
        On any failed check (unsorted times, one row, radians, implausible speed, partial array columns).
    """
    what = "navigation"
    df = read_numeric_table(path, what)
    check_columns(df, NAV_COLUMNS, what, path)
    t = numeric_column(df, "time_s", what, path, lo=-MAX_TIME_S, hi=MAX_TIME_S)
    check_sorted(t, what, path, strict=True)
    require(len(t) >= 2, f"{what} file {path} has one row: give at least two times")
    x, y = (numeric_column(df, c, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M) for c in ("x_m", "y_m"))
    check_platform_speed(t, x, y, what, path)
    heading = _heading_rad(df, "heading_deg", path, (t, x, y))
    have = [c for c in ARRAY_COLUMNS if c in df.columns]
    if have and len(have) < len(ARRAY_COLUMNS):
        raise InputError(f"{what} file {path} has {', '.join(have)} but not all of {', '.join(ARRAY_COLUMNS)}: give "
                         "all three array columns or none (the array is then taken at the ship)")
    if not have:
        return Navigation(t, x, y, heading, x, y, heading, array_given=False)
    ax, ay = (numeric_column(df, c, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M) for c in ("array_x_m",
                                                                                                  "array_y_m"))
    check_platform_speed(t, ax, ay, what, path, "array")
    return Navigation(t, x, y, heading, ax, ay, _heading_rad(df, "array_heading_deg", path, (t, ax, ay)))


def check_array_fallback(nav: Navigation, path="navigation") -> str | None:
    """State the array-at-the-ship fallback of a file without array columns, or refuse it where the side decision
    would rest on it.

    Without array columns the array is taken at the ship, along its heading: right for a hull array, wrong for a
    towed one, whose centre is the tow length astern and whose heading lags the ship's through a turn by tow
    length / speed. A line array's side is decided by how the bearings change when the array turns, so a ship that
    turns more than :data:`MAX_FALLBACK_TURN_DEG` would have its side (and its range) decided on headings the file
    does not give.

    Parameters
    ----------
    nav : Navigation
        The navigation read.
    path : str or path-like
        The file (for the message).

    Returns
    -------
    str or None
        None when the file gives the array; else one warning line (the ship keeps its course). Raises
        InputError when the ship turns.
    """
    if nav.array_given:
        return None
    turn_deg = float(np.rad2deg(np.ptp(nav.heading_rad)))
    require(turn_deg <= MAX_FALLBACK_TURN_DEG,
            f"navigation file {path} has no array columns and the ship turns {turn_deg:.0f} deg: the side of each "
            "target would be decided on array headings the file does not give (a towed array's headings lag the "
            f"ship's); add {', '.join(ARRAY_COLUMNS)} (for a hull array, copies of x_m, y_m, heading_deg)")
    return (f"warning: navigation file {path} has no array columns: the array is taken at the ship along its heading "
            "(a hull array); the ship keeps its course, so no side is resolved")


def check_navigation_covers(nav: Navigation, start_s: float, end_s: float, path="navigation") -> None:
    """Require the navigation to span the recording ``[start_s, end_s]`` (positions are not extrapolated).

    Parameters
    ----------
    nav : Navigation
        The navigation.
    start_s, end_s : float
        Recording start and end (s, on the navigation's time base).
    path : str, default "navigation"
        File name used in the message.

    Raises
    ------
    InputError
        If the recording runs outside the navigation's times.
    """
    t0, t1 = float(nav.time_s[0]), float(nav.time_s[-1])
    if t0 > start_s or t1 < end_s:
        raise InputError(f"{path} covers {t0:g}..{t1:g} s but the recording runs {start_s:g}..{end_s:g} s: give "
                         "navigation for the whole recording (times in seconds from the recording's start)")
