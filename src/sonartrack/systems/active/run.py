"""The active sonar chain: pings on a towed line array and the navigation in, confirmed target tracks out.

Stages, ping by ping (each a library function; this module only joins them, and memory does not grow with
the number of pings beyond the per-ping tables and a small B-scan):

1. front end (detection/cells.py): beams, matched filter (LFM pulse compression or CW Doppler bank), CFAR ->
   the normalised square-law statistic per beam x travel-time x Doppler cell (:class:`PingCells`);
2. detection at the root's false-alarm rate ``pfa``: single-ping (detection/cells.py: local maxima above the
   CFAR's threshold) and paper P1's MFTD across the last K pings per beam (detection/ping_mftd.py); the tracker
   gets the detector named by ``settings.detector``, and both detectors' detections are kept;
3. contacts (systems/active/contacts.py): each detection to two mirror bistatic positions by paper P4's
   eq. 2 with covariance J Sigma J^T, Doppler carried;
4. gates in front of the tracker (contacts.py): the range-rate gate (:func:`range_rate_gate`: a contact in a
   confirmed track's position gate with a range rate the track cannot have is kept from the tracker) and the
   decided sides (sides.py: each confirmed track's side by the likelihood ratio of its contacts and their
   mirrors under constant-velocity motion, once it has lived through a turn of the array; a track decided on
   its target's side has the mirror contact of each detection it gates dropped (:func:`resolve_mirrors`), a
   track decided a ghost has the contacts in its gate dropped, so it starves), and the clutter map
   (detection/clutter_map.py: still world positions over pings; on a CW a second map of the echoes the ridge notch
   hides, detection/cw_cells.py ``ridge_echoes``, whose still points' skirt and images are withheld too);
5. tracking: P4's IMM-IPDA with one-point initiation and existence-based confirmation (tracking/), one scan
   per ping, and after each scan the duplicate tracks merged (tracking/duplicates.py: a track whose state passes
   the track-to-track test against a confirmed one is deleted, the older confirmed track kept): IPDA tracks share
   the contacts in their gates, so a track started beside a target coalesces with that target's track (measured
   on the default scene, seed 9101: 8-18 segments per strong target without it, 1-2 with it).

:func:`track_detections` runs stages 3-5 alone on stored detections (the study tracks one set of detections
with several trackers).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import numpy as np

from sonartrack.core.errors import require
from sonartrack.detection.cells import Detections, PingCells
from sonartrack.detection.normalise import DelayShapes
from sonartrack.systems.active.checks import check_memory, check_spacing
from sonartrack.systems.active.contact_tracker import (  # noqa: F401 - re-exported: the chain's tracker stage
    ActiveTracks,
    ContactTracker,
    clutter_map_of,
    endfire_alias_of,
    rate_sd_of,
    ridge_map_of,
    track_detections,
)
from sonartrack.systems.active.contacts import (
    ActiveGeometry,
    Contacts,
    form_contacts,
)
from sonartrack.systems.active.cw_tracking import (
    cw_clutter_area,
    cw_contact_errors,
    cw_echo_window,
    cw_form_contacts,
    cw_merge_echoes,
    cw_peaked,
    cw_rate_sd_mps,
    cw_ridge_window,
    cw_unpeaked_errors,
    detection_rows,
)
from sonartrack.systems.active.settings import ActiveSettings

#: the stages timed in :attr:`ActiveResult.stage_seconds`
STAGES = ("front end", "single-ping detection", "mftd", "contacts", "tracking", "b-scan")


@dataclass(frozen=True, slots=True)
class BScan:
    """Range-bearing picture per ping: ``level (pings, beams, bins)`` float32, the largest normalised statistic of
    the travel-time cells of each bin (and of its Doppler cells); ``travel_time_s (bins,)`` bin centres (s),
    ``cone_deg (beams,)``, ``time_s (pings,)``."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    travel_time_s: np.ndarray
    level: np.ndarray


