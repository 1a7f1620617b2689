"""The live active chain's display updates: the B-scan of a ping with its tracks, and the active target table.

The contract (/work/team/LIVE.md, "active pings"), numbers as lists of float, angles in degrees, times in s since
the stream's start::

    {"type": "bscan", "t_s", "ping", "bearing_deg": [cone per beam], "range_m": [per bin],
     "level_db": [[per range] per bearing], "detections": int,
     "tracks": [{"id", "status": "tentative"|"confirmed", "cone_deg", "range_m"}]}
    {"type": "active_targets", "t_s", "ping", "rows": [{"id", "track", "mirror_track", "side", "decision",
     "bearing_deg", "range_m", "range_sd_m", "reason", "tonal_hz": null, "course_deg", "speed_mps", "x_m", "y_m",
     "ellipse", "mirror": {"x_m", "y_m"} | null, "legs": [], "log_lr"}]}

A B-scan's ``bearing_deg`` are the beams' cone angles (from the array's forward axis) and ``range_m`` is c tau / 2
of each bin's travel time tau; a track is drawn on it where its echo falls: its cone angle seen from the array
centre and half its bistatic path, (|x - Tx| + |x - Rx|) / 2 (paper P4 eq. 1). A target row is a target of
systems/active/targets.py (a confirmed track and its mirror twin): ``side`` starboard | port once decided, else
"undecided" with ``decision`` "undecided" and the other hypothesis in ``mirror`` (the console shows an "undecided
pair"); bearing (clockwise from north) and range from the array centre, the range's sd the position covariance
along the line of sight, sqrt(u^T P u), the 95 % ellipse from the same covariance.
"""

from __future__ import annotations

import math

import numpy as np

from sonartrack.systems.live.updates import ellipse_points


def _num(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def echo_place(geometry, t_s: float, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cone angle (deg), half bistatic range (m)) of positions ``xy (n, 2)`` at ``t_s``: where their echoes fall
    on the B-scan (module doc)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    tx, rx, h = geometry.tx_at(t_s), geometry.rx_at(t_s), float(geometry.heading_at(t_s))
    d = xy - rx
    r_rx = np.hypot(d[:, 0], d[:, 1])
    axis = np.array([math.sin(h), math.cos(h)])
    cone = np.degrees(np.arccos(np.clip(d @ axis / np.maximum(r_rx, 1e-9), -1.0, 1.0)))
    return cone, 0.5 * (np.hypot(*(xy - tx).T) + r_rx)


def bscan_update(t_s: float, ping: int, cone_deg, range_m, row: np.ndarray, detections: int) -> dict:
    """One ping's B-scan: ``row (beams, bins)`` the largest statistic of each bin (run.py ``_bscan_row``), in dB."""
    return {"type": "bscan", "t_s": float(t_s), "ping": int(ping), "bearing_deg": [float(c) for c in cone_deg],
            "range_m": [float(r) for r in range_m],
            # in float64: a float32 rounded to 0.01 is printed with 17 digits (462 kB a ping instead of ~150)
            "level_db": (10.0 * np.log10(np.maximum(np.asarray(row, float), 1e-12))).round(2).tolist(),
            "detections": int(detections),
            "tracks": []}


def scan_tracks(active_tracks, geometry, t_s: float) -> list[dict]:
    """The tracks of the scan at ``t_s`` where they fall on the B-scan."""
    tr = active_tracks.tracks
    rows = np.nonzero(tr.time_s == t_s)[0]
    if not len(rows):
        return []
    cone, rng = echo_place(geometry, t_s, tr.x[rows, :2])
    return [{"id": int(tr.track_id[k]), "status": "confirmed" if tr.confirmed[k] else "tentative",
             "cone_deg": float(c), "range_m": float(r)} for k, c, r in zip(rows, cone, rng, strict=True)]


def _state(active_tracks, track_id: int) -> tuple[float, np.ndarray, np.ndarray] | None:
    """(time, state [x, y, vx, vy], covariance 4x4) of a track's last confirmed row; None when never confirmed."""
    tr = active_tracks.tracks
    rows = np.nonzero((tr.track_id == track_id) & tr.confirmed)[0]
    if track_id < 0 or not len(rows):
        return None
    return float(tr.time_s[rows[-1]]), tr.x[rows[-1]], active_tracks.P[rows[-1]]


def target_row(targets, k: int, active_tracks, geometry) -> dict:
    """Row ``k`` of a MirrorTargets table for the console (module doc)."""
    decided = targets.decision[k] == "decided"
    row = {"id": int(targets.target[k]), "track": int(targets.track_id[k]),
           "mirror_track": int(targets.mirror_track_id[k]), "side": str(targets.side[k]) if decided else "undecided",
           "decision": str(targets.decision[k]), "log_lr": _num(targets.log_lr[k]), "tonal_hz": None, "legs": [],
           "reason": None, "bearing_deg": None, "range_m": None, "range_sd_m": None, "course_deg": None,
           "speed_mps": None, "x_m": None, "y_m": None, "ellipse": [], "mirror": None}
    mxy = targets.mirror_xy[k]
    if np.all(np.isfinite(mxy)):
        row["mirror"] = {"x_m": float(mxy[0]), "y_m": float(mxy[1])}
    last = _state(active_tracks, int(targets.track_id[k]))
    if last is None:
        row["reason"] = "only the mirror's track is confirmed"
        return row
    t, x, P = last
    d = x[:2] - geometry.rx_at(t)
    r = float(np.hypot(*d))
    u = d / max(r, 1e-9)
    row.update(bearing_deg=math.degrees(math.atan2(d[0], d[1])) % 360.0, range_m=r,
               range_sd_m=math.sqrt(max(float(u @ P[:2, :2] @ u), 0.0)),
               course_deg=math.degrees(math.atan2(x[2], x[3])) % 360.0, speed_mps=float(np.hypot(x[2], x[3])),
               x_m=float(x[0]), y_m=float(x[1]), ellipse=ellipse_points(x[0], x[1], P[:2, :2]))
    return row


def active_targets_update(t_s: float, ping: int, active_tracks, geometry) -> dict:
    """The targets confirmed at the scan ``t_s`` (either hypothesis's track), one row each (module doc)."""
    from sonartrack.systems.active.targets import mirror_targets

    targets = mirror_targets(active_tracks, geometry)
    rows = [target_row(targets, k, active_tracks, geometry) for k in range(len(targets))
            if targets.last_s[k] >= t_s]
    return {"type": "active_targets", "t_s": float(t_s), "ping": int(ping), "rows": rows}


def active_ownship_update(t_s: float, geometry, ship: tuple[float, float, float] | None, aperture_m: float) -> dict:
    """The ownship (the ship when its fixes are known, else the array centre) and the array's line at ``t_s``."""
    rx, h = geometry.rx_at(t_s), float(geometry.heading_at(t_s))
    x, y, head = ship if ship is not None else (float(rx[0]), float(rx[1]), h)
    half = 0.5 * aperture_m
    dx, dy = half * math.sin(h), half * math.cos(h)
    return {"type": "ownship", "t_s": float(t_s), "x_m": float(x), "y_m": float(y),
            "heading_deg": math.degrees(head) % 360.0, "lat_deg": None, "lon_deg": None, "nav": "ok",
            "array": [[float(rx[0] + dx), float(rx[1] + dy)], [float(rx[0] - dx), float(rx[1] - dy)]]}
