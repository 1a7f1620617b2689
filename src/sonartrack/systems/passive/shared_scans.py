"""Tracks that hold one ship twice or share its scans: duplicates merged, each shared run given to one track.

Two confirmed tracks on one ship (a track and its mirror image, or a track started again beside itself) agree on
their overlap and are merged (:func:`merge_duplicates`); tracks that share a run of peaks keep it only where they
are resolved (:func:`drop_unresolved`: not within one beam), and a run both claim goes to the one whose history
predicts it (:func:`resolve_shared`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.systems.passive.fragments import _join_statistic, _union, swap_at_crossings
from sonartrack.systems.passive.measurements import TrackMeasurements, _without, within_one_beam


def _overlap_agrees(a: TrackMeasurements, b: TrackMeasurements, max_offset_deg: float, min_scans: int) -> bool:
    common, ia, ib = np.intersect1d(a.track_time_s, b.track_time_s, return_indices=True)
    if len(common) < min_scans:
        return False
    return bool(np.median(np.abs(a.track_cone_deg[ia] - b.track_cone_deg[ib])) <= max_offset_deg)


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


#: two tracks on the very same peaks for at least this long (s) are two tracks on one ship, not two ships in one
#: beam: the peaks go to the track whose earlier history predicts them (:func:`resolve_shared`); shorter shared runs
#: (the merged peak of a crossing) are left out of both
MIN_SHARED_RUN_S = 60.0


def _shared_runs(a: TrackMeasurements, b: TrackMeasurements) -> list[tuple[np.ndarray, np.ndarray]]:
    """Maximal runs of scans at which a and b hold the identical peak: (indices into a, indices into b) per run
    (a run ends where either holds another peak or none; gaps of a few scans where neither has one are bridged)."""
    _, ia, ib = np.intersect1d(a.time_s, b.time_s, return_indices=True)
    same = (a.cone_deg[ia] == b.cone_deg[ib]) & (a.amplitude[ia] == b.amplitude[ib])
    ia, ib = ia[same], ib[same]
    if not len(ia):
        return []
    t = a.time_s[ia]
    # a run breaks where a or b holds a peak of its own in between, or where the gap exceeds 10 s
    own = np.concatenate([a.time_s, b.time_s])
    cuts = [k for k in range(1, len(t)) if t[k] - t[k - 1] > 10.0
            or np.any((own > t[k - 1]) & (own < t[k]))]
    return [(ia[lo:hi], ib[lo:hi]) for lo, hi in zip([0, *cuts], [*cuts, len(t)], strict=True)]


def drop_unresolved(tracks: list[TrackMeasurements], min_separation_deg: float, nav=None
                    ) -> list[TrackMeasurements]:
    """Remove the scans at which two tracks' peaks lie within one beam (:func:`within_one_beam`: closer in
    u = cos(theta) than the broadside beamwidth ``min_separation_deg`` in rad, so within that many degrees at
    broadside and many more near endfire): there the two targets share one beam, each peak is pulled towards the
    other target, and that bias — not noise — would steer a batch TMA fit far off while its covariance stays small.

    With the navigation, two tracks on the identical peak for ``MIN_SHARED_RUN_S`` or longer are not two ships in
    one beam but two tracks on one ship (the tracker's tracks coalesced after a crossing): those scans go to the
    track whose earlier history predicts them (:func:`resolve_shared`) instead of leaving both targets without
    them, and two tracks whose identities the crossing swapped get their parts after it exchanged
    (:func:`swap_at_crossings`).

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The tracks' measurements.
    min_separation_deg : float
        The broadside beamwidth (deg): scans where two tracks' peaks lie within one beam are removed from both.
    nav : Navigation, optional
        The array's position and heading (io/navigation.py); None: only the scans are removed.

    Returns
    -------
    list of TrackMeasurements
        The same tracks without those scans (their filtered track kept whole but where it followed the other
        track's ship), parts exchanged where a crossing swapped them.
    """
    drop = [np.zeros(len(m.time_s), bool) for m in tracks]
    keep = [np.zeros(len(m.time_s), bool) for m in tracks]
    for i, a in enumerate(tracks):
        for j in range(i + 1, len(tracks)):
            b = tracks[j]
            _, ia, ib = np.intersect1d(a.time_s, b.time_s, return_indices=True)
            close = within_one_beam(a.cone_deg[ia], b.cone_deg[ib], min_separation_deg)
            drop[i][ia[close]] = True
            drop[j][ib[close]] = True
            for ra, rb in _shared_runs(a, b) if nav is not None else []:
                if a.time_s[ra[-1]] - a.time_s[ra[0]] >= MIN_SHARED_RUN_S:
                    keep[i][ra] = keep[j][rb] = True
    out = [_without(m, d & ~k) for m, d, k in zip(tracks, drop, keep, strict=True)]
    if nav is None:
        return out
    out = resolve_shared(out, nav)
    return swap_at_crossings(out, nav, min_separation_deg)


def resolve_shared(tracks: list[TrackMeasurements], nav) -> list[TrackMeasurements]:
    """Two tracks on the same ship: each run of identical peaks two tracks hold (kept by :func:`drop_unresolved`)
    goes to the one whose history before the run one constant-velocity target continues best (the lower variance
    ratio of :func:`_join_statistic`: track-to-track association, Bar-Shalom, Willett & Tian 2011, sec. 7.2), and
    is removed from the other, whose record then ends (or resumes) apart from it. This is the track coalescence of
    two trackers' tracks after a crossing (Blackman & Popoli, Design and Analysis of Modern Tracking Systems, 1999,
    ch. 10): the peaks are one ship's, and only one of the two tracks followed that ship before.

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The tracks' measurements (after :func:`drop_unresolved`).
    nav : Navigation
        The array's position and heading (io/navigation.py).

    Returns
    -------
    list of TrackMeasurements
        The same tracks, each shared run held by one of its two tracks.
    """
    out = list(tracks)
    for i in range(len(out)):
        for j in range(i + 1, len(out)):
            while runs := _shared_runs(out[i], out[j]):
                (ra, rb), a, b = runs[0], out[i], out[j]
                run = _without(a, ~np.isin(np.arange(len(a.time_s)), ra))
                before = [_without(m, m.time_s >= run.time_s[0]) for m in (a, b)]
                if _first_predicts(before, run, nav):
                    out[j] = _off_run(b, rb)
                else:
                    out[i] = _off_run(a, ra)
    return out


def _first_predicts(before: list[TrackMeasurements], run: TrackMeasurements, nav) -> bool:
    """Whether the first of two tracks' histories continues into ``run`` at least as well as the second's (the
    variance ratio of :func:`_join_statistic`, the run's own fit made once for both); the longer history where
    neither can be tested (under 10 peaks)."""
    costs: dict = {}
    ratio = [_join_statistic(m, run, nav, costs) if len(m.time_s) >= 10 else np.inf for m in before]
    if not np.isfinite(min(ratio)):
        return len(before[0].time_s) >= len(before[1].time_s)
    return ratio[0] <= ratio[1]


def _off_run(m: TrackMeasurements, run: np.ndarray) -> TrackMeasurements:
    """``m`` without the measurements ``run`` (indices) and without its filtered track over their span: there it
    followed the other track's ship."""
    lo, hi = m.time_s[run[0]], m.time_s[run[-1]]
    rest = _without(m, np.isin(np.arange(len(m.time_s)), run))
    off = (m.track_time_s >= lo) & (m.track_time_s <= hi)
    return replace(rest, track_time_s=m.track_time_s[~off], track_cone_deg=m.track_cone_deg[~off])