@dataclass(frozen=True, slots=True)
class ActiveResult:
    """Everything the chain produced (the faces write and draw it).

    ``detections``: the tracked ones, whose rows ``contacts.detection`` counts (the single-ping detector's, or the
    MFTD's with the strong single-ping ones :func:`with_strong` adds, ``detection_kind`` saying which row is which:
    "single", "mftd" or "strong"); ``single`` and ``mftd``: each detector's (``mftd`` empty when the MFTD did not
    run); ``contacts`` the mirror pairs of ``detections`` with the gate's verdict (``gated_out``: True where the
    contact passed the range-rate gate and went to the tracker, False where the gate kept it from the tracker: the
    name is historical, files.py's ``gated`` column); ``tracks``; ``bscan``; ``geometry`` the source and receiver;
    ``ping_time_s``; ``stage_seconds`` wall time per stage (s); ``thresholds`` each detector's threshold on its
    statistic ("single": on s; "mftd": on P1's S for K pings)."""

    detections: Detections
    single: Detections
    mftd: Detections
    contacts: Contacts
    gated_out: np.ndarray
    tracks: ActiveTracks
    bscan: BScan
    geometry: ActiveGeometry
    ping_time_s: np.ndarray
    settings: ActiveSettings
    stage_seconds: dict = field(default_factory=dict)
    thresholds: dict = field(default_factory=dict)
    detection_kind: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

    @property
    def duration_s(self) -> float:
        """Span of the pings (s): first to last transmit time plus one interval."""
        t = self.ping_time_s
        return float(t[-1] - t[0] + (t[1] - t[0] if len(t) > 1 else 0.0)) if len(t) else 0.0


class _Timer:
    def __init__(self):
        self.seconds = dict.fromkeys(STAGES, 0.0)

    def run(self, stage: str, fn, *args, **kwargs):
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        self.seconds[stage] += time.perf_counter() - t0
        return out


def geometry_of(nav) -> ActiveGeometry:
    """The source and receiver of an :class:`~sonartrack.systems.active.records.ActiveNav` (array centre = Rx).

    Parameters
    ----------
    nav : ActiveNav
        The navigation (times s, positions m, array heading rad).

    Returns
    -------
    ActiveGeometry
        Source positions as Tx, array-centre positions as Rx, the array-axis heading.
    """
    return ActiveGeometry(np.asarray(nav.time_s, float), np.asarray(nav.source_xy, float),
                          np.asarray(nav.array_xy, float), np.asarray(nav.array_heading_rad, float))


def _bscan_row(stat: np.ndarray, bins: int) -> np.ndarray:
    """(beams, bins) float32: the max over Doppler and over each bin's run of travel-time cells."""
    level = stat.max(axis=2)
    n = level.shape[1]
    edges = np.linspace(0, n, min(bins, n) + 1).astype(np.int64)
    return np.maximum.reduceat(level, edges[:-1], axis=1).astype(np.float32)


def _bscan_axis(delay_s: np.ndarray, bins: int) -> np.ndarray:
    n = len(delay_s)
    edges = np.linspace(0, n, min(bins, n) + 1).astype(np.int64)
    return 0.5 * (delay_s[edges[:-1]] + delay_s[np.maximum(edges[1:] - 1, 0)])


def ping_interval(ping_table, settings: ActiveSettings) -> float:
    """The ping interval T: the setting, or the ping table's median interval (one-line error for one ping).

    Parameters
    ----------
    ping_table : PingTable
        The pings (transmit times in s).
    settings : ActiveSettings
        The chain's settings (``ping_interval_s``, None to take it from the table).

    Returns
    -------
    float
        The ping interval (s).
    """
    if settings.ping_interval_s is not None:
        return float(settings.ping_interval_s)
    t = np.asarray(ping_table.transmit_time_s, float)
    require(len(t) >= 2, "a single ping has no ping interval for the MFTD: give more pings, or set ping_interval_s "
                         "(s) in a --config file (see --print-config), or use --detector single")
    return float(np.median(np.diff(t)))


