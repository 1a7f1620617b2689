"""The passive chain on a live stream, window by window, with bounded state (issue 31, items 2 and 4).

The file chain's windowed core (systems/passive/chain.py :class:`~sonartrack.systems.passive.chain.PassiveCore`)
runs on each window as its last sample arrives: beams, normaliser and peaks (a ``btr`` row), the LOFAR accumulator
and the tonal band's spectra from the same transforms, and the tracker's scan on the peaks (a ``tracks`` update)
once the navigation fixes the array's heading at the scan (systems/live/navigation.py). Stages 3-5 -- measurements,
tonal lines, joins, narrowband lines, sides, TMA and legs -- are the file chain's own
(:func:`~sonartrack.systems.passive.chain.finish_passive`), run on the kept history by :meth:`LivePassive.refresh`
(on a schedule, off the display's path) and :meth:`LivePassive.finish`.

Equality with the file chain: the same core and the same finishing on the same windows, so on a stream no longer
than ``history_s`` the final targets equal ``run_passive_recording``'s to the rounding of the front end's batched
products (the file chain transforms 32 windows at once, the live chain one: ~1e-13 deg in a peak). The final tonal
pass reads the spectra the file chain's spill holds, kept in a ring of the last ``history_s``
(systems/live/windows.py). A refresh reads the tonal lines from per-track accumulators fed scan by scan instead
(systems/live/tonals.py), so that its cost does not grow with the history.

Bounded state over a day: the bearing-time rows, peaks and tracker rows of the last ``history_s`` (default 1 h:
3.6 MB of rows, ~2 MB of tracker rows), the LOFAR periods of that span (61 beams x the band's bins x 8 bytes a
period: ~100 MB at 16 x 2.5 m and 4 kHz), the tonal spectra of that span on disk, the tracker's live tracks and the
navigation of that span. A live run longer than ``history_s`` differs from the file run there: the TMA sees the
last ``history_s`` of each track only.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque

import numpy as np

from sonartrack.core.errors import require
from sonartrack.io.stream.types import NavFix, SampleBlock, StreamEvent, StreamHeader
from sonartrack.systems.live.navigation import LiveNavigation
from sonartrack.systems.live.tonals import LiveTonals
from sonartrack.systems.live.updates import btr_update, lofar_update, ownship_update, targets_update, tracks_update
from sonartrack.systems.live.windows import RingSpill, WindowAssembler
from sonartrack.systems.passive.chain import PassiveCore, PassiveResult
from sonartrack.systems.passive.settings import PassiveSettings

#: windows the tonal ring holds beyond the history: a refresh reads the oldest while the stream writes new ones
#: (10 minutes at 1 s windows; a slot overwritten before it was read reads as a blank window)
SPILL_MARGIN_WINDOWS = 600
#: events kept for the health update
HEALTH_EVENTS = 20


class LivePassive:
    """The passive chain on a stream (module doc; the contract of /work/team/LIVE.md).

    Parameters
    ----------
    settings : PassiveSettings
        The chain's settings (``[btr_mftd]`` must be off: it needs the whole record).
    header : StreamHeader
        The stream: channels, rate, UTC start.
    history_s : float
        Span of history kept for the TMA and the displays (s).
    nav : Navigation, optional
        A known navigation (a finished recording replayed with its navigation table); None: from :meth:`push_nav`.
    tow_length_m : float
        Array centre behind the ship (m) for the fixes of :meth:`push_nav`.
    nav_timeout_s : float
        No fix for this long (stream time): the ownship coasts (module doc of systems/live/navigation.py).
    calibration : Calibration, optional
        The hydrophones' calibration (io/calibration.py, ``--calibration``): with the stream's full scale
        (:func:`stream_scale`) the samples become pascals as the file chain's are; None: pascals already.
    """

    def __init__(self, settings: PassiveSettings, header: StreamHeader, *, history_s: float = 3600.0, nav=None,
                 tow_length_m: float = 0.0, nav_timeout_s: float = 5.0, calibration=None):
        check_live_settings(settings)
        require(history_s >= settings.window_s, f"history_s {history_s:g} s is shorter than one window: give at "
                                                "least window_s")
        self.settings, self.header, self.history_s = settings, header, float(history_s)
        self.options = {"tow_length_m": float(tow_length_m), "nav_timeout_s": float(nav_timeout_s),
                        "calibration": calibration}
        self.scale, scale_note = stream_scale(header, calibration)
        self.stages = settings.stages(header.rate_hz, channels=header.channels)
        self.window_s = settings.window_s
        self.n_samples = int(round(self.window_s * header.rate_hz))
        self.keep_windows = max(1, int(math.ceil(self.history_s / self.window_s)))
        self.lock = threading.RLock()
        self.fixed_nav = nav
        self.nav = LiveNavigation(header.start_utc, tow_length_m=tow_length_m, timeout_s=nav_timeout_s,
                                  keep_s=self.history_s + 600.0)
        self._fresh()
        if scale_note:
            self.events.append(f"calibration: {scale_note}")
            self.new_events.append(self.events[-1])

    def _fresh(self) -> None:
        """The stream's state from scratch (also the base a restore fills in)."""
        self.assembler = WindowAssembler(self.header.channels, self.n_samples)
        self.spill = RingSpill(self.n_samples, self.header.rate_hz, self.stages.tonal,
                               self.keep_windows + SPILL_MARGIN_WINDOWS)
        self.core = PassiveCore(self.stages, self.spill)
        self.tonals = LiveTonals(self.stages, self.spill)
        self.rows: deque = deque()      # (k, z row float32, peak angles, peak heights): the btr history
        self.scans: deque = deque()     # (k, the tracker's rows of that scan)
        self.pending: deque = deque()   # (k, t, angles, heights): scans waiting for the navigation
        self.periods: deque = deque()   # (p, power float32 (B, F), statistic float32 (B, F)): LOFAR history
        self.k_first: int | None = None
        self.k_next = 0
        self.n_periods = 0
        self.selected: int | None = None
        self.events: deque = deque(maxlen=HEALTH_EVENTS)
        self.new_events: list[str] = []  # not yet in a health update (the console logs each event once)
        self.gaps = 0
        self.latency_s: deque = deque(maxlen=1000)
        self.last_targets: dict | None = None
        self._no_heading = False

    # ---- input --------------------------------------------------------------------------------------------
    def push_nav(self, fix: NavFix) -> None:
        """A navigation fix (ignored when the chain runs on a known navigation)."""
        with self.lock:
            self.nav.push(fix)

    def push_block(self, block: SampleBlock) -> list[dict]:
        """A block of samples: the display updates of the windows it completes."""
        require(block.samples.ndim == 2 and block.samples.shape[1] == self.header.channels,
                f"a block of shape {block.samples.shape} on a {self.header.channels}-channel stream: give "
                "(samples, channels)")
        with self.lock:
            return self._windows(self.assembler.add(int(block.first_index), block.samples))

    def note(self, event: StreamEvent) -> list[dict]:
        """A stream event: a gap restarts the window after it (the windows it touches are zeros); every event goes
        to the health update."""
        with self.lock:
            self.events.append(f"{event.kind}: {event.detail}")
            self.new_events.append(self.events[-1])
            out = []
            if event.kind == "gap" and event.first_index is not None and event.count:
                self.gaps += 1
                out = self._windows(self.assembler.gap(int(event.first_index), int(event.count)))
            return out + [self._health()]

    # ---- per window ---------------------------------------------------------------------------------------
    def _windows(self, done: list) -> list[dict]:
        out = []
        for k, x in done:
            t0 = time.perf_counter()
            out += self._window(k, x)
            self.latency_s.append(time.perf_counter() - t0)
        if done:
            out.append(self._health())
        return out

    def _window(self, k: int, x: np.ndarray | None) -> list[dict]:
        """One window through the core: its btr row, the scans the navigation now allows, the LOFAR rows."""
        if self.k_first is None:
            self.k_first = k
            self.spill.skip_to(k)
        block = np.zeros((self.header.channels, self.n_samples), np.float32) if x is None else x
        if self.scale is not None and x is not None:
            block = block * self.scale[:, None]  # float64, as the file chain's calibrated blocks: the same product
        row, angle, height = next(self.core.front.windows([block]))
        t = k * self.window_s + 0.5 * self.window_s
        self.rows.append((k, row.astype(np.float32), angle, height))
        self.k_next = k + 1
        out = [btr_update(t, self.stages.front_end.cone_deg, row)]
        if len(angle):
            self.pending.append((k, t, angle, height))
        out += self._step_scans(t + 0.5 * self.window_s)
        out += self._new_periods()
        self._trim()
        return out

    def _heading(self, t: float, coasting: bool):
        """The array's heading for the scan at ``t`` (a Navigation, degrees, or None: wait for the fixes)."""
        if self.fixed_nav is not None:
            return self.fixed_nav
        if self.nav.covers(t):
            return self.nav.heading_deg(t)
        if not coasting:
            return None
        h = self.nav.heading_deg(t)
        return 0.0 if h is None else h  # no navigation at all: no turn predicted

    def _step_scans(self, stream_t: float) -> list[dict]:
        coasting = self.fixed_nav is None and self.nav.update(stream_t)
        out = []
        while self.pending:
            k, t, angle, height = self.pending[0]
            heading = self._heading(t, coasting)
            if heading is None:
                break
            self.pending.popleft()
            if self._no_heading and self.nav.navigation() is not None:
                self.core.heading_deg = None  # the first heading after none: no turn from the placeholder
            self._no_heading = self.fixed_nav is None and self.nav.navigation() is None
            rows = self.core.scan(t, angle, height, heading)[0]
            self.scans.append((k, rows))
            self.tonals.add_scan(k, rows)
            out.append(tracks_update(t, rows))
        return out

    def _new_periods(self) -> list[dict]:
        """LOFAR periods completed: into the history (the accumulator's list emptied), and the selected track's
        row."""
        acc = self.core.front.lofar
        if acc is None:
            return []
        out = []
        for power, stat in acc.take_periods():
            self.periods.append((self.n_periods, power.astype(np.float32), stat))
            self.n_periods += 1
            out += self._lofar_row(self.periods[-1])
        return out

    def _period_time(self, p: int) -> float:
        length = self.settings.narrowband.integration
        return (p + 0.5) * length * self.window_s + self.k_first * self.window_s

    def _lofar_row(self, period, track_id: int | None = None) -> list[dict]:
        """The LOFAR row of the selected track's beam in one period (none when it did not live then)."""
        tid = self.selected if track_id is None else track_id
        if tid is None:
            return []
        t = self._period_time(period[0])
        cone = self._track_cone(tid, t)
        if cone is None:
            return []
        beams = self.settings.narrowband.cone_deg
        beam = int(np.argmin(np.abs(beams - cone)))
        return [lofar_update(tid, t, self.core.front.lofar.freqs_hz, period[1][beam])]

    def _track_cone(self, track_id: int, t: float) -> float | None:
        """The track's cone angle at its scan nearest before ``t`` (None: not alive by then)."""
        for _, rows in reversed(self.scans):
            if rows["time_s"].size and rows["time_s"][0] <= t:
                hit = np.flatnonzero(rows["track_id"] == track_id)
                if hit.size:
                    return float(rows["bearing_deg"][hit[0]])
        return None

    def _trim(self) -> None:
        """Drop what is older than the history."""
        first = self.k_next - self.keep_windows
        while self.rows and self.rows[0][0] < first:
            self.rows.popleft()
        while self.scans and self.scans[0][0] < first:
            self.scans.popleft()
        self.tonals.trim(first)
        length = self.settings.narrowband.integration
        while self.periods and self._period_time(self.periods[0][0]) - 0.5 * length * self.window_s < \
                first * self.window_s:
            self.periods.popleft()

    def _health(self, every_event: bool = False) -> dict:
        """The health update: its ``events`` the ones since the last (``every_event``: the recent ones kept)."""
        lat = np.array(self.latency_s) if self.latency_s else np.zeros(1)
        events, self.new_events = (list(self.events) if every_event else self.new_events), []
        coasting = self.fixed_nav is None and self.nav.coasting
        return {"type": "health", "t_s": self.k_next * self.window_s, "rate_hz": float(self.header.rate_hz),
                "latency_s": float(lat[-1]), "latency_median_s": float(np.median(lat)),
                "latency_p99_s": float(np.quantile(lat, 0.99)), "gaps": self.gaps, "events": events,
                "nav": "coasting" if coasting else "ok",
                "warning": "navigation dropout: ownship coasting" if coasting else None}

    # ---- the display's choices -----------------------------------------------------------------------------
    def select(self, track_id: int | None) -> list[dict]:
        """Select a track for the LOFAR rows: its rows over the history kept (then one per period as they come)."""
        with self.lock:
            self.selected = None if track_id is None else int(track_id)
            if self.selected is None:
                return []
            return [u for period in self.periods for u in self._lofar_row(period)]

    def history(self) -> list[dict]:
        """The display's history (a client that joins, or the chain restored): the btr rows kept, the latest
        tracks, targets and ownship."""
        with self.lock:
            cone = self.stages.front_end.cone_deg
            out = [btr_update(k * self.window_s + 0.5 * self.window_s, cone, z) for k, z, _, _ in self.rows]
            if self.scans:
                out.append(tracks_update(float(self.scans[-1][1]["time_s"][0]) if len(self.scans[-1][1]["time_s"])
                                         else 0.0, self.scans[-1][1]))
            out += [self.last_targets] if self.last_targets is not None else []
            own = self._ownship()
            return out + ([own] if own is not None else []) + [self._health(every_event=True)]

    def _ownship(self) -> dict | None:
        nav = self.fixed_nav if self.fixed_nav is not None else self.nav.navigation()
        latlon = None
        if self.fixed_nav is None and self.nav.fixes:
            latlon = (self.nav.fixes[-1][1], self.nav.fixes[-1][2])
        half = 0.5 * (self.stages.array.elements - 1) * self.stages.array.spacing_m
        return ownship_update(self.k_next * self.window_s, nav, self.fixed_nav is None and self.nav.coasting,
                              latlon, half)

    # ---- the slow part -------------------------------------------------------------------------------------
    def refresh(self) -> list[dict]:
        """Sides, TMA and legs on the current tracks (slow: on a schedule, from a worker thread): the targets and
        the ownship."""
        snap = self._snapshot(exact_tonals=False)
        result = None if snap is None else _result(self, snap)
        with self.lock:
            t = self.k_next * self.window_s
            self.last_targets = targets_update(t, result) if result is not None else \
                {"type": "targets", "t_s": t, "rows": []}
            own = self._ownship()
            return [self.last_targets] + ([own] if own is not None else [])

    def finish(self) -> PassiveResult:
        """At the end of the stream: the scans still waiting stepped (on the navigation there is), and the same
        PassiveResult the file chain gives (module doc)."""
        with self.lock:
            while self.pending:
                k, t, angle, height = self.pending.popleft()
                heading = self._heading(t, True)
                self.scans.append((k, self.core.scan(t, angle, height, heading)[0]))
                self.tonals.add_scan(k, self.scans[-1][1])
        snap = self._snapshot(exact_tonals=True)
        require(snap is not None, "the stream ended before one whole window or without navigation: no result")
        return _result(self, snap)

    def _snapshot(self, exact_tonals: bool) -> dict | None:
        """What the finishing stages read, taken under the lock (the arrays are not written again); the tonal lines
        from the accumulators (systems/live/tonals.py), or with ``exact_tonals`` from the file chain's pass over the
        spectra ring where it holds every window of the history (not after a restore)."""
        with self.lock:
            nav = self.fixed_nav if self.fixed_nav is not None else self.nav.navigation()
            if nav is None or not self.rows:
                return None
            first = max(self.rows[0][0], self.spill.first_window)
            ring = exact_tonals and first == self.rows[0][0]
            return {"rows": list(self.rows), "scans": [r for _, r in self.scans], "periods": list(self.periods),
                    "nav": nav, "n_windows": self.k_next, "first_window": first,
                    "tonals": None if ring else self.tonals.snapshot(),
                    "nav_times": np.array([f[0] for f in self.nav.fixes]) - self.header.start_utc.timestamp()
                    if self.fixed_nav is None else self.fixed_nav.time_s}

    # ---- checkpoints ----------------------------------------------------------------------------------------
    def checkpoint(self, path) -> None:
        """Write the chain's state to ``path`` atomically (systems/live/checkpoint.py)."""
        from sonartrack.systems.live.checkpoint import write_checkpoint

        with self.lock:
            write_checkpoint(self, path)

    @classmethod
    def restore(cls, path) -> LivePassive:
        """The chain as checkpointed: it continues from the next sample, its display history back."""
        from sonartrack.systems.live.checkpoint import read_checkpoint

        return read_checkpoint(cls, path)

    def close(self) -> None:
        """Free the tonal ring's disk."""
        self.spill.close()


