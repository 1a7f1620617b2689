"""Whether a navigation log can be taken on trust: positions that jump, headings that are not the course made
good, and holes in the log over the recording.

* Jumps (:func:`drop_position_jumps`, NMEA and GPX logs): a ship that tows an array makes well under
  :data:`MAX_LOG_SPEED_KN` (60 kn, the toolkit's own 58 kn target limit, ``verdict.max_speed_mps``, rounded up).
  A run of at most :data:`MAX_DROPPED_RUN` fixes that leaves the track faster than that and comes back to it (one
  fix in the wrong hemisphere, a multipath jump) is dropped and reported with its lines; a track that leaves and
  does not come back is refused, naming the two fixes.
* Headings (:func:`check_logged_heading`, NMEA and GPX logs whose heading is logged): judged against the course
  made good between fixes at least :data:`COURSE_STEP_M` apart (a GNSS fix's metres of noise average out). A
  heading that fits only when read as radians is refused (io/navigation.py :func:`heading_unit`); so is one whose
  median misfit to the course exceeds :data:`MAX_HEADING_MISFIT_DEG` -- no towing ship drifts that far off its
  heading, while a hemisphere letter wrong on every fix mirrors the course (N/S: c -> 180 - c; E/W: c -> -c).
* Gaps (:func:`navigation_gaps`, every kind of navigation): an interval between samples longer than
  :data:`GAP_FACTOR` times the log's median interval and than :data:`MIN_GAP_S` (both: a 1 Hz log's 10 s hole, a
  10 s log's 50 s one; a single missed fix is no gap). Positions and headings across it are interpolated in a
  straight line, which is right only when the ship kept its course and speed: that is judged from the headings at
  the gap's two ends (within :data:`MAX_GAP_TURN_DEG`) and the distance and direction made good across it against
  the ship's speed and course either side (within :data:`MAX_GAP_SPEED_CHANGE`, or :data:`GAP_POSITION_TOL_M`). A
  turn in the gap puts the array's interpolated heading off by tens of degrees (a 100 s hole over a 45 deg turn:
  10 deg and 37 m), which bearings-only TMA reads as the target's motion: the faces report every gap and withhold
  the range of a target tracked across one the ship turned in (systems/passive/files.py).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from datetime import UTC, datetime

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.core.units import KNOT_MPS
from sonartrack.io.navigation import MIN_COURSE_SEGMENTS, MIN_COURSE_SPEED_MPS, Navigation, heading_unit
from sonartrack.io.nmea import GeoTrack

#: fastest ownship taken between two fixes (kn); module doc
MAX_LOG_SPEED_KN = 60.0
#: most consecutive fixes dropped as one jump away from the track and back
MAX_DROPPED_RUN = 5
#: fixes at least this far apart (m) give the course made good a heading is judged against
COURSE_STEP_M = 30.0
#: a logged heading whose median misfit to the course made good exceeds this (deg) is not this ship's heading
MAX_HEADING_MISFIT_DEG = 45.0
#: a gap is an interval longer than this many times the log's median interval ...
GAP_FACTOR = 5.0
#: ... and than this (s)
MIN_GAP_S = 10.0
#: a heading change across a gap beyond this (deg) is a turn in it
MAX_GAP_TURN_DEG = 5.0
#: distance made good across a gap that differs from the speed either side times its length by more than this
#: fraction (or than GAP_POSITION_TOL_M, whichever is larger) is a change of speed or a zig-zag in it
MAX_GAP_SPEED_CHANGE = 0.05
#: positions' tolerance across a gap (m): a GNSS fix's noise
GAP_POSITION_TOL_M = 10.0
#: the speed and course either side of a gap are made good over this long (s) at most
GAP_SIDE_S = 60.0


def _fix_name(track: GeoTrack, i: int) -> str:
    when = datetime.fromtimestamp(float(track.time_unix_s[i]), UTC).strftime("%H:%M:%S UTC")
    return f"line {int(track.fix_line[i])} ({when})" if track.fix_line.size else f"point {i + 1} ({when})"


def _speed_mps(geod, track: GeoTrack, i: int, j: int) -> float:
    _, _, d = geod.inv(track.lon_deg[i], track.lat_deg[i], track.lon_deg[j], track.lat_deg[j])
    return float(d) / float(track.time_unix_s[j] - track.time_unix_s[i])


def _kept_fixes(geod, track: GeoTrack, path) -> list[int]:
    """Indices of the fixes kept (module doc: runs that jump away and back dropped); InputError otherwise."""
    limit, n = MAX_LOG_SPEED_KN * KNOT_MPS, track.time_unix_s.size
    keep, k = [0], 1
    while k < n:
        last = keep[-1]
        if _speed_mps(geod, track, last, k) <= limit:
            keep.append(k)
            k += 1
            continue
        back = next((j for j in range(k + 1, min(n, k + 1 + MAX_DROPPED_RUN)) if _speed_mps(geod, track, last, j)
                     <= limit), None)
        if back is not None:
            k = back
        elif len(keep) == 1 and last == 0 and k + 1 < n and _speed_mps(geod, track, k, k + 1) <= limit:
            keep = [k]  # the first fix is the one off the track
            k += 1
        else:
            kn = _speed_mps(geod, track, last, k) / KNOT_MPS
            raise InputError(f"navigation log {path}: the ship moves at {kn:.0f} kn from the fix of "
                             f"{_fix_name(track, last)} to that of {_fix_name(track, k)} and does "
                             f"not come back (no towing ship makes {MAX_LOG_SPEED_KN:g} kn): a position error in the "
                             "log (a hemisphere letter, a unit?): fix or delete those fixes")
    return keep


def drop_position_jumps(track: GeoTrack, path) -> tuple[GeoTrack, list[str]]:
    """The track without the runs of fixes that jump away from it and back (module doc), and a warning line naming
    them.

    Parameters
    ----------
    track : GeoTrack
        A ship's UTC track.
    path : str or path-like
        The log (for the messages).

    Returns
    -------
    (GeoTrack, list of str)
        The fixes kept; no warning when none is dropped. InputError when the track leaves at more than
        :data:`MAX_LOG_SPEED_KN` and does not come back, or when more than 5 % of the fixes would be dropped.
    """
    from pyproj import Geod

    geod = Geod(ellps="WGS84")
    n = track.time_unix_s.size
    _, _, d = geod.inv(track.lon_deg[:-1], track.lat_deg[:-1], track.lon_deg[1:], track.lat_deg[1:])
    if n < 2 or np.all(np.asarray(d) / np.diff(track.time_unix_s) <= MAX_LOG_SPEED_KN * KNOT_MPS):
        return track, []
    keep = _kept_fixes(geod, track, path)
    dropped = sorted(set(range(n)) - set(keep))
    names = ", ".join(_fix_name(track, i) for i in dropped[:5]) + (" ..." if len(dropped) > 5 else "")
    if len(dropped) > max(MAX_DROPPED_RUN, 0.05 * n):
        raise InputError(f"navigation log {path}: {len(dropped)} of {n} fixes jump away from the track faster than "
                         f"{MAX_LOG_SPEED_KN:g} kn ({names}): the log's positions are not to be trusted: fix the log")
    _, _, far = geod.inv(track.lon_deg[dropped], track.lat_deg[dropped],
                         np.interp(dropped, keep, track.lon_deg[keep]), np.interp(dropped, keep, track.lat_deg[keep]))
    sel = np.asarray(keep)
    kept = replace(track, time_unix_s=track.time_unix_s[sel], lat_deg=track.lat_deg[sel], lon_deg=track.lon_deg[sel],
                   fix_line=track.fix_line[sel] if track.fix_line.size else track.fix_line)
    return kept, [f"warning: navigation log {path}: {len(dropped)} fix(es) dropped, up to {np.max(far) / 1e3:.3g} km "
                  f"off the track either side and back within {MAX_DROPPED_RUN} fixes (a wrong hemisphere letter, a "
                  f"multipath jump?): {names}"]


def _course_steps(t, x, y) -> np.ndarray:
    """Indices of fixes at least :data:`COURSE_STEP_M` apart along the track."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    idx = np.searchsorted(s, np.arange(0.0, s[-1] + 1e-9, COURSE_STEP_M))
    return np.unique(np.clip(idx, 0, len(s) - 1))


