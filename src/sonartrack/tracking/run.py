"""Run a tracker over a whole record and return its tracks as a table (what ``sonartrack track`` writes).

* :func:`track_contacts` -- the position tracker (IPDA / IMM-IPDA, paper P4) over contacts: rows
  sharing a time form one scan; one output row per live track per scan.
* :func:`track_peaks` -- the bearing tracker (JPDA / JPDA_A, paper P0) with automatic initiation over
  cross-correlation peaks; one output row per live track per scan.

Inputs are arrays sorted by time (io/contacts.py and io/peaks.py read and check the files).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require
from sonartrack.tracking.configurations import bearing_tracker, position_tracker
from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings

CONTACT_TRACK_COLUMNS = ["time_s", "track_id", "status", "existence", "x_m", "y_m", "vx_mps", "vy_mps", "sd_x_m",
                         "sd_y_m"]
PEAK_TRACK_COLUMNS = ["time_s", "track_id", "bearing_deg", "bearing_rate_deg_s", "bearing_std_deg", "strength",
                      "confirmed"]


def scan_slices(time_s) -> list[tuple[float, slice]]:
    """(time, rows) of each scan: the runs of equal times of a time-sorted column."""
    t = np.asarray(time_s, float)
    require(bool(np.all(np.diff(t) >= 0)), "measurement times must not decrease (sort the rows by time)")
    times, starts = np.unique(t, return_index=True)
    bounds = list(starts) + [len(t)]
    return [(float(tk), slice(bounds[i], bounds[i + 1])) for i, tk in enumerate(times)]


def _table(parts: list[dict], columns: list[str]):
    import pandas as pd

    if not parts:
        return pd.DataFrame(columns=columns)
    return pd.DataFrame({c: np.concatenate([p[c] for p in parts]) for c in columns})


def track_contacts(time_s, z, R, settings: PositionTrackerSettings | None = None, *, confirmed_only: bool = False):
    """Tracks of position contacts ``z (k, 2)`` (m) with covariances ``R (k, 2, 2)`` at ``time_s (k,)``.

    Returns a DataFrame with CONTACT_TRACK_COLUMNS and ``mode_prob_<r>`` per IMM mode."""
    s = settings or PositionTrackerSettings()
    trk = position_tracker(s)
    z, R = np.asarray(z, float), np.asarray(R, float)
    modes = [f"mode_prob_{j}" for j in range(len(s.q))]
    parts = []
    for t, rows in scan_slices(time_s):
        snap = trk.step(t, z[rows], R[rows])
        keep = snap.confirmed if confirmed_only else np.ones(len(snap.track_id), bool)
        x, P = snap.x[keep], snap.P[keep]
        part = {"time_s": np.full(len(x), t), "track_id": snap.track_id[keep],
                "status": np.where(snap.confirmed[keep], "confirmed", "tentative"), "existence": snap.existence[keep],
                "x_m": x[:, 0], "y_m": x[:, 1], "vx_mps": x[:, 2], "vy_mps": x[:, 3],
                "sd_x_m": np.sqrt(P[:, 0, 0]), "sd_y_m": np.sqrt(P[:, 1, 1])}
        part.update({name: snap.mu[keep, j] for j, name in enumerate(modes)})
        parts.append(part)
    return _table(parts, CONTACT_TRACK_COLUMNS + modes)


def track_peaks(time_s, bearing_deg, amplitude, settings: BearingTrackerSettings | None = None, *,
                amplitude_aided: bool = True):
    """Bearing tracks of peaks (cone angles, deg, with amplitudes) at ``time_s``: JPDA_A with eq. 9 strengths
    (``amplitude_aided``) or JPDA; tracks start on strong peaks and are confirmed M-of-N.

    Returns a DataFrame with PEAK_TRACK_COLUMNS."""
    trk = bearing_tracker(settings, amplitude_aided=amplitude_aided, adaptive_strength=True)
    b, a = np.asarray(bearing_deg, float), np.asarray(amplitude, float)
    parts = []
    for t, rows in scan_slices(time_s):
        snap = trk.step(t, b[rows], amplitude=a[rows])
        parts.append({"time_s": np.full(len(snap.x), t), "track_id": snap.track_id, "bearing_deg": snap.x[:, 0],
                      "bearing_rate_deg_s": snap.x[:, 1], "bearing_std_deg": np.sqrt(snap.P[:, 0, 0]),
                      "strength": snap.attrs.get("strength", np.zeros(0)), "confirmed": snap.confirmed})
    return _table(parts, PEAK_TRACK_COLUMNS)
