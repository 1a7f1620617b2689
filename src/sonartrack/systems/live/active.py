"""Active pings on a live stream: each ping through the file chain's own per-ping core as it arrives, with the
ping's geometry from the live navigation (issue 31 items 1-3).

A ping frame (io/stream/frames.py, kind 4) carries one listening window as complex baseband. Each ping runs
through systems/active/run.py's ``_Chain`` -- the core :func:`~sonartrack.systems.active.run.run_active` runs on
a file's pings: front end, single-ping detections, the MFTD (where the settings say), mirror contacts, the gates,
the IMM-IPDA tracker, the sides -- so that on the same pings and navigation the live run's tracks ARE the file
run's (tests/systems/live/test_live_active.py). Its geometry (source, array, heading, their velocities: the LFM's
direct blast, the CW's reverberation ridge, the contacts, the range-rate gate) comes from:

- ``nav``: an ActiveGeometry (or ActiveNav) of the whole run, as the file chain takes it (a replay); or
- the live fixes (:meth:`LiveActive.push_nav`; active_geometry.py :class:`LiveGeometry`: the source and the array
  towed ``source_tow_m`` and ``array_tow_m`` behind the ship). A ping waits (at most until the next ping comes)
  for the fixes to reach 1 s past its transmit time; a ping run before then is run on the last fixes (the
  navigation is late: "coasting", said in a health update); a ping before any navigation, or with no tow lengths
  given, is shown on the B-scan only (its front end for a platform at rest) and not tracked, said once.

The chain starts at the first ping it can track, once the ping interval is known: ``ping_interval_s`` of the
settings, else the first two pings' interval (the file chain takes the ping table's median: the same for pings at
a regular interval), so the first ping's updates come with the second's when the interval is not set.

Updates per ping (active_updates.py): the B-scan (with the scan's tracks where their echoes fall), the active
targets (``active_targets``: confirmed pairs, a side each once decided) and the ownship.

Bounded state (issue 31 item 4): the chain keeps the per-ping rows (detections, contacts, gate verdicts, tracker
rows) of the last ``history_s`` only, and the newest ``bscan_rows`` B-scan rows; the live tracks, the MFTD stack and
the clutter map are the chain's own (bounded by what is live), so a run longer than ``history_s`` returns the last
``history_s`` of the run's result (the tracks of each ping there are the unbounded run's). :meth:`checkpoint` and
:meth:`restore` keep the whole state (systems/live/checkpoint.py); a ping at or before the newest taken is skipped
(a resumed stream's replay, a repeated or out-of-order frame), said once.
"""

from __future__ import annotations

import threading
from collections import deque

import numpy as np

from sonartrack.io.stream.types import NavFix, PingBlock, StreamHeader
from sonartrack.systems.live import active_updates as au