def check_logged_heading(nav: Navigation, source: str, path) -> None:
    """Refuse a logged heading (HDT, VTG, RMC or GPX course) that is not the ship's, judged against the course made
    good between its fixes (module doc).

    Parameters
    ----------
    nav : Navigation
        The ship's navigation from the log (io/nmea.py ``navigation_from_track``).
    source : str
        Where the heading came from (``GeoTrack.heading_source``); "none" (the direction of motion): nothing to judge.
    path : str or path-like
        The log (for the messages).

    Raises
    ------
    InputError
        When the heading fits the course only as radians, or misfits it by more than :data:`MAX_HEADING_MISFIT_DEG`.
    """
    if source == "none":
        return
    k = _course_steps(nav.time_s, nav.x_m, nav.y_m)
    t, x, y, h = nav.time_s[k], nav.x_m[k], nav.y_m[k], np.rad2deg(nav.heading_rad[k])
    col = f"the {source} heading"
    heading_unit(h, t, x, y, col=col, path=path, fix="log the heading in degrees (a logger set to radians?)")
    dx, dy, dt = np.diff(x), np.diff(y), np.diff(t)
    moving = np.hypot(dx, dy) >= MIN_COURSE_SPEED_MPS * dt
    if moving.sum() < MIN_COURSE_SEGMENTS:
        return
    course = np.rad2deg(np.arctan2(dx, dy))[moving]
    mid = (0.5 * (h[1:] + h[:-1]))[moving]
    misfit = float(np.median(np.abs((mid - course + 180.0) % 360.0 - 180.0)))
    if misfit > MAX_HEADING_MISFIT_DEG:
        raise InputError(f"navigation log {path}: the fixes move on courses {misfit:.0f} deg (median) off {col}, more "
                         f"than any ship drifts ({MAX_HEADING_MISFIT_DEG:g} deg): a hemisphere letter (N/S, E/W) wrong "
                         "on the fixes, or headings of another unit or reference: fix the log")


