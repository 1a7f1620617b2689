"""The passive sonar chain: an array recording and its navigation in, target tracks and solutions out.

Stages (each a library function of its own; this module only joins them), with their settings built once
from the system's one settings tree (:meth:`~sonartrack.systems.passive.settings.PassiveSettings.stages`):

1. front end (acoustics/beamforming.py :func:`bearing_time_record`): per window, beam powers over cone angle,
   normalised against the background across bearing, peaks above the threshold -> bearing-time record and
   peaks;
2. bearing tracking (tracking/run.py :func:`track_peaks`): JPDA_A on the peaks (paper P0), tracks started
   on strong peaks and confirmed M-of-N, dropped after a run of empty gates -> :class:`BearingTracks`;
3. each confirmed track's raw peaks (systems/passive/measurements.py; two tracks on the same peaks joined,
   scans where two targets share a beam left out, fragments of one target -- a track that broke at a crossing
   or a turn -- joined when one constant-velocity target explains them and their tonal lines agree) with, from a
   second pass over the recording before the join, each fragment's tonal line on its own beam
   (systems/passive/tonal_pass.py; a joined target's line is its fragments');
4. narrowband (``[narrowband]``, on by default; systems/passive/narrowband.py): the LOFAR gram per beam (from the
   front end's own pass, acoustics/beamforming.py; else one more pass), its lines tracked in frequency and bearing and
   grouped into sources; a source that follows a track gives it its tonal where its own beam showed none, a
   source that no track explains becomes a narrowband target (the quiet ship with a tonal);
5. per target: the array side from the two mirror hypotheses, batch ML and IMM-MGEKF TMA
   (systems/passive/targets.py), the same for bearing tracks and narrowband sources.

Option, off by default: ``[btr_mftd]`` runs paper P1's MFTD over the bearing-time record between 1 and 2 and adds
its detections that no peak lies near to the tracker's peaks (detection/btr_mftd.py).

The recording arrives as blocks of ``window_s`` (``blocks()`` is called once per pass, and must give the
same blocks each time), so memory does not grow with the recording's length.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.beamforming import BearingTimeRecord, RecordBuilder
from sonartrack.acoustics.lofar import LofarGram
from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.detection.btr_mftd import BtrDetections
from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.measurements import (
    TrackMeasurements,
    drop_unresolved,
    join_fragments,
    joined_tonal,
    merge_duplicates,
    track_measurements,
)
from sonartrack.systems.passive.narrowband import NarrowbandLines
from sonartrack.systems.passive.settings import PassiveSettings, PassiveStages
from sonartrack.systems.passive.targets import UNSUPPORTED_RANGE, Target, solve_target
from sonartrack.systems.passive.tonal_pass import SpectraSpill, measure_tonals
from sonartrack.tracking.line_tracks import LineSource, LineTrack
from sonartrack.tracking.run import BearingTracks, track_peaks


@dataclass(frozen=True, slots=True)
class PassiveResult:
    """Everything the chain produced (the faces write and draw it).

    ``record``: the bearing-time record and its peaks; ``tracks``: the tracker's rows; ``targets``: one per
    confirmed track long enough for TMA, then one per narrowband target; ``short_tracks``: ids of the confirmed
    tracks too short for TMA; ``duration_s``: the recording processed (s); ``stages``: the settings as run
    (``stages.settings`` the tree); ``nav``: the navigation; ``plain_jpda_tracks``: the same peaks tracked with
    plain JPDA, when asked for; ``warnings``: one line per warning about the inputs (the faces print them)."""

    record: BearingTimeRecord
    tracks: BearingTracks
    targets: list[Target]
    short_tracks: list[int]
    duration_s: float
    stages: PassiveStages
    nav: Navigation
    plain_jpda_tracks: BearingTracks | None = None
    #: warning lines about the inputs (systems/passive/checks.py, io/navigation.py): the run went on, with care
    warnings: tuple[str, ...] = ()
    #: the bearing-time MFTD's detections (``[btr_mftd] enabled``), before they join the peaks
    mftd_detections: BtrDetections | None = None
    #: narrowband line tracks and the sources they group into (``[narrowband] enabled``)
    line_tracks: tuple[LineTrack, ...] = ()
    line_sources: tuple[LineSource, ...] = ()
    #: the targets found by their lines alone (ids into ``targets``); None when the narrowband pass did not run
    narrowband_target_ids: tuple[int, ...] | None = None
    #: the LOFAR gram the lines came from (None: the narrowband pass did not run or the recording is too short)
    lofar: LofarGram | None = None
    #: line source id -> the target it feeds or became (a source that is neither is absent)
    source_targets: dict[int, int] | None = None

    @property
    def settings(self) -> PassiveSettings:
        """The settings tree as run."""
        return self.stages.settings


class _Stage:
    """``progress`` hooks (start(label, total, done), advance(n)) around one pass, or nothing."""

    def __init__(self, progress, label: str, total: int):
        self.progress = progress
        if progress is not None:
            progress.start(label, total, 0)

    def __call__(self, _k: int) -> None:
        if self.progress is not None:
            self.progress.advance(1)


def run_passive(blocks: Callable[[], Iterable[np.ndarray]], n_windows: int, nav: Navigation, stages: PassiveStages,
                *, progress=None, plain_jpda: bool = False) -> PassiveResult:
    """Run the chain over a recording (module docstring).

    Parameters
    ----------
    blocks : callable
        Returns an iterable of the recording's windows, (elements, window_s fs) each; called once per pass.
    n_windows : int
        Number of windows to process.
    nav : Navigation
        The ownship and array over the recording (io/navigation.py).
    stages : PassiveStages
        The chain's settings, built for this recording (:meth:`PassiveSettings.stages`).
    progress : object, optional
        ``start(label, total, done)`` and ``advance(n)`` hooks (the command line's progress bar).
    plain_jpda : bool
        Also track the same peaks with plain JPDA (no amplitude), for comparison with JPDA_A; the result's
        ``plain_jpda_tracks``.

    Returns
    -------
    PassiveResult
        The record, the tracks and the targets.
    """
    s, settings = stages, stages.settings
    # the tonal band's spectra kept from the front end's transforms (systems/passive/tonal_pass.py SpectraSpill)
    spill = SpectraSpill(int(round(settings.window_s * s.fs_hz)), s.fs_hz, s.tonal)
    core = PassiveCore(s, spill)
    rows = RecordBuilder(s.front_end, _Stage(progress, "beamforming", n_windows))
    scans = []
    for row in core.front.windows(blocks()):
        t = (rows.k + 0.5) * settings.window_s
        rows.add(*row)
        if not settings.btr_mftd.enabled:  # with the MFTD the tracker waits for its detections (below)
            scans += core.scan(t, row[1], row[2], nav)
    btr = rows.record(core.gram())
    pk, mftd = btr.peaks, None
    if settings.btr_mftd.enabled:
        pk, mftd = _with_mftd_peaks(btr, s)
    # the array's turns predicted from the navigation, and two ships within a beam seen as one merged peak
    # (tracking/own_motion.py, tracking/resolution.py): identities kept through crossings and turns
    tracks = track_peaks(pk.time_s, pk.bearing_deg, pk.amplitude, s.tracker, nav=nav,
                         resolution_deg=s.min_separation_deg) if mftd is not None else core.tracker.tracks(scans)
    tonal = spill.windows if spill.usable(n_windows) else blocks
    try:
        return finish_passive(btr, tracks, nav, s, n_windows, tonal, blocks=blocks, progress=progress,
                              plain_jpda=plain_jpda, mftd=(pk, mftd) if mftd is not None else None)
    finally:
        spill.close()


class PassiveCore:
    """The chain's windowed part: each window's front end (stage 1, with the LOFAR accumulator and the tonal
    spill fed from its transforms) and the tracker's scan on its peaks (stage 2). :func:`run_passive` drives it over
    a recording, the live chain (systems/live/) over a stream's windows as they complete: one core, so the two give
    the same tracks (to the rounding of the front end's batched products, ~1e-13 deg).

    Parameters
    ----------
    stages : PassiveStages
        The chain's settings.
    spill : SpectraSpill or None
        Where the front end hands the tonal band's spectra (systems/passive/tonal_pass.py), or None.
    """

    def __init__(self, stages: PassiveStages, spill=None):
        from sonartrack.acoustics.beamforming import FrontEnd
        from sonartrack.tracking.run import PeakTracker

        s, settings = stages, stages.settings
        self.stages = s
        self.front = FrontEnd(s.fs_hz, s.array, s.front_end, band=s.band, mvdr=settings.mvdr,
                              narrowband=settings.narrowband if settings.narrowband.enabled else None,
                              spectra_sink=spill if spill is not None and spill.bins is not None else None)
        self.tracker = PeakTracker(s.tracker, array_turn=True, resolution_deg=s.min_separation_deg)
        #: the array's heading (deg) at the last scan (None before the first)
        self.heading_deg: float | None = None

    def scan(self, time_s: float, angle_deg: np.ndarray, height: np.ndarray, nav) -> list[dict]:
        """The tracker's scan on one window's peaks (none: a window without peaks is no scan, as
        :func:`~sonartrack.tracking.run.track_peaks` has it): [its rows] or [].

        Parameters
        ----------
        time_s : float
            The window's centre (s).
        angle_deg, height : ndarray
            Its peaks.
        nav : Navigation or float
            The navigation (the array's heading is read at ``time_s``), or that heading itself (deg).
        """
        if not len(angle_deg):
            return []
        h = float(nav) if isinstance(nav, float | int) else float(np.rad2deg(nav.array_at(np.array([time_s]))[1])[0])
        turn = 0.0 if self.heading_deg is None else h - self.heading_deg
        self.heading_deg = h
        return [self.tracker.step(time_s, angle_deg, height, turn)]

    def gram(self) -> LofarGram | None:
        """The LOFAR gram of the complete integration periods so far (None: none, or no narrowband)."""
        return None if self.front.lofar is None else self.front.lofar.gram(self.stages.settings.window_s)


def finish_passive(btr: BearingTimeRecord, tracks: BearingTracks, nav: Navigation, stages: PassiveStages,
                   n_windows: int, tonal_windows: Callable[[], Iterable], *, first_window: int = 0, blocks=None,
                   progress=None, plain_jpda: bool = False, mftd=None) -> PassiveResult:
    """Stages 3-5 on the windowed part's record and tracks (module doc): measurements, tonal lines, joins,
    narrowband lines and sources, side and TMA per target.

    Parameters
    ----------
    btr : BearingTimeRecord
        The record (its peaks and LOFAR gram) of windows ``first_window`` on.
    tracks : BearingTracks
        The tracker's rows.
    nav : Navigation
        The navigation.
    stages : PassiveStages
        The settings.
    n_windows : int
        Windows processed since the first (the duration is n_windows window_s).
    tonal_windows : callable
        Returns the windows (or their spectra, SpectraSpill.windows) from ``first_window`` on, for the tonal pass.
    first_window : int
        The index of the first window the record, the gram and ``tonal_windows`` hold (the live chain keeps a
        bounded history).
    blocks : callable, optional
        The recording's windows, for a narrowband pass of its own when the front end made no gram.
    progress, plain_jpda
        As :func:`run_passive`.
    mftd : (PeakRecord, BtrDetections), optional
        The peaks with the bearing-time MFTD's detections, and those detections.
    """
    s, settings = stages, stages.settings
    pk = btr.peaks if mftd is None else mftd[0]
    meas = merge_duplicates(track_measurements(tracks, pk, settings.max_peak_offset_deg), settings.max_peak_offset_deg)
    meas = drop_unresolved(meas, s.min_separation_deg, nav=nav)
    # the tonal pass runs on the fragments, so that their lines take part in the join (two ships' fragments
    # with lines apart are not joined); a joined target's line is its fragments' lines
    tonal_of = _fragment_tonals(tonal_windows, [m for m in meas if _long_enough(m, settings)], s,
                                n_windows - first_window, progress, first_window)
    meas = join_fragments(meas, nav, min_fragment_s=settings.min_track_s, tonals=tonal_of)
    long_enough = [m for m in meas if _long_enough(m, settings)]
    short = [m.track_id for m in meas if m not in long_enough]
    tonals = [joined_tonal(m, tonal_of) if m.joined_track_ids else tonal_of.get(m.track_id) for m in long_enough]
    nb = _narrowband(blocks, btr, s, n_windows, progress) if settings.narrowband.enabled else None
    records, nb_records, roles = _with_lines(nb, long_enough, tonals, nav, s)
    targets = [solve_target(i + 1, m, tonal, nav, s, neighbours=meas, use_frequency_ml=i >= len(records))
               for i, (m, tonal) in enumerate(records + nb_records)]
    jpda = track_peaks(pk.time_s, pk.bearing_deg, pk.amplitude, s.tracker, amplitude_aided=False) if plain_jpda \
        else None
    notes = tuple(f"warning: target {tg.target_id}: {w}" for tg in targets for w in tg.ml.warnings
                  if w.startswith(UNSUPPORTED_RANGE))
    result = PassiveResult(btr, tracks, targets, short, n_windows * settings.window_s, s, nav, jpda, notes,
                           None if mftd is None else mftd[1])
    return result if nb is None else _with_narrowband(result, nb, roles, len(records))


def _long_enough(m: TrackMeasurements, settings: PassiveSettings) -> bool:
    """A track (or fragment) long enough for TMA: ``min_track_s`` and at least 10 scans (the only fragments
    :func:`join_fragments` may join, as it asks both to span ``min_track_s``)."""
    return m.duration_s >= settings.min_track_s and len(m.time_s) >= 10


def _fragment_tonals(blocks, frags: list[TrackMeasurements], s: PassiveStages, n_windows: int,
                     progress, first_window: int = 0) -> dict:
    """track id -> its tonal line on its own beam (systems/passive/tonal_pass.py, one pass over the recording)
    or None; no pass when there is no fragment."""
    if not frags:
        return {}
    tonals = measure_tonals(blocks(), s.fs_hz, s.array, frags, s.tonal, n_windows,
                            progress=_Stage(progress, "tonal lines", n_windows), first_window=first_window)
    return {m.track_id: t for m, t in zip(frags, tonals, strict=True)}


def _with_lines(nb: NarrowbandLines | None, tracks: list, tonals: list, nav: Navigation, s: PassiveStages):
    """(the bearing tracks with their tonals, a line source's where their own beams showed none; the narrowband
    targets' records; the sources' roles) -- systems/passive/narrowband.py; without lines, the tracks as they are."""
    if nb is None:
        return list(zip(tracks, tonals, strict=True)), [], None
    from sonartrack.systems.passive.narrowband import narrowband_records, source_roles, tonals_from_lines

    roles = source_roles(nb, tracks, tonals, s)
    records = list(zip(tracks, tonals_from_lines(nb, roles, tracks, tonals, s), strict=True))
    return records, narrowband_records(nb, roles, nav, s), roles


def _with_narrowband(result: PassiveResult, nb: NarrowbandLines, roles, n_broadband: int) -> PassiveResult:
    """The result with the narrowband lines, gram and targets (ids after the bearing tracks' targets)."""
    from dataclasses import replace

    ids = tuple(tg.target_id for tg in result.targets[n_broadband:])
    feeds = {src: i + 1 for src, i in roles.track.items()}
    feeds |= {sid: tg.target_id for tg in result.targets[n_broadband:] for sid in (tg.track.track_id,
                                                                                    *tg.track.joined_track_ids)}
    return replace(result, line_tracks=nb.lines, line_sources=nb.sources, narrowband_target_ids=ids,
                   lofar=nb.gram, source_targets=feeds)


def _with_mftd_peaks(btr: BearingTimeRecord, s: PassiveStages) -> tuple[PeakRecord, BtrDetections]:
    """The peaks with the MFTD's detections that no peak of their window lies within half a gate of, as peaks of
    z = the tracker's init_amplitude (settings doc of ``[btr_mftd]``), in time order."""
    from sonartrack.detection.btr_mftd import btr_mftd

    cfg = s.settings.btr_mftd
    det = btr_mftd(btr.level, btr.cone_deg, s.settings.window_s, cfg.pfa, cfg)
    pk = btr.peaks
    near = np.array([np.any((pk.time_s == t) & (np.abs(pk.bearing_deg - c) <= 0.5 * s.tracker.gate_deg))
                     for t, c in zip(det.time_s, det.cone_deg, strict=True)], bool)
    t = np.concatenate([pk.time_s, det.time_s[~near]])
    order = np.argsort(t, kind="stable")
    b = np.concatenate([pk.bearing_deg, det.cone_deg[~near]])
    a = np.concatenate([pk.amplitude, np.full(int(np.sum(~near)), float(s.tracker.init_amplitude))])
    return PeakRecord(t[order], b[order], a[order]), det


def _narrowband(blocks, btr: BearingTimeRecord, s: PassiveStages, n_windows: int, progress) -> NarrowbandLines:
    """The narrowband stage's lines (systems/passive/narrowband.py), on the front end's gram (made in its pass), else
    -- a front end that makes none -- on a pass of its own over the recording (acoustics/lofar.py)."""
    from sonartrack.acoustics.lofar import lofar_gram
    from sonartrack.systems.passive.narrowband import narrowband_lines

    cfg = s.settings.narrowband
    gram = getattr(btr, "lofar", None)
    if gram is None and blocks is not None and n_windows >= cfg.integration:  # else no period (or no samples): no lines
        stage = _Stage(progress, "narrowband", n_windows)
        counted = (stage(k) or b for k, b in enumerate(blocks()))  # stage() returns None: the block passes through
        gram = lofar_gram(counted, s.fs_hz, s.array, cfg, s.settings.window_s)
    return narrowband_lines(gram, s)