class LiveActive:
    """The active chain on a stream's pings (module doc).

    Parameters
    ----------
    settings : ActiveSettings
        The active chain's settings (``spacing_m`` required; ``elements`` set from the stream).
    header : StreamHeader
        The stream (its channels are the array's elements; its start is the pings' and the fixes' time zero).
    nav : ActiveGeometry or ActiveNav, optional
        The navigation of the whole run; default: the fixes given to :meth:`push_nav`.
    source_tow_m, array_tow_m : float, optional
        The source and the array centre behind the ship along its track (m), for the live fixes.
    bscan_rows : int
        B-scan rows the chain keeps (the newest).
    history_s : float
        The chain's per-ping rows kept (s before the newest ping; module doc): the final result of a longer run is
        that of the last ``history_s``.
    """

    def __init__(self, settings, header: StreamHeader, *, nav=None, source_tow_m: float | None = None,
                 array_tow_m: float | None = None, bscan_rows: int = 32, history_s: float = 3600.0):
        from sonartrack.acoustics.active_beams import LineArray
        from sonartrack.core.errors import require
        from sonartrack.systems.active.contacts import ActiveGeometry
        from sonartrack.systems.active.run import geometry_of
        from sonartrack.systems.live.active_geometry import LiveGeometry
        from sonartrack.systems.live.navigation import LiveNavigation

        require(history_s > 0, f"history_s {history_s:g} s: give a positive history to keep")
        s = self.settings = settings.checked(int(header.channels))
        self.header, self.bscan_rows, self.history_s = header, int(bscan_rows), float(history_s)
        self.options = {"nav": nav, "source_tow_m": source_tow_m, "array_tow_m": array_tow_m,
                        "bscan_rows": self.bscan_rows, "history_s": self.history_s}
        self.array = LineArray(int(s.elements), float(s.spacing_m))
        self.front_end = s.front_end_settings()
        self.fixes = None if nav is not None else LiveNavigation(header.start_utc)
        if nav is not None:
            self.geometry = nav if isinstance(nav, ActiveGeometry) else geometry_of(nav)
        elif source_tow_m is not None and array_tow_m is not None:
            self.geometry = LiveGeometry(self.fixes, source_tow_m, array_tow_m)
        else:
            self.geometry = None  # no tow lengths: no geometry from the fixes (B-scan only, said)
        self.chain = None
        self.pending: deque[PingBlock] = deque()
        self.pings, self.last, self.said, self.newest = 0, None, set(), None
        self.shown: deque[dict] = deque(maxlen=self.bscan_rows)  # the B-scan updates sent (a restart's history)
        self.targets: dict | None = None  # the last target table sent
        self.lock = threading.RLock()

    def push_nav(self, fix: NavFix) -> list[dict]:
        """A navigation fix; the updates of the pings it lets run."""
        with self.lock:
            if self.fixes is None:
                return []
            self.fixes.push(fix)
            return self._drain()

    def push_ping(self, ping: PingBlock) -> list[dict]:
        """One ping: the updates of the pings that can run now (this one when the navigation covers it)."""
        from sonartrack.core.errors import require

        s = self.settings
        require(ping.samples.shape[0] == s.elements, f"ping {ping.ping} has {ping.samples.shape[0]} channels, the "
                                                     f"stream {s.elements}: give the pings of one array")
        with self.lock:
            if self.newest is not None and ping.transmit_time_s <= self.newest:
                return self._say("pings at or before one already taken are skipped (repeated, out of order, or a "
                                 "resumed stream's replay)")
            self.newest = float(ping.transmit_time_s)
            self.pending.append(ping)
            return self._drain()

    def finish(self):
        """At the end of the stream: the pings still waiting run on the navigation there is; the chain's
        ActiveResult (None when no ping was tracked) and the last updates."""
        from dataclasses import replace

        with self.lock:
            updates = self._drain(final=True) + [self._health(["the stream ended: the picture is final"], "ok")]
            if self.chain is None:
                return None, updates
            result, g = self.chain.result(), self.geometry
            return (replace(result, geometry=g.current()) if hasattr(g, "current") else result), updates

    def _covered(self, ping: PingBlock) -> bool:
        """Whether the navigation fixes the ping's geometry for good (a whole run's always does)."""
        g = self.geometry
        return g is not None and (g.covers(ping.transmit_time_s) if hasattr(g, "nav") else True)

    def _drain(self, final: bool = False) -> list[dict]:
        """Run the waiting pings in order: each once the navigation covers it, or a later ping has come (or the
        stream ended): then on what there is; without a way to a geometry (no tow lengths) at once."""
        out = []
        while self.pending:
            p = self.pending[0]
            covered, later = self._covered(p), len(self.pending) > 1 or final
            if not (covered or later or self.geometry is None):
                break
            if self.chain is None and self.settings.ping_interval_s is None and not later and \
                    self._trackable() is None:
                break  # the interval from the first two pings
            interval = (self.pending[1].transmit_time_s - p.transmit_time_s) if len(self.pending) > 1 else None
            self.pending.popleft()
            out += self._run(p, covered, interval)
        return out

    def _trackable(self) -> str | None:
        """Why the pings cannot be tracked now (None: they can)."""
        if self.geometry is None:
            return ("no tow lengths for the navigation (give the source's and the array's): pings on the B-scan "
                    "only, not tracked") if self.fixes is not None and len(self.fixes.fixes) else \
                "no navigation: pings on the B-scan only, not tracked"
        if hasattr(self.geometry, "current") and self.geometry.current() is None:
            return "no navigation yet: pings on the B-scan only, not tracked"
        return None

    def _run(self, ping: PingBlock, covered: bool, interval: float | None) -> list[dict]:
        why = self._trackable()
        if why is None and self.chain is None:
            why = self._start(ping, interval)
        self.pings += 1
        if why is not None:
            return self._bscan_only(ping) + self._say(why)
        late = "navigation late: pings run on the last fixes (coasting)"
        out = self._tracked(ping)
        said = self._say(late) if not covered else []
        return out + (said or [self._health([], "ok" if covered else "coasting")])

    def _start(self, ping: PingBlock, interval: float | None) -> str | None:
        """Build the chain at its first ping (checked as the file chain checks its table); why not (None: built)."""
        from sonartrack.systems.active.checks import check_memory, check_spacing
        from sonartrack.systems.active.run import _Chain

        s = self.settings
        period = s.ping_interval_s if s.ping_interval_s is not None else interval
        if period is None and (s.detector == "mftd" or s.false_tracks_per_h is not None):
            return "a single ping has no ping interval for the MFTD: on the B-scan only"
        table = _table_of(ping)
        check_spacing(s, table)
        check_memory(s, table, period if s.detector == "mftd" else None)
        self.chain = _Chain(self.geometry, s, cw=ping.kind == "cw", period_s=period if s.detector == "mftd" else None,
                            scan_interval_s=period, bscan_rows=self.bscan_rows, history_s=self.history_s)
        return None

    def _tracked(self, ping: PingBlock) -> list[dict]:
        from sonartrack.systems.active.run import _bscan_axis

        c, g, s = self.chain, self.geometry, self.settings
        n_before = c.n_detections
        cells = c.ping(int(ping.ping), float(ping.transmit_time_s), np.asarray(ping.samples), _waveform(ping),
                       float(ping.fs_hz))
        t = float(ping.transmit_time_s)
        range_m = 0.5 * s.sound_speed_mps * _bscan_axis(np.asarray(cells.delay_s, float), s.bscan_bins)
        tracks = c.tracker.result()
        bscan = au.bscan_update(t, ping.ping, cells.cone_deg, range_m, c.bscan[-1], c.n_detections - n_before)
        bscan["tracks"] = au.scan_tracks(tracks, g, t)
        self.last = bscan
        self.shown.append(bscan)
        ship = g.ship_at(t) if hasattr(g, "ship_at") else None
        aperture = (int(s.elements) - 1) * float(s.spacing_m)
        self.targets = au.active_targets_update(t, ping.ping, tracks, g)
        return [au.active_ownship_update(t, g, ship, aperture), bscan, self.targets]

    def _bscan_only(self, ping: PingBlock) -> list[dict]:
        """A ping's B-scan without tracking: its front end for a platform at rest (no navigation)."""
        from sonartrack.detection.cells import detect_ping, detection_threshold, ping_front_end
        from sonartrack.detection.cw_cells import cw_ping_cells, cw_threshold
        from sonartrack.systems.active.run import _bscan_axis, _bscan_row

        s, x, w = self.settings, np.asarray(ping.samples), _waveform(ping)
        if w.kind != "cw":
            cells = ping_front_end(x, ping.fs_hz, w, self.array, self.front_end, time_s=ping.transmit_time_s,
                                   ping=ping.ping)
            threshold = detection_threshold(self.front_end)
        else:
            cells = cw_ping_cells(x, ping.fs_hz, w, self.array, self.front_end, s.cw, time_s=ping.transmit_time_s,
                                  ping=ping.ping, motion=(0.0, np.zeros(2), np.zeros(2)))
            threshold = cw_threshold(s.pfa, s.cw)
        detections = detect_ping(cells, threshold)
        range_m = 0.5 * s.sound_speed_mps * _bscan_axis(np.asarray(cells.delay_s, float), s.bscan_bins)
        self.last = au.bscan_update(ping.transmit_time_s, ping.ping, cells.cone_deg, range_m,
                                    _bscan_row(cells.statistic, s.bscan_bins), len(detections))
        self.shown.append(self.last)
        return [self.last]

    def history(self) -> list[dict]:
        """The display's history (a client that joins, or the chain restored): the B-scan updates kept and the
        last target table."""
        with self.lock:
            return list(self.shown) + ([self.targets] if self.targets is not None else [])

    def checkpoint(self, path):
        """Write the chain's state to ``path`` (systems/live/checkpoint.py, atomically); returns the path."""
        from sonartrack.systems.live.checkpoint import write_active_checkpoint

        with self.lock:
            return write_active_checkpoint(self, path)

    @classmethod
    def restore(cls, path) -> LiveActive:
        """The chain of a checkpoint file :meth:`checkpoint` wrote (InputError when it is not one)."""
        from sonartrack.systems.live.checkpoint import read_active_checkpoint

        return read_active_checkpoint(cls, path)

    def _say(self, why: str) -> list[dict]:
        """A health update with ``why``, once per reason."""
        if why in self.said:
            return []
        self.said.add(why)
        return [self._health([why], "coasting" if "late" in why else ("ok" if self.chain is not None else "none"))]

    def _health(self, events: list[str], nav: str) -> dict:
        """The stream's health at the last ping (LIVE.md; no sample rate or latency for pings)."""
        t = self.last["t_s"] if self.last else 0.0
        return {"type": "health", "t_s": t, "rate_hz": None, "latency_s": None, "gaps": 0, "events": events,
                "nav": nav}


def _waveform(ping: PingBlock):
    from sonartrack.acoustics.matched_filter import Waveform

    return Waveform(ping.kind, ping.duration_s, ping.fc_hz, ping.bandwidth_hz)


def _table_of(ping: PingBlock):
    """A one-row PingTable of a ping (the file chain's checks take a table)."""
    from sonartrack.systems.active.records import PingTable

    n = np.asarray(ping.samples).shape[1]
    return PingTable(np.array([ping.ping]), np.array([ping.transmit_time_s]), np.array([""]), np.array([ping.kind]),
                     np.array([ping.fc_hz]), np.array([ping.bandwidth_hz]), np.array([ping.duration_s]),
                     np.array([ping.fs_hz]), np.array([ping.samples.shape[0]]), np.array([n]))