def check_live_settings(settings: PassiveSettings) -> None:
    """InputError for settings the live chain cannot run: ``[btr_mftd]`` (it needs the whole bearing-time record)."""
    require(not settings.btr_mftd.enabled, "the live chain cannot run [btr_mftd] (the bearing-time MFTD needs the "
                                           "whole record): set [btr_mftd] enabled = false, or run passive on the file")


def stream_scale(header: StreamHeader, calibration) -> tuple[np.ndarray | None, str | None]:
    """Pascals per sample unit of a stream (channels,), or None for samples in pascals; and a note for the operator.

    The stream's samples are in full-scale units (io/stream/types.py). A header's ``full_scale_v`` is the
    recorder's own statement of the volts at full scale, the V_fs of io/calibration.py's p = x V_fs 1e-6 /
    10^((S + G) / 20); the calibration gives S and G (its own full_scale_v stands where the header states none). A
    calibration whose full scale is not 1 V and differs from the header's is refused (which one holds?). A header's
    full scale without a calibration: the samples become volts (V_fs x), said in the note (levels in dB re 1 V, not
    re 1 uPa; bearings and tracks do not depend on the scale).
    """
    from sonartrack.io.calibration import Calibration

    cal = calibration if calibration is not None else Calibration.identity()
    vfs = header.full_scale_v
    if vfs is None:
        return (None, None) if cal.is_identity else (cal.pa_per_unit(header.channels), None)
    require(vfs > 0 and math.isfinite(vfs), f"the stream states full scale {vfs} V: a recorder's full scale is a "
                                            "positive voltage (fix the recorder's header)")
    if cal.is_identity:
        return np.full(header.channels, float(vfs)), (f"the stream states full scale {vfs:g} V but no --calibration "
                                                      "gives the hydrophones' sensitivity: levels are in volts, not "
                                                      "pascals")
    stated = np.asarray(cal.full_scale_v, float)
    require(np.all(stated == 1.0) or np.allclose(stated, vfs, rtol=1e-9),
            f"the calibration's full_scale_v ({stated[0]:g} V) differs from the stream's ({vfs:g} V): remove "
            "full_scale_v from the calibration (the recorder states it)")
    return cal.pa_per_unit(header.channels) * (float(vfs) / stated if np.all(stated == 1.0) else 1.0), None