class _Chain:
    """The per-ping core of the active chain (front end, both detectors, contacts, tracker, B-scan), shared by
    :func:`run_active` (:meth:`of_table`) and the live chain (systems/live/active.py): each ping comes with its own
    waveform and sample rate, and ``geometry`` is read only at and before the ping being run (a navigation that
    grows ping by ping serves; duck-typed as :class:`ActiveGeometry`).

    Parameters
    ----------
    geometry : ActiveGeometry or like
        Source, receiver and array heading (``tx_at``, ``rx_at``, ``heading_at``, ``velocity``, ``side_of``).
    settings : ActiveSettings
        The chain's settings, checked (``elements`` set).
    cw : bool
        The pings are CWs (the detector's threshold and the contacts' errors are a CW's).
    period_s : float or None
        The MFTD's ping interval (s; None when the MFTD does not run).
    scan_interval_s : float or None
        The tracker's scan interval (s; None: one ping).
    bscan_rows : int or None
        B-scan rows kept (the newest; None: every ping's).
    history_s : float or None
        The live chain's bounded history (s): the per-ping rows (detections, contacts, gate verdicts, tracker rows,
        B-scan rows) of pings more than this before the newest are dropped, so memory and the per-ping cost of
        :meth:`result` stop growing; :meth:`result` is then that of the last ``history_s``. None (the file run):
        every ping's.
    """

    def __init__(self, geometry, settings: ActiveSettings, *, cw: bool, period_s: float | None,
                 scan_interval_s: float | None, bscan_rows: int | None = None, history_s: float | None = None):
        from collections import deque

        from sonartrack.acoustics.active_beams import LineArray
        from sonartrack.detection.cells import detection_threshold
        from sonartrack.detection.cw_cells import cw_threshold

        s = self.settings = settings
        self.geometry, self.cw, self.period, self.scan_interval = geometry, bool(cw), period_s, scan_interval_s
        self.array = LineArray(int(s.elements), float(s.spacing_m))
        self.front_end = s.front_end_settings()
        fe = self.front_end
        self.shapes = (DelayShapes(fe.cfar.n_reference, fe.cfar.rank, fe.heavy_tail_tiles)
                       if fe.heavy_tail and fe.heavy_tail_by_delay and fe.cfar.method == "os" else None)
        self.threshold = cw_threshold(s.pfa, s.cw) if self.cw else detection_threshold(self.front_end)
        strong = s.mftd_strong_pfa
        self.strong = None if strong is None else (cw_threshold(strong, s.cw) if self.cw else detection_threshold(
            self.front_end.model_copy(update={"pfa": strong})))
        self.timer, self.mftd, self.tracker = _Timer(), None, None
        self.single: list[Detections] = []
        self.multi: list[Detections] = []
        self.tracked: list[Detections] = []  # what the contacts were formed from: the MFTD's + strong single-ping
        self.tracked_mftd_rows: list[int] = []  # how many of each ping's tracked rows are the MFTD's (the rest strong)
        self.bscan: deque[np.ndarray] = deque(maxlen=bscan_rows)
        self.times: list[float] = []
        self.gate: list[np.ndarray] = []
        self.contacts: list[Contacts] = []
        self.axes = None
        self.n_detections = 0
        self.history_s = None if history_s is None else float(history_s)
        self.ping_detections: list[int] = []  # each kept ping's detections (their rows dropped with it)
        self.dropped_detections = 0

    @classmethod
    def of_table(cls, ping_table, geometry: ActiveGeometry, settings: ActiveSettings) -> _Chain:
        """The chain for the pings of a table (its first ping's waveform; the intervals from its times), checked
        against the table (the array's spacing for its band, the memory its pings need)."""
        s = settings.checked(int(ping_table.channels[0]))
        period = ping_interval(ping_table, s) if s.detector == "mftd" else None
        check_spacing(s, ping_table)
        check_memory(s, ping_table, period)
        cw = len(ping_table) > 0 and ping_table.waveform(0).kind == "cw"
        return cls(geometry, s, cw=cw, period_s=period,
                   scan_interval_s=ping_interval(ping_table, s) if len(ping_table) > 1 else None)

    def _start(self, cells: PingCells, waveform, fs_hz: float) -> None:
        from sonartrack.detection.ping_mftd import CellAxes, PingMftd

        s = self.settings
        if self.cw:  # a CW's delay is known to its pulse length, not to P4's 10 ms; an unpeaked MFTD cell to its lobe
            s = self.settings = s.model_copy(update={"contacts": cw_contact_errors(s, cells.delay_s)})
        if self.cw and s.cw_peak_contacts:
            self.unpeaked = cw_unpeaked_errors(s.contacts, waveform.duration_s, int(s.elements), float(s.spacing_m),
                                               waveform.carrier_hz, s.sound_speed_mps)
            self.echo = cw_echo_window(s, waveform)
        self.axes = CellAxes.of(cells)
        if s.detector == "mftd":
            pfa = s.mftd_pfa if s.mftd_pfa is not None else s.pfa
            self.mftd = PingMftd(self.axes, self.period, pfa, s.sound_speed_mps, s.mftd_settings(), noise_mean=1.0,
                                 cfar=s.cw.estimate() if self.cw else self.front_end.cfar)
        # a CW's range rate is known to its Doppler resolution cell (cw_tracking.py)
        self.rate_sd = (cw_rate_sd_mps(waveform, float(fs_hz), self.front_end.doppler_pad, s.sound_speed_mps)
                        if self.cw else rate_sd_of(cells.range_rate_mps))
        self.beam_step = float(np.median(np.diff(cells.cone_deg))) if len(cells.cone_deg) > 1 else None
        self.tracker = ContactTracker(s.tracker_settings(), self.geometry, s.range_rate_gate_sigma, self.rate_sd,
                                      s.side_turn_deg, s.merge_probability, s.max_range_rate_mps,
                                      turns=s.turn_modes(), clutter_area_m2=cw_clutter_area(cells, s.sound_speed_mps),
                                      clutter_map=clutter_map_of(s), scan_interval_s=self.scan_interval,
                                      rejoin_s=s.rejoin_s, claims=s.contact_claims,
                                      keep_apart=s.merge_keep_apart, reunite_scans=s.merge_reunite_scans,
                                      endfire_alias=endfire_alias_of(s, waveform),
                                      ridge_window=cw_ridge_window(waveform, s.sound_speed_mps) if self.cw else None,
                                      ridge_map=ridge_map_of(s) if self.cw else None)

    def _front_end(self, w, fs: float, number: int, time_s: float, samples: np.ndarray) -> PingCells:
        """The ping's cells: detection/cells.py's for an LFM (samples before the direct blast's end gated, its
        arrival from the navigation), detection/cw_cells.py's for a CW (its normaliser across Doppler and delay,
        the reverberation ridge of each beam notched from the navigation)."""
        from sonartrack.detection.cells import ping_front_end
        from sonartrack.detection.cw_cells import cw_ping_cells

        g = self.geometry
        if w.kind != "cw":
            direct_s = float(np.hypot(*(g.tx_at(time_s) - g.rx_at(time_s)))) / self.settings.sound_speed_mps
            return ping_front_end(samples, fs, w, self.array, self.front_end, time_s=time_s, ping=number,
                                  direct_arrival_s=direct_s, shapes=self.shapes)
        motion = (float(g.heading_at(time_s)), g.velocity(time_s, "tx"), g.velocity(time_s, "rx"))
        return cw_ping_cells(samples, fs, w, self.array, self.front_end, self.settings.cw, time_s=time_s, ping=number,
                             motion=motion)

    def ping(self, number: int, time_s: float, samples: np.ndarray, waveform, fs_hz: float) -> PingCells:
        """One ping through every stage (module doc): its number, transmit time (s), samples (channels, n) complex
        baseband, transmitted pulse (Waveform) and sample rate (Hz); returns its cells (the B-scan row is kept)."""
        from sonartrack.detection.cells import detect_ping

        s, tm = self.settings, self.timer
        require(samples.shape[0] == s.elements, f"ping {number} has {samples.shape[0]} channels, the array "
                                                f"{s.elements}: give the pings of one array")
        cells = tm.run("front end", self._front_end, waveform, float(fs_hz), number, time_s, samples)
        if self.axes is None:
            self._start(cells, waveform, fs_hz)
        single = tm.run("single-ping detection", detect_ping, cells, self.threshold)
        peak = self.cw and s.cw_peak_contacts
        if peak:  # one detection per echo (cw_tracking.py)
            single = detection_rows(single, cw_merge_echoes(single, cells.cone_deg, *self.echo))
        self.single.append(single)
        det, peaked, n_mftd = single, None, 0
        if self.mftd is not None:
            det = tm.run("mftd", self.mftd.push, cells)
            self.multi.append(det)
            n_mftd = len(det)
            if peak:
                det, peaked, n_mftd = self._cw_tracked(det, single, cells)
            elif self.strong is not None:
                det = with_strong(det, single, self.strong, float(np.median(np.diff(self.axes.travel_time_s))))
        self.tracked.append(det)
        self.tracked_mftd_rows.append(n_mftd)
        self.bscan.append(tm.run("b-scan", _bscan_row, cells.statistic, s.bscan_bins))
        if peaked is None:
            c = tm.run("contacts", form_contacts, det, [time_s], self.geometry, s.sound_speed_mps, s.contacts,
                       self.beam_step, [number])
        else:
            c = tm.run("contacts", cw_form_contacts, det, peaked, [time_s], self.geometry, s.sound_speed_mps,
                       s.contacts, self.unpeaked, self.beam_step, [number])
        c = replace(c, detection=c.detection + self.n_detections)  # rows of the whole record's detections
        self.n_detections += len(det)
        self.contacts.append(c)
        ridge = tm.run("contacts", self._ridge_contacts, cells, number, time_s) if self.cw else None
        self.gate.append(tm.run("tracking", self.tracker.step, time_s, c, ridge))
        self.times.append(float(time_s))
        self.ping_detections.append(len(det))
        if self.history_s is not None:
            self._forget(float(time_s) - self.history_s)
        return cells

    def _ridge_contacts(self, cells: PingCells, number: int, time_s: float) -> Contacts | None:
        """The contacts of a CW ping's echoes hidden by the ridge notch (detection/cw_cells.py ``ridge_echoes``, at
        the single-ping threshold), for the clutter map alone (a still point sits on its own beam's ridge: the map
        sees the point itself, not only its skirt); None without a map or without the power before the notch."""
        from sonartrack.detection.cw_cells import ridge_echoes

        if self.tracker.ridge_map is None:
            return None
        det = ridge_echoes(cells, self.threshold)
        if det is None:
            return None
        s = self.settings
        return form_contacts(det, [time_s], self.geometry, s.sound_speed_mps, s.contacts, self.beam_step, [number])

    def _cw_tracked(self, mftd: Detections, single: Detections, cells: PingCells):
        """A CW ping's tracked detections (cw_tracking.py): each MFTD detection measured by the ping's own echo peak
        where there is one, the strong single-ping ones joined, one per echo (the MFTD's preferred); which were
        measured by a peak of this ping (the strong ones are); how many of the rows kept are the MFTD's (first)."""
        m = self.settings.mftd_settings()
        det, peaked = cw_peaked(mftd, single, m.pool_beams, 2 * m.pool_cells, self.front_end.doppler_pad)
        n = len(det)
        if self.strong is not None:
            det = with_strong(det, single, self.strong, float(np.median(np.diff(self.axes.travel_time_s))))
        peaked = np.concatenate([peaked, np.ones(len(det) - n, bool)])
        group = np.concatenate([np.zeros(n), np.ones(len(det) - n)])
        keep = cw_merge_echoes(det, cells.cone_deg, *self.echo, group)
        return detection_rows(det, keep), peaked[keep], int(keep[:n].sum())

    def _forget(self, before_s: float) -> None:
        """Drop the rows of the pings sent before ``before_s`` (s): the bounded history of a live run."""
        n = int(np.searchsorted(np.asarray(self.times), before_s, side="left"))
        if n <= 0:
            return
        self.dropped_detections += sum(self.ping_detections[:n])
        for rows in (self.single, self.multi, self.tracked, self.tracked_mftd_rows, self.contacts, self.gate,
                     self.times, self.ping_detections):
            del rows[:n]
        self.tracker.drop_scans(n)
        while len(self.bscan) > len(self.times):
            self.bscan.popleft()

    def result(self) -> ActiveResult:
        from sonartrack.detection.ping_mftd import concat_detections

        single, multi = concat_detections(self.single), concat_detections(self.multi)
        tracked = concat_detections(self.tracked) if self.mftd is not None else single
        t = np.asarray(self.times, float)
        a = self.axes
        bins = _bscan_axis(np.asarray(a.travel_time_s), self.settings.bscan_bins) if a is not None else np.zeros(0)
        level = np.stack(self.bscan) if self.bscan else np.zeros((0, 0, 0), np.float32)
        cone = np.asarray(a.cone_deg) if a is not None else np.zeros(0)
        bscan = BScan(t[len(t) - len(self.bscan):], cone, bins, level)  # the newest rows (all in a file run)
        tracks = self.tracker.result() if self.tracker is not None else ContactTracker(
            self.settings.tracker_settings(), self.geometry, None, 1.0).result()
        contacts = Contacts.concat(self.contacts)
        if self.dropped_detections:  # the rows of the kept detections (a bounded live history)
            contacts = replace(contacts, detection=contacts.detection - self.dropped_detections)
        return ActiveResult(tracked, single, multi, contacts,
                            np.concatenate(self.gate) if self.gate else np.zeros(0, bool), tracks, bscan,
                            self.geometry, t, self.settings, dict(self.timer.seconds),
                            self._thresholds(), self._tracked_kind(len(tracked)))

    def _tracked_kind(self, n: int) -> np.ndarray:
        """Each tracked row's source: "single" (the single-ping detector tracked), "mftd" or "strong"."""
        if self.mftd is None:
            return np.full(n, "single", dtype=object)
        return np.concatenate([np.array(["mftd"] * m + ["strong"] * (len(d) - m), dtype=object)
                               for d, m in zip(self.tracked, self.tracked_mftd_rows, strict=True)]
                              or [np.zeros(0, object)])

    def _thresholds(self) -> dict:
        out = {"single": float(self.threshold)}
        if self.mftd is not None:
            out["mftd"] = float(self.mftd.threshold(self.mftd.settings.frames))
        return out


