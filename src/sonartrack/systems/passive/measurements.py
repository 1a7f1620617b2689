"""A bearing track's own measurements: the peak of each scan nearest the track (what TMA fits).

The tracker's output bearing is a filtered state, correlated from scan to scan; batch ML (paper P3, eq. 4)
assumes independent bearing errors, so TMA is given the raw peaks instead: at each scan of a confirmed
track, the peak nearest the track's bearing, when within ``max_offset_deg`` of it. The stages on these
measurements: duplicates and shared scans (systems/passive/shared_scans.py), crossings and gaps
(systems/passive/fragments.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.tracking.run import BearingTracks


@dataclass(frozen=True, slots=True)
class TrackMeasurements:
    """Raw cone-angle measurements of one confirmed bearing track."""

    track_id: int
    time_s: np.ndarray
    cone_deg: np.ndarray
    amplitude: np.ndarray
    #: the track's filtered cone angle at every scan it lived (for pictures and the tonal beam)
    track_time_s: np.ndarray
    track_cone_deg: np.ndarray
    #: each measurement's image through the array's axis nearest the tracker's unfolded angle phi (deg; equal to
    #: ``cone_deg`` until the track first passes endfire), or None when the tracker does not unfold
    unfolded_deg: np.ndarray | None = None
    #: ids of the other confirmed tracks joined into this one as fragments of the same target (:func:`join_fragments`)
    joined_track_ids: tuple[int, ...] = ()

    @property
    def duration_s(self) -> float:
        """Time (s) from the first measurement to the last (0 without measurements)."""
        return float(self.time_s[-1] - self.time_s[0]) if len(self.time_s) else 0.0


def confirmed_segments(tracks: BearingTracks, unfolded: bool = False) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Each track from its first confirmed scan on.

    Parameters
    ----------
    tracks : BearingTracks
        The tracker's rows (tracking/run.py), in scan order.
    unfolded : bool
        The tracker's unfolded angles (``tracks.unfolded_deg``) instead of the cone angles.

    Returns
    -------
    dict
        track id -> (times (s), cone angles (deg)) of every track that was ever confirmed, in increasing id.
    """
    tid = np.asarray(tracks.track_id)
    if tid.size == 0:
        return {}
    order = np.argsort(tid, kind="stable")  # stable: each track's rows stay in scan order
    ids, starts = np.unique(tid[order], return_index=True)
    angle = tracks.unfolded_deg if unfolded else tracks.bearing_deg
    t, cone, conf = (np.asarray(a)[order] for a in (tracks.time_s, angle, tracks.confirmed))
    out = {}
    for i, rows in zip(ids, np.split(np.arange(len(order)), starts[1:]), strict=True):
        c = conf[rows].astype(bool)
        if c.any():
            first = rows[int(np.argmax(c))]
            out[int(i)] = (t[first:rows[-1] + 1].astype(float), cone[first:rows[-1] + 1].astype(float))
    return out


def nearest_peaks(track_time_s, track_cone_deg, peak_time_s, peak_cone_deg, max_offset_deg: float) -> np.ndarray:
    """The peak nearest the track at each of its times.

    Parameters
    ----------
    track_time_s, track_cone_deg : ndarray (n,)
        The track's times (s) and cone angles (deg).
    peak_time_s, peak_cone_deg : ndarray (k,)
        The peaks' times (s, sorted) and cone angles (deg).
    max_offset_deg : float
        Largest offset of a track's peak from the track (deg).

    Returns
    -------
    ndarray (n,) of int
        Index into the peaks at each track time, -1 where no peak of that time lies within ``max_offset_deg``.
    """
    lo = np.searchsorted(peak_time_s, track_time_s, side="left")
    hi = np.searchsorted(peak_time_s, track_time_s, side="right")
    idx = np.full(len(track_time_s), -1, np.int64)
    for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
        if b > a:
            j = a + int(np.argmin(np.abs(peak_cone_deg[a:b] - track_cone_deg[i])))
            if abs(peak_cone_deg[j] - track_cone_deg[i]) <= max_offset_deg:
                idx[i] = j
    return idx


