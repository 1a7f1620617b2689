"""Where a survey's ships were: each recording's ownship track and its targets' ML positions, in lat/lon when the
navigation gives them.

A recording's folder (systems/survey/files.py) names its navigation file in status.json and holds targets.csv,
whose positions are in the chain's local frame (x east, y north, m). For an NMEA 0183 log or a GPX track that
frame is the azimuthal equidistant projection about the log's first fix kept (systems/passive/files.py
``_read_utc_navigation``: the fixes that jump away and back dropped first, io/nav_checks.py), so the log is read
again the same way, the ownship drawn from its own latitudes and longitudes and the targets' x/y turned into
latitude and longitude by the inverse projection (io/nmea.py ``LocalProjection``). A navigation table (CSV,
Parquet) is in a local frame of its own: the recording is drawn in km in that frame, and said so. A target's
position exists only where its range is determined (targets.csv leaves x/y empty elsewhere); its bearings do
not make a position and are not drawn.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError

#: "latlon": east is longitude and north latitude (deg, WGS84); "local": x east and y north (km) of the file's frame
FRAMES = ("latlon", "local")


@dataclass(frozen=True, slots=True)
class TargetPath:
    """A target's ML solution over time: times (s from the recording's start), east and north in its recording's
    frame (NaN where the range is not determined), side at each time, last true bearing (deg)."""

    target_id: int
    time_s: np.ndarray
    east: np.ndarray
    north: np.ndarray
    side: str
    last_bearing_deg: float

    @property
    def determined(self) -> np.ndarray:
        """Where the position is known (the range determined)."""
        return np.isfinite(self.east) & np.isfinite(self.north)


@dataclass(frozen=True, slots=True)
class RecordingPositions:
    """A recording's ownship track (times in s from its start; east, north in ``frame``: :data:`FRAMES`) and its
    targets; ``start_utc`` None when its start is unknown; ``note`` says what could not be drawn and why."""

    name: str
    frame: str
    start_utc: datetime | None
    time_s: np.ndarray
    east: np.ndarray
    north: np.ndarray
    targets: list[TargetPath] = field(default_factory=list)
    note: str = ""


def _over(t_s: np.ndarray, span_s: float) -> tuple[int, int]:
    """The slice of the navigation's samples over the recording [0, span_s] and the one on each side of it, so that
    the drawn track spans the recording whole."""
    inside = np.flatnonzero((t_s >= 0) & (t_s <= span_s))
    return (max(inside[0] - 1, 0), min(inside[-1] + 2, t_s.size)) if inside.size else (0, 0)


def _utc_track(path: Path, kind: str):
    """The UTC log as the chain read it: its track with the jumping fixes dropped (module doc)."""
    from sonartrack.io.nav_checks import drop_position_jumps

    if kind == "gpx":
        from sonartrack.io.gpx import read_gpx

        track = read_gpx(path)
    else:
        from sonartrack.io.nmea import read_nmea

        track = read_nmea(path).track
    return drop_position_jumps(track, path)[0]


def _targets(folder: Path, to_frame) -> list[TargetPath]:
    """The ML rows of targets.csv per target, positions turned into the recording's frame by ``to_frame``."""
    import pandas as pd

    path = folder / "targets.csv"
    if not path.is_file():
        return []
    t = pd.read_csv(path)
    if t.empty or "method" not in t.columns:
        return []
    out = []
    for tid, g in t[t["method"] == "ml"].groupby("target_id", sort=True):
        g = g.sort_values("time_s")
        east, north = to_frame(g["x_m"].to_numpy(float), g["y_m"].to_numpy(float))
        side = str(g["side"].iloc[-1]) if "side" in g.columns else ""
        out.append(TargetPath(int(tid), g["time_s"].to_numpy(float), np.asarray(east, float), np.asarray(north, float),
                              side, float(g["bearing_deg"].iloc[-1])))
    return out


def _latlon(folder: Path, name: str, nav: Path, kind: str, start: datetime, span_s: float) -> RecordingPositions:
    from sonartrack.io.nmea import LocalProjection

    track = _utc_track(nav, kind)
    proj = LocalProjection(float(track.lat_deg[0]), float(track.lon_deg[0]))
    t = track.time_unix_s - start.timestamp()
    lo, hi = _over(t, span_s)

    def to_latlon(x_m, y_m):
        lat, lon = proj.latlon(x_m, y_m)
        return lon, lat

    return RecordingPositions(name, "latlon", start, t[lo:hi], track.lon_deg[lo:hi], track.lat_deg[lo:hi],
                              _targets(folder, to_latlon))


def _local(folder: Path, name: str, nav: Path, start: datetime | None, span_s: float) -> RecordingPositions:
    from sonartrack.io.navigation import read_navigation

    n = read_navigation(nav)
    lo, hi = _over(n.time_s, span_s)
    return RecordingPositions(name, "local", start, n.time_s[lo:hi], n.x_m[lo:hi] / 1e3, n.y_m[lo:hi] / 1e3,
                              _targets(folder, lambda x, y: (x / 1e3, y / 1e3)),
                              note=f"{name}: navigation {nav.name} is in a local frame (x east, y north from its own "
                                   "origin), not in latitude and longitude: drawn in km on the local panel")


def recording_positions(folder, status: dict) -> RecordingPositions | None:
    """The ownship track and target positions of one stored recording (module doc).

    Parameters
    ----------
    folder : path
        The recording's folder (``OUT/recordings/NAME``).
    status : dict
        Its status.json (name, status, navigation, start_utc, duration_s).

    Returns
    -------
    RecordingPositions or None
        None when the recording did not run (status not ok). When its navigation file cannot be read any more
        (moved, changed), a track with no points and a note saying so.
    """
    from sonartrack.systems.passive.files import navigation_kind

    if status.get("status") != "ok":
        return None
    name, folder = str(status["name"]), Path(folder)
    start = datetime.fromisoformat(status["start_utc"]) if status.get("start_utc") else None
    nav = Path(str(status.get("navigation", "")))
    try:
        kind = navigation_kind(nav)
        span_s = float(status.get("duration_s", 0.0))
        if kind != "table" and start is not None:
            return _latlon(folder, name, nav, kind, start, span_s)
        return _local(folder, name, nav, start, span_s)
    except (InputError, OSError, ValueError) as e:
        why = " ".join(str(e).split())
        empty = np.zeros(0)
        return RecordingPositions(name, "local", start, empty, empty, empty, [],
                                  note=f"{name}: ownship and targets not drawn: {why}")