def with_strong(mftd: Detections, single: Detections, threshold: float, delay_step_s: float) -> Detections:
    """The MFTD's detections of a ping and the single-ping ones at least ``threshold`` strong that no MFTD detection
    already holds (not within one beam and 3 delay cells of one): a target entering the window echoes strongly on
    its first ping, while the MFTD's K-ping stack holds it on one frame of K (measured: its first MFTD contact on its
    3rd ping at 15 dB)."""
    from sonartrack.detection.ping_mftd import concat_detections

    strong = np.asarray(single.statistic) >= threshold
    if len(mftd) and strong.any():
        near = (np.abs(single.beam[:, None] - mftd.beam[None, :]) <= 1) & (
            np.abs(single.travel_time_s[:, None] - mftd.travel_time_s[None, :]) <= 3 * delay_step_s)
        strong &= ~near.any(axis=1)
    if not strong.any():
        return mftd
    idx = np.nonzero(strong)[0]
    return concat_detections([mftd, type(single)(*(np.asarray(getattr(single, f))[idx] for f in
                                                   single.__dataclass_fields__))])


def run_active(pings: Iterable[tuple[int, float, np.ndarray]], ping_table, nav, settings: ActiveSettings, *,
               progress=None) -> ActiveResult:
    """The active chain over a sequence of pings (module doc).

    Parameters
    ----------
    pings : iterable of (int, float, ndarray)
        (ping number, transmit time s, samples (channels, samples) complex baseband) per ping, in the order of
        ``ping_table`` (systems/active/scene_files.py ``iter_pings``); one ping in memory at a time.
    ping_table : PingTable
        The pings' table (systems/active/records.py): times, waveform, sample rate, channels.
    nav : ActiveNav or ActiveGeometry
        Source, array centre and array heading against time, covering the pings.
    settings : ActiveSettings
        The chain's settings tree (``spacing_m`` required).
    progress : optional
        ``start(label, total, done)`` / ``advance(n)`` hooks (cli/_progress.py), advanced once per ping.

    Returns
    -------
    ActiveResult
        Detections of both detectors, contacts, tracks, the B-scan and the stage timings.
    """
    geometry = nav if isinstance(nav, ActiveGeometry) else geometry_of(nav)
    t = np.asarray(ping_table.transmit_time_s, float)
    require(len(t) >= 1, "the ping table holds no ping")
    require(geometry.covers(t[0] - 1.0, t[-1] + 1.0) or geometry.covers(t[0], t[-1]),
            f"the navigation ({geometry.time_s[0]:g}..{geometry.time_s[-1]:g} s) does not cover the pings "
            f"({t[0]:g}..{t[-1]:g} s): give the navigation of the whole ping sequence")
    chain = _Chain.of_table(ping_table, geometry, settings)
    if progress is not None:
        progress.start("active pings", len(t), 0)
    for i, (number, time_s, samples) in enumerate(pings):
        chain.ping(int(number), float(time_s), np.asarray(samples), ping_table.waveform(i), float(ping_table.fs_hz[i]))
        if progress is not None:
            progress.advance(1)
    return chain.result()