def track_measurements(tracks: BearingTracks, peaks, max_offset_deg: float) -> list[TrackMeasurements]:
    """The raw peaks of every confirmed track.

    Parameters
    ----------
    tracks : BearingTracks
        The tracker's rows (tracking/run.py).
    peaks : PeakRecord
        The peaks the tracks were formed from (acoustics/xcorr_bearing.py), sorted by time.
    max_offset_deg : float
        A peak is a track's measurement when within this of the track's cone angle (deg).

    Returns
    -------
    list of TrackMeasurements
        One per confirmed track, in increasing track id.
    """
    pt, pb, pa = (np.asarray(a, float) for a in (peaks.time_s, peaks.bearing_deg, peaks.amplitude))
    unfolded = confirmed_segments(tracks, unfolded=True) if tracks.unfolded_deg is not None else {}
    out = []
    for tid, (t, cone) in confirmed_segments(tracks).items():
        j = nearest_peaks(t, cone, pt, pb, max_offset_deg)
        hit = j >= 0
        phi = unfolded_image(pb[j[hit]], unfolded[tid][1][hit]) if tid in unfolded else None
        out.append(TrackMeasurements(tid, t[hit], pb[j[hit]], pa[j[hit]], t, cone, phi))
    return out


def unfolded_image(cone_deg, phi_deg) -> np.ndarray:
    """The image of each cone angle theta (deg, 0..180) nearest the unfolded angle phi (deg): among theta + 360 m
    and -theta + 360 m (the fold's preimages, tracking/measurements.py ``fold_cone_deg``), the closest to phi.

    Parameters
    ----------
    cone_deg : ndarray (n,)
        Measured cone angles (deg).
    phi_deg : ndarray (n,)
        The track's unfolded angles at the same times (deg).

    Returns
    -------
    ndarray (n,)
        The unfolded measurements (deg).
    """
    theta, phi = np.asarray(cone_deg, float), np.asarray(phi_deg, float)
    up = theta + 360.0 * np.round((phi - theta) / 360.0)
    down = -theta + 360.0 * np.round((phi + theta) / 360.0)
    return np.where(np.abs(up - phi) <= np.abs(down - phi), up, down)


def within_one_beam(cone_a_deg, cone_b_deg, beamwidth_deg: float) -> np.ndarray:
    """Whether two cone angles lie within one beam of a line array: |cos(a) - cos(b)| < the broadside beamwidth in
    rad. A line array's beam has one width in the direction cosine u = cos(theta) at every steering angle (about
    lambda / L; Van Trees, Optimum Array Processing, 2002, sec. 2.4), so in cone angle it widens as 1 / sin(theta)
    towards endfire: 10 and 13 deg share a 2 deg beam (du = 0.010 < 0.035), 88 and 91 deg do not (du = 0.052).
    u is the same for every image of a cone angle through the axis (cos(-theta) = cos(theta)), so folded and
    unfolded angles compare alike.

    Parameters
    ----------
    cone_a_deg, cone_b_deg : array_like
        Cone angles (deg), broadcast together.
    beamwidth_deg : float
        The array's broadside beamwidth (deg).

    Returns
    -------
    ndarray of bool
        True where the two are within one beam.
    """
    du = np.abs(np.cos(np.deg2rad(np.asarray(cone_a_deg, float))) - np.cos(np.deg2rad(np.asarray(cone_b_deg, float))))
    return du < np.deg2rad(beamwidth_deg)


def _without(m: TrackMeasurements, drop: np.ndarray) -> TrackMeasurements:
    return TrackMeasurements(m.track_id, m.time_s[~drop], m.cone_deg[~drop], m.amplitude[~drop], m.track_time_s,
                             m.track_cone_deg, None if m.unfolded_deg is None else m.unfolded_deg[~drop],
                             m.joined_track_ids)


_LATER_STAGES = {"merge_duplicates": "shared_scans", "drop_unresolved": "shared_scans",
                 "resolve_shared": "shared_scans", "join_fragments": "fragments", "joined_tonal": "fragments",
                 "swap_at_crossings": "fragments", "tonals_agree": "fragments"}


def __getattr__(name: str):
    """The later stages on these measurements, now in systems/passive/shared_scans.py and fragments.py, still
    importable from here (lazily: those modules import this one)."""
    if name in _LATER_STAGES:
        import importlib

        return getattr(importlib.import_module(f"sonartrack.systems.passive.{_LATER_STAGES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