@dataclass(frozen=True, slots=True)
class NavGap:
    """A hole in the navigation (module doc): from ``start_s`` to ``end_s`` (s on the navigation's time base),
    whether the ship kept its course and speed across it (``why`` says how it did not), and the time until which
    the array's position rests on the interpolation (``array_end_s``: the tow lag later)."""

    start_s: float
    end_s: float
    median_interval_s: float
    kept_course: bool
    why: str = ""
    array_end_s: float = np.nan

    def reason(self) -> str:
        """The targets' reason of a range not determined (tma/verdict.py ``with_reasons``)."""
        return f"navigation gap {self.start_s:.0f}-{self.end_s:.0f} s during the track, the ship turned in it"

    def describe(self) -> str:
        """One line about the gap, without the targets."""
        how = f"the ship turned in it ({self.why})" if not self.kept_course else (
            "the ship kept its course and speed across it: positions interpolated")
        return (f"no navigation for {self.end_s - self.start_s:.0f} s ({self.start_s:.0f}-{self.end_s:.0f} s; the "
                f"log's median interval {self.median_interval_s:.3g} s): {how}")


def _made_good(nav: Navigation, a_s: float, b_s: float) -> tuple[float, float]:
    """Speed (m/s) and course (deg) made good by the ship from ``a_s`` to ``b_s``."""
    x, y = np.interp([a_s, b_s], nav.time_s, nav.x_m), np.interp([a_s, b_s], nav.time_s, nav.y_m)
    dx, dy = x[1] - x[0], y[1] - y[0]
    return float(np.hypot(dx, dy) / (b_s - a_s)), float(np.rad2deg(np.arctan2(dx, dy)))


def _how_turned(nav: Navigation, t0: float, t1: float) -> str:
    """"" when the ship kept its course and speed from ``t0`` to ``t1`` (module doc), else how it did not."""
    turn = max(abs(float(np.rad2deg(np.diff(np.interp([t0, t1], nav.time_s, h)))[0]))
               for h in (nav.heading_rad, nav.array_heading_rad))
    if turn > MAX_GAP_TURN_DEG:
        return f"the heading changes {turn:.0f} deg across it"
    sides = [_made_good(nav, a, b) for a, b in ((max(t0 - GAP_SIDE_S, nav.time_s[0]), t0),
                                                (t1, min(t1 + GAP_SIDE_S, nav.time_s[-1]))) if b - a > 0]
    sides = [(v, c) for v, c in sides if v >= MIN_COURSE_SPEED_MPS]
    if not sides:
        return ""
    v_gap, c_gap = _made_good(nav, t0, t1)
    v_side = float(np.mean([v for v, _ in sides]))
    tol_m = max(MAX_GAP_SPEED_CHANGE * v_side * (t1 - t0), GAP_POSITION_TOL_M)
    if abs(v_gap - v_side) * (t1 - t0) > tol_m:
        return f"{v_gap:.2f} m/s made good across it, {v_side:.2f} m/s either side"
    off = max(abs((c_gap - c + 180.0) % 360.0 - 180.0) for _, c in sides)
    if off > max(MAX_GAP_TURN_DEG, np.rad2deg(np.arctan2(tol_m, v_gap * (t1 - t0)))):
        return f"the course made good across it is {off:.0f} deg off the course either side"
    return ""


def navigation_gaps(sample_time_s, nav: Navigation, start_s: float, end_s: float, *, lag_s: float = 0.0
                    ) -> list[NavGap]:
    """The gaps (module doc) between samples of the navigation that overlap ``[start_s, end_s]``.

    Parameters
    ----------
    sample_time_s : ndarray (n,)
        Times of the log's samples (s, on the navigation's time base; its fixes, or its heading sentences).
    nav : Navigation
        The navigation (positions and headings at its times).
    start_s, end_s : float
        The recording (s).
    lag_s : float
        How long after a gap the array's position still rests on it (s; the tow length over the speed).

    Returns
    -------
    list of NavGap
        In time order; empty when the log has no gap over the recording.
    """
    t = np.asarray(sample_time_s, float)
    if t.size < 3:
        return []
    dt = np.diff(t)
    median = float(np.median(dt))
    wide = np.flatnonzero((dt > max(GAP_FACTOR * median, MIN_GAP_S)) & (t[1:] > start_s) & (t[:-1] < end_s))
    gaps = []
    for i in wide:
        why = _how_turned(nav, float(t[i]), float(t[i + 1]))
        gaps.append(NavGap(float(t[i]), float(t[i + 1]), median, not why, why, float(t[i + 1]) + lag_s))
    return gaps
