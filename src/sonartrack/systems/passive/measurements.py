"""A bearing track's own measurements: the peak of each scan nearest the track (what TMA fits).

The tracker's output bearing is a filtered state, correlated from scan to scan; batch ML (paper P3, eq. 4)
assumes independent bearing errors, so TMA is given the raw peaks instead: at each scan of a confirmed
track, the peak nearest the track's bearing, when within ``max_offset_deg`` of it.
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

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0]) if len(self.time_s) else 0.0


def confirmed_segments(tracks: BearingTracks) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Each track from its first confirmed scan on.

    Parameters
    ----------
    tracks : BearingTracks
        The tracker's rows (tracking/run.py), in scan order.

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
    t, cone, conf = (np.asarray(a)[order] for a in (tracks.time_s, tracks.bearing_deg, tracks.confirmed))
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
    out = []
    for tid, (t, cone) in confirmed_segments(tracks).items():
        j = nearest_peaks(t, cone, pt, pb, max_offset_deg)
        hit = j >= 0
        out.append(TrackMeasurements(tid, t[hit], pb[j[hit]], pa[j[hit]], t, cone))
    return out


def _overlap_agrees(a: TrackMeasurements, b: TrackMeasurements, max_offset_deg: float, min_scans: int) -> bool:
    common, ia, ib = np.intersect1d(a.track_time_s, b.track_time_s, return_indices=True)
    if len(common) < min_scans:
        return False
    return bool(np.median(np.abs(a.track_cone_deg[ia] - b.track_cone_deg[ib])) <= max_offset_deg)


def _union(a: TrackMeasurements, b: TrackMeasurements) -> TrackMeasurements:
    """``a`` extended by ``b``'s scans that ``a`` lacks (``a``'s values where both have one)."""
    def join(ta, xa, tb, xb):
        extra = ~np.isin(tb, ta)
        t = np.concatenate([ta, tb[extra]])
        order = np.argsort(t, kind="stable")
        return t[order], [np.concatenate([u, v[extra]])[order] for u, v in zip(xa, xb, strict=True)]

    t, (cone, amp) = join(a.time_s, (a.cone_deg, a.amplitude), b.time_s, (b.cone_deg, b.amplitude))
    tt, (tc,) = join(a.track_time_s, (a.track_cone_deg,), b.track_time_s, (b.track_cone_deg,))
    return TrackMeasurements(a.track_id, t, cone, amp, tt, tc)


def merge_duplicates(tracks: list[TrackMeasurements], max_offset_deg: float,
                     min_scans: int = 5) -> list[TrackMeasurements]:
    """Join confirmed tracks that follow the same target: when a later track runs within ``max_offset_deg`` of an
    earlier one (median over at least ``min_scans`` common scans), it is a second track on the same peaks (JPDA
    lets two tracks share them, e.g. when a fast cone-angle change during the array's turn outruns one and a new
    one starts), and its scans extend the earlier track instead of making a second target.

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The confirmed tracks' measurements.
    max_offset_deg : float
        Largest median offset (deg) of two tracks on the same peaks.
    min_scans : int
        Fewest common scans for the comparison.

    Returns
    -------
    list of TrackMeasurements
        The tracks, duplicates joined into the earlier one, in order of first scan.
    """
    out: list[TrackMeasurements] = []
    for m in sorted(tracks, key=lambda m: (m.track_time_s[0], m.track_id)):
        for i, kept in enumerate(out):
            if _overlap_agrees(kept, m, max_offset_deg, min_scans):
                out[i] = _union(kept, m)
                break
        else:
            out.append(m)
    return out


def drop_unresolved(tracks: list[TrackMeasurements], min_separation_deg: float) -> list[TrackMeasurements]:
    """Remove the scans at which two tracks' peaks lie closer than ``min_separation_deg`` (about a beamwidth):
    there the two targets share one beam, each peak is pulled towards the other target, and that bias — not
    noise — would steer a batch TMA fit far off while its covariance stays small.

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The tracks' measurements.
    min_separation_deg : float
        Scans where two tracks' peaks lie closer than this (deg) are removed from both.

    Returns
    -------
    list of TrackMeasurements
        The same tracks without those scans (their filtered track kept whole).
    """
    drop = [np.zeros(len(m.time_s), bool) for m in tracks]
    for i, a in enumerate(tracks):
        for j in range(i + 1, len(tracks)):
            b = tracks[j]
            _, ia, ib = np.intersect1d(a.time_s, b.time_s, return_indices=True)
            close = np.abs(a.cone_deg[ia] - b.cone_deg[ib]) < min_separation_deg
            drop[i][ia[close]] = True
            drop[j][ib[close]] = True
    return [TrackMeasurements(m.track_id, m.time_s[~d], m.cone_deg[~d], m.amplitude[~d], m.track_time_s,
                              m.track_cone_deg) for m, d in zip(tracks, drop, strict=True)]