def _with_measurements(tracks, peaks, max_offset_deg: float):
    """The tracks without those that hold no peak in the history kept (a track that coasted through its whole
    stretch after the cut: its measurements would be empty, which the finishing stages do not take --
    systems/passive/measurements.py ``merge_duplicates`` fails on one)."""
    from dataclasses import fields, replace

    from sonartrack.systems.passive.measurements import track_measurements

    empty = [m.track_id for m in track_measurements(tracks, peaks, max_offset_deg) if not len(m.time_s)]
    if not empty:
        return tracks
    keep = ~np.isin(tracks.track_id, empty)
    return replace(tracks, **{f.name: getattr(tracks, f.name)[keep] for f in fields(tracks)
                              if getattr(tracks, f.name) is not None})


def _result(live: LivePassive, snap: dict) -> PassiveResult:
    """The file chain's stages 3-5 on a snapshot (systems/passive/chain.py ``finish_passive``), with the file run's
    verdicts on fast batch solutions and on navigation gaps (systems/passive/nav_flags.py)."""
    from dataclasses import replace

    from sonartrack.acoustics.beamforming import BearingTimeRecord
    from sonartrack.acoustics.lofar import LofarGram
    from sonartrack.acoustics.xcorr_bearing import PeakRecord
    from sonartrack.systems.passive.chain import finish_passive
    from sonartrack.systems.passive.files import RecordingNavigation
    from sonartrack.systems.passive.nav_flags import bound_batch_speed, flag_navigation_gaps, recording_gaps

    w, rows = live.window_s, snap["rows"]
    ks = np.array([r[0] for r in rows])
    peaks = PeakRecord(np.concatenate([np.full(len(a), k * w + 0.5 * w) for k, _, a, _ in rows]),
                       np.concatenate([a for _, _, a, _ in rows]), np.concatenate([h for _, _, _, h in rows]))
    gram = None
    if snap["periods"] and live.core.front.lofar is not None:
        ps = np.array([p for p, _, _ in snap["periods"]])
        length = live.settings.narrowband.integration
        t = (ps + 0.5) * length * w + live.k_first * w
        gram = LofarGram(t, live.settings.narrowband.cone_deg, live.core.front.lofar.freqs_hz,
                         np.stack([p for _, p, _ in snap["periods"]]), np.stack([z for _, _, z in snap["periods"]]))
    cone = live.stages.front_end.cone_deg
    btr = BearingTimeRecord(ks * w + 0.5 * w, cone, np.stack([r[1] for r in rows]), peaks, gram)
    tracks = _with_measurements(live.core.tracker.tracks(snap["scans"]), peaks, live.settings.max_peak_offset_deg)
    first, stop = snap["first_window"], snap["n_windows"]
    tonals = snap["tonals"]
    result = finish_passive(btr, tracks, snap["nav"], live.stages, stop,
                            (lambda: tonals) if tonals is not None else (lambda: live.spill.windows(first, stop)),
                            first_window=first)
    result = bound_batch_speed(result)
    lag = live.options["tow_length_m"] / 3.0 if live.fixed_nav is None else 0.0  # tow length over a slow 3 m/s
    navr = RecordingNavigation(snap["nav"], [], (snap["nav_times"],), lag)
    result, lines = flag_navigation_gaps(result, recording_gaps(navr, stop * w), "navigation")
    return replace(result, warnings=tuple(lines) + result.warnings)
