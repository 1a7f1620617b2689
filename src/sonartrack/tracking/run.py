"""Run a tracker over a whole record and return its tracks as typed records of arrays.

* :func:`track_contacts` -- the position tracker (IPDA / IMM-IPDA, paper P4) over contacts: rows
  sharing a time form one scan; one output row per live track per scan (:class:`PositionTracks`).
* :func:`track_peaks` -- the bearing tracker (JPDA / JPDA_A, paper P0) with automatic initiation over
  cross-correlation peaks; one output row per live track per scan (:class:`BearingTracks`).

Inputs are arrays sorted by time (io/contacts.py and io/peaks.py read and check the files). The records
hold arrays only; ``to_frame()`` gives the table ``sonartrack track`` writes (pandas is imported there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.rows import Rows
from sonartrack.tracking.configurations import bearing_tracker, position_tracker
from sonartrack.tracking.measurements import fold_cone_state
from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings

CONTACT_TRACK_COLUMNS = ["time_s", "track_id", "status", "existence", "x_m", "y_m", "vx_mps", "vy_mps", "sd_x_m",
                         "sd_y_m"]
PEAK_TRACK_COLUMNS = ["time_s", "track_id", "bearing_deg", "bearing_rate_deg_s", "bearing_std_deg", "strength",
                      "confirmed"]


@dataclass(frozen=True, slots=True)
class BearingTracks(Rows):
    """Bearing tracks, one row per live track per scan (n rows), in scan order.

    time_s (s), track_id, bearing_deg and bearing_rate_deg_s (the combined estimate, deg and deg/s),
    bearing_std_deg (sqrt of P[0, 0], deg), strength (the track's amplitude strength, paper P0 eq. 9),
    confirmed (bool, M-of-N): equal-length 1-D arrays. ``unfolded_deg``: the tracker's state phi where it runs on
    through endfire (``endfire_fold``; bearing_deg and its rate are then fold(phi), tracking/measurements.py
    :func:`~sonartrack.tracking.measurements.fold_cone_deg`), else None.
    """

    time_s: np.ndarray
    track_id: np.ndarray
    bearing_deg: np.ndarray
    bearing_rate_deg_s: np.ndarray
    bearing_std_deg: np.ndarray
    strength: np.ndarray
    confirmed: np.ndarray
    unfolded_deg: np.ndarray | None = None

    def to_frame(self):
        """The tracks as a table.

        Returns
        -------
        pandas.DataFrame
            Columns PEAK_TRACK_COLUMNS (units in the names), one row per live track per scan.
        """
        import pandas as pd

        return pd.DataFrame({c: getattr(self, c) for c in PEAK_TRACK_COLUMNS})


@dataclass(frozen=True, slots=True)
class PositionTracks(Rows):
    """Position tracks, one row per live track per scan (n rows, r IMM modes), in scan order.

    time_s (s), track_id, confirmed (bool), existence (IPDA probability), x (n, 4) combined state
    [x, y, vx, vy] (m, m/s), sd_x_m and sd_y_m (square roots of P's position diagonal, m) and
    mode_prob (n, r) the IMM mode probabilities.
    """

    time_s: np.ndarray
    track_id: np.ndarray
    confirmed: np.ndarray
    existence: np.ndarray
    x: np.ndarray
    sd_x_m: np.ndarray
    sd_y_m: np.ndarray
    mode_prob: np.ndarray

    def to_frame(self):
        """The tracks as a table.

        Returns
        -------
        pandas.DataFrame
            Columns CONTACT_TRACK_COLUMNS (``status`` is "confirmed" or "tentative") and
            ``mode_prob_<j>`` per IMM mode j, one row per live track per scan.
        """
        import pandas as pd

        x = self.x
        cols = {"time_s": self.time_s, "track_id": self.track_id,
                "status": np.where(self.confirmed, "confirmed", "tentative"), "existence": self.existence,
                "x_m": x[:, 0], "y_m": x[:, 1], "vx_mps": x[:, 2], "vy_mps": x[:, 3],
                "sd_x_m": self.sd_x_m, "sd_y_m": self.sd_y_m}
        cols.update({f"mode_prob_{j}": self.mode_prob[:, j] for j in range(self.mode_prob.shape[1])})
        return pd.DataFrame(cols)


def scan_slices(time_s) -> list[tuple[float, slice]]:
    """The scans of a time-sorted column: the runs of equal times.

    Parameters
    ----------
    time_s : array_like, shape (k,)
        Measurement times (s), not decreasing.

    Returns
    -------
    list of (float, slice)
        Each scan's time (s) and the rows holding it.
    """
    t = np.asarray(time_s, float)
    require(bool(np.all(np.diff(t) >= 0)), "measurement times must not decrease (sort the rows by time)")
    times, starts = np.unique(t, return_index=True)
    bounds = list(starts) + [len(t)]
    return [(float(tk), slice(bounds[i], bounds[i + 1])) for i, tk in enumerate(times)]


def _stack(parts: list[np.ndarray], empty: np.ndarray) -> np.ndarray:
    return np.concatenate(parts) if parts else empty


def track_contacts(time_s, z, R, settings: PositionTrackerSettings | None = None, *,
                   confirmed_only: bool = False) -> PositionTracks:
    """The position tracker (IPDA / IMM-IPDA, paper P4) over a whole record of contacts.

    Parameters
    ----------
    time_s : array_like, shape (k,)
        Contact times (s), not decreasing; equal times form one scan.
    z : array_like, shape (k, 2)
        Contact positions x, y (m).
    R : array_like, shape (k, 2, 2)
        Contact covariances (m^2).
    settings : PositionTrackerSettings, optional
        Tracker settings (default: the paper's).
    confirmed_only : bool
        Keep confirmed tracks only.

    Returns
    -------
    PositionTracks
        One row per live (or confirmed) track per scan.
    """
    s = settings or PositionTrackerSettings()
    trk = position_tracker(s)
    z, R = np.asarray(z, float), np.asarray(R, float)
    cols: dict[str, list] = {k: [] for k in ("time_s", "track_id", "confirmed", "existence", "x", "P", "mu")}
    for t, rows in scan_slices(time_s):
        snap = trk.step(t, z[rows], R[rows])
        keep = snap.confirmed if confirmed_only else np.ones(len(snap.track_id), bool)
        for k, v in (("track_id", snap.track_id), ("confirmed", snap.confirmed), ("existence", snap.existence),
                     ("x", snap.x), ("P", snap.P), ("mu", snap.mu)):
            cols[k].append(v[keep])
        cols["time_s"].append(np.full(int(keep.sum()), t))
    r = len(s.q)
    P = _stack(cols["P"], np.zeros((0, 4, 4)))
    return PositionTracks(_stack(cols["time_s"], np.zeros(0)), _stack(cols["track_id"], np.zeros(0, np.int64)),
                          _stack(cols["confirmed"], np.zeros(0, bool)), _stack(cols["existence"], np.zeros(0)),
                          _stack(cols["x"], np.zeros((0, 4))), np.sqrt(P[:, 0, 0]), np.sqrt(P[:, 1, 1]),
                          _stack(cols["mu"], np.zeros((0, r))))


def track_peaks(time_s, bearing_deg, amplitude, settings: BearingTrackerSettings | None = None, *,
                amplitude_aided: bool = True, nav=None, resolution_deg: float | None = None) -> BearingTracks:
    """The bearing tracker (JPDA_A or JPDA, paper P0) with automatic initiation over a record of peaks.

    Tracks start on strong peaks and are confirmed M-of-N; strengths follow paper P0 eq. 9. With ``nav`` the
    array's heading change between scans is predicted in each track's cone angle, its side a hypothesis
    (tracking/own_motion.py); without, the tracker is paper P0's (the turn left to the process noise).

    Parameters
    ----------
    time_s : array_like, shape (k,)
        Peak times (s), not decreasing; equal times form one scan.
    bearing_deg : array_like, shape (k,)
        Peak bearings (cone angles, deg).
    amplitude : array_like, shape (k,)
        Peak amplitudes (the detection statistic's units).
    settings : BearingTrackerSettings, optional
        Tracker settings (default: the paper's).
    amplitude_aided : bool
        JPDA_A (amplitude ratio in the association) when true, plain JPDA when false.
    nav : Navigation, optional
        The array's heading over the record (io/navigation.py ``array_at``); None: not used.
    resolution_deg : float, optional
        Two confirmed tracks closer than this (deg, about a beamwidth) are updated as one group
        (tracking/resolution.py); None: the settings' ``resolution_deg``.

    Returns
    -------
    BearingTracks
        One row per live track per scan.
    """
    b, a = np.asarray(bearing_deg, float), np.asarray(amplitude, float)
    scans = scan_slices(time_s)
    turn = np.zeros(len(scans))
    if nav is not None and scans:
        turn[1:] = np.diff(np.rad2deg(nav.array_at(np.array([t for t, _ in scans]))[1]))
    trk = PeakTracker(settings, amplitude_aided=amplitude_aided, array_turn=nav is not None,
                      resolution_deg=resolution_deg)
    rows = [trk.step(t, b[r], a[r], dh) for (t, r), dh in zip(scans, turn, strict=True)]
    return trk.tracks(rows)


class PeakTracker:
    """:func:`track_peaks`'s tracker stepped one scan at a time (the live chain steps it as each window's peaks
    arrive, systems/live/; :func:`track_peaks` steps it over a whole record): the same tracker, the same rows.

    Parameters
    ----------
    settings : BearingTrackerSettings, optional
        Tracker settings (default: the paper's).
    amplitude_aided : bool
        JPDA_A when true, plain JPDA when false.
    array_turn : bool
        Predict the array's heading change given to :meth:`step` (tracking/own_motion.py).
    resolution_deg : float, optional
        As :func:`track_peaks`.
    """

    def __init__(self, settings: BearingTrackerSettings | None = None, *, amplitude_aided: bool = True,
                 array_turn: bool = False, resolution_deg: float | None = None):
        self.tracker = bearing_tracker(settings, amplitude_aided=amplitude_aided, adaptive_strength=True,
                                       array_turn=array_turn, resolution_deg=resolution_deg)
        self.fold = settings is not None and settings.endfire_fold

    def step(self, time_s: float, bearing_deg: np.ndarray, amplitude: np.ndarray,
             array_turn_deg: float = 0.0) -> dict[str, np.ndarray]:
        """One scan: the peaks of time ``time_s`` (s) in, one row per live track out.

        Parameters
        ----------
        time_s : float
            The scan's time (s), after the previous scan's.
        bearing_deg, amplitude : ndarray (k,)
            The scan's peaks: cone angles (deg) and amplitudes.
        array_turn_deg : float
            The array's heading change since the previous scan (deg; 0 at the first).

        Returns
        -------
        dict of str to ndarray
            The scan's rows: PEAK_TRACK_COLUMNS and ``unfolded_deg`` (the tracker's phi), one per live track.
        """
        snap = self.tracker.step(time_s, np.asarray(bearing_deg, float), amplitude=np.asarray(amplitude, float),
                                 array_turn_deg=array_turn_deg)
        x = fold_cone_state(snap.x)[0] if self.fold else snap.x
        return {"time_s": np.full(len(snap.x), time_s), "track_id": snap.track_id, "bearing_deg": x[:, 0],
                "bearing_rate_deg_s": x[:, 1], "bearing_std_deg": np.sqrt(snap.P[:, 0, 0]),
                "strength": snap.attrs.get("strength", np.zeros(0)), "confirmed": snap.confirmed,
                "unfolded_deg": snap.x[:, 0]}

    def tracks(self, rows: list[dict[str, np.ndarray]]) -> BearingTracks:
        """The rows of a run of scans (:meth:`step`'s, in scan order) as one record.

        Parameters
        ----------
        rows : list of dict
            The scans' rows.

        Returns
        -------
        BearingTracks
            One row per live track per scan (``unfolded_deg`` when the tracker folds at endfire).
        """
        empty = {"track_id": np.zeros(0, np.int64), "confirmed": np.zeros(0, bool)}
        cols = [_stack([r[c] for r in rows], empty.get(c, np.zeros(0))) for c in PEAK_TRACK_COLUMNS]
        return BearingTracks(*cols, _stack([r["unfolded_deg"] for r in rows], np.zeros(0)) if self.fold else None)
