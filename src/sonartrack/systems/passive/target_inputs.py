"""What a target's solutions are made from: the scans kept (another track's beam left out,
:func:`without_neighbour_scans`), the time the side was first resolved (:func:`side_resolved_time`) and the tonal
line when it is usable (:func:`usable_tonal`, :func:`line_tonal`, :func:`frequency_record`) (moved out of
systems/passive/targets.py, which solves each target from them).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveStages
from sonartrack.tma.record_verdict import (  # the checks shared with ``sonartrack tma``; re-exported for the chain
    UNSUPPORTED_RANGE,  # noqa: F401
    )
from sonartrack.tma.records import BearingRecord
from sonartrack.tma.sides import (
    SideDecision,
    resolve_side,
)

#: interval at which the side decision is re-taken on the growing record
SIDE_CHECK_S = 60.0



def side_resolved_time(t, cone_rad, heading_rad, xy, final: SideDecision, min_log_lr: float) -> float:
    """First checkpoint from which every later decision on the growing record agrees with ``final``.

    Parameters
    ----------
    t, cone_rad, heading_rad : ndarray (n,)
        The track's times (s), cone angles (rad) and the array's heading (rad) at those times.
    xy : ndarray (n, 2)
        The array centre (m).
    final : SideDecision
        The decision on the whole record.
    min_log_lr : float
        The decision threshold on |ln LR|.

    Returns
    -------
    float
        The time (s), checked every ``SIDE_CHECK_S``; NaN when the side was never resolved.
    """
    if final.side == "unresolved":
        return float("nan")
    checkpoints = np.arange(t[0] + SIDE_CHECK_S, t[-1], SIDE_CHECK_S)
    since = float(t[-1])
    for c in checkpoints[::-1]:
        n = int(np.searchsorted(t, c, side="right"))
        d = resolve_side(t[:n], cone_rad[:n], heading_rad[:n], xy[:n], min_log_lr=min_log_lr,
                         unfolded=final.unfolded_rad is not None)
        if d.side != final.side:
            break
        since = float(c)
    return since


def frequency_record(t, bearing_rad, tonal: TonalTrack) -> BearingRecord:
    """Bearings with the tonal's frequency at the same times.

    Parameters
    ----------
    t, bearing_rad : ndarray (n,)
        The bearings' times (s) and true bearings (rad).
    tonal : TonalTrack
        The track's tonal line.

    Returns
    -------
    BearingRecord
        The times that have both a bearing and a tonal frequency (Hz).
    """
    f = np.interp(t, tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
    on = np.isin(t, tonal.time_s)
    f = np.where(on, f, np.nan)
    keep = np.isfinite(f)
    return BearingRecord(time_s=t[keep], bearing_rad=bearing_rad[keep], frequency_hz=f[keep])


def usable_tonal(tonal: TonalTrack | None, stages: PassiveStages) -> TonalTrack | None:
    """The tonal if it is clean enough for bearing + frequency TMA.

    Parameters
    ----------
    tonal : TonalTrack or None
        The track's tonal line.
    stages : PassiveStages
        Its settings' ``max_sigma_freq_hz`` and ``tma_min_tonal_snr_db``.

    Returns
    -------
    TonalTrack or None
        ``tonal``, or None when it is too noisy or too weak (the record is then bearings only).
    """
    s = stages.settings
    if tonal is None or tonal.sigma_hz > s.max_sigma_freq_hz or tonal.line_snr_db < s.tma_min_tonal_snr_db:
        return None
    return tonal


def line_tonal(tonal: TonalTrack | None, stages: PassiveStages) -> TonalTrack | None:
    """The tonal of a target found through its line (a narrowband target) if its frequency is clean enough for the
    bearings + frequency ML.

    Only the frequency noise gate of :func:`usable_tonal` (``max_sigma_freq_hz``) applies: its line-strength gate
    (``tma_min_tonal_snr_db``) keeps a broadband track from taking a weak line that may be another source's, but a
    narrowband target's bearings are its line's own, and a quiet target's line is weak by nature (the default
    scene's submarine: 3 dB over its beam's background).

    Parameters
    ----------
    tonal : TonalTrack or None
        The target's line.
    stages : PassiveStages
        Its settings' ``max_sigma_freq_hz``.

    Returns
    -------
    TonalTrack or None
        ``tonal``, or None when there is none or its frequency noise exceeds the gate.
    """
    if tonal is None or tonal.sigma_hz > stages.settings.max_sigma_freq_hz:
        return None
    return tonal


def without_neighbour_scans(m: TrackMeasurements, neighbours, min_separation_deg: float
                            ) -> tuple[TrackMeasurements, str | None]:
    """The track's measurements without the scans at which another track lies within ``min_separation_deg``.

    Where two ships share a beam each one's peak is pulled towards the other (by up to a degree near a crossing):
    a bias, not noise, which the white-noise ML would take as information. The other tracks' filtered cone
    angles (``track_cone_deg``, at every scan they lived, also where they had no peak) are compared with this
    track's measured cone angles; those scans are left out when at least 10 scans remain.

    Parameters
    ----------
    m : TrackMeasurements
        The track's raw peaks.
    neighbours : sequence of TrackMeasurements
        The other confirmed tracks (this one, by its track id, is skipped).
    min_separation_deg : float
        About a beamwidth (deg).

    Returns
    -------
    TrackMeasurements
        ``m`` without those scans (its filtered track kept whole).
    str or None
        What was left out, or None when nothing was.
    """
    t = np.asarray(m.time_s, float)
    close = np.zeros(len(t), bool)
    ids = []
    for other in neighbours:
        if other.track_id == m.track_id or len(other.track_time_s) == 0:
            continue
        tt = np.asarray(other.track_time_s, float)
        alive = (t >= tt[0]) & (t <= tt[-1])
        near = alive & (np.abs(np.interp(t, tt, np.asarray(other.track_cone_deg, float)) - m.cone_deg)
                        < min_separation_deg)
        if near.any():
            close |= near
            ids.append(other.track_id)
    if not close.any() or int((~close).sum()) < 10:
        return m, None
    keep = ~close
    reduced = replace(m, time_s=m.time_s[keep], cone_deg=m.cone_deg[keep], amplitude=m.amplitude[keep],
                      unfolded_deg=None if m.unfolded_deg is None else m.unfolded_deg[keep])
    return reduced, (f"{int(close.sum())} scan(s) left out of the TMA: track(s) {', '.join(map(str, ids))} within "
                     f"{min_separation_deg:.2g} deg (one beam)")
