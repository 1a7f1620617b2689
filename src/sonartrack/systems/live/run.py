"""The live loop: a sample source and a navigation source in, display updates out, the slow stages on a schedule.

:func:`run_live` reads the sample source on the calling thread (each block's updates published at once), the
navigation source on a thread of its own (fixes handed to the chain under its lock), and runs
:meth:`~sonartrack.systems.live.passive.LivePassive.refresh` on a worker thread every ``refresh_s`` -- or, when a
refresh takes longer than a tenth of that, every ten refresh times, so that the slow stages never take more than
about a tenth of a core from the windows. With ``checkpoint`` the chain starts from that file when it exists (its
display history published first) and writes it every ``checkpoint_s`` and at the end (Ctrl-C included: the
caller's ``stop`` event, or KeyboardInterrupt). A stream's pings go to the active chain (systems/live/active.py,
built at the first ping; the navigation's fixes go to it as well), whose result is returned for a stream of pings
alone. The active chain's checkpoint is ``checkpoint`` + ".active" beside the passive one (:func:`active_checkpoint`),
written on the same schedule and at Ctrl-C; the same command resumes it at the stream's first ping (its B-scan
rows and target table published first; pings the checkpoint already holds are skipped).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from functools import partial
from pathlib import Path

from sonartrack.io.stream.types import NavFix, PingBlock, SampleBlock, StreamEvent
from sonartrack.systems.live.passive import LivePassive
from sonartrack.systems.passive.chain import PassiveResult
from sonartrack.systems.passive.settings import PassiveSettings

#: a refresh may take this share of the time between refreshes at most (the schedule stretches)
REFRESH_SHARE = 0.1
#: events kept from before the passive chain is built (its first sample block)
EARLY_EVENTS = 20


def _nav_thread(nav, live_ref: list, publish, stop: threading.Event, active=None) -> threading.Thread | None:
    """Read the navigation source on a thread: fixes to the chains (the passive once built; the active's kept
    until its first ping), events to the health."""
    if nav is None:
        return None

    def run():
        for item in nav:
            if stop.is_set():
                break
            if isinstance(item, NavFix) and active is not None:
                for u in active.push_nav(item):
                    publish(u)
            live = live_ref[0]
            if live is None:
                continue
            if isinstance(item, NavFix):
                live.push_nav(item)
            elif isinstance(item, StreamEvent):
                for u in live.note(item):
                    publish(u)

    th = threading.Thread(target=run, name="live-nav", daemon=True)
    th.start()
    return th


def _refresh_thread(live: LivePassive, publish, refresh_s: float, stop: threading.Event) -> threading.Thread:
    """Refresh the targets on a schedule (module doc)."""
    def run():
        wait = refresh_s
        while not stop.wait(wait):
            t0 = time.perf_counter()
            try:
                updates = live.refresh()
            except Exception as exc:  # noqa: BLE001 - a failed refresh must not end the live run: said, and retried
                updates = live.note(StreamEvent("refresh_failed", f"targets not refreshed ({type(exc).__name__}: "
                                                                  f"{exc}); the stream goes on"))
            for u in updates:
                publish(u)
            wait = max(refresh_s, (time.perf_counter() - t0) / REFRESH_SHARE)

    th = threading.Thread(target=run, name="live-refresh", daemon=True)
    th.start()
    return th


def warm_up(settings: PassiveSettings, windows: int = 12) -> float:
    """Run a throwaway chain on a few windows of a synthetic plane wave (8 channels, 2 kHz, fixes of a straight
    course), so that the imports, the compiled kernels' loading, the map projection's database and the first calls'
    set-up are done before the stream starts: without it the first windows of a live run reached the screen 2-5 s
    late (benchmarks/bench_live_latency.py). Returns the seconds it took."""
    from datetime import UTC, datetime, timedelta

    import numpy as np

    from sonartrack.io.stream.types import StreamHeader

    t0 = time.perf_counter()
    channels, fs, start = 8, 2000.0, datetime(2000, 1, 1, tzinfo=UTC)
    live = LivePassive(settings, StreamHeader(channels, fs, "float32", start),
                       history_s=max(60.0, settings.window_s))
    for k in range(int(windows * settings.window_s) + 3):
        live.push_nav(NavFix(start + timedelta(seconds=k), 54.0, 11.0 + 5e-5 * k, 90.0, 3.0))
    rng = np.random.default_rng(0)
    n = int(round(windows * settings.window_s * fs))
    f = np.fft.rfftfreq(n, 1.0 / fs)
    delay = np.arange(channels) * settings.spacing_m * np.cos(np.deg2rad(60.0)) / 1500.0  # a broadband plane wave
    phase = np.exp(-2j * np.pi * f[None, :] * delay[:, None])
    wave = np.fft.irfft(np.fft.rfft(rng.standard_normal(n))[None, :] * phase, n, axis=1)
    x = rng.standard_normal((n, channels)) + 3.0 * wave.T
    try:
        live.push_block(SampleBlock(0, x.astype(np.float32)))
        live.select(1)
        live.refresh()
    finally:
        live.close()
    return time.perf_counter() - t0


def _build(samples, settings, checkpoint, options) -> tuple[LivePassive, bool]:
    """The chain: restored from ``checkpoint`` when that file exists, else new on the source's header."""
    if checkpoint is not None and Path(checkpoint).is_file():
        return LivePassive.restore(checkpoint), True
    return LivePassive(settings, samples.header, **options), False


def run_live(samples, nav, settings: PassiveSettings, publish: Callable[[dict], None], *, refresh_s: float = 10.0,
             checkpoint=None, stop: threading.Event | None = None, checkpoint_s: float = 60.0,
             ready: Callable[[LivePassive], None] | None = None, warm: bool = True, active_settings=None,
             active_options: dict | None = None, **options):
    """Run the live chain until the sample source ends or ``stop`` is set (module doc).

    Parameters
    ----------
    samples : iterable
        The sample source (io/stream): ``header`` (known once it yields), SampleBlock and StreamEvent items.
    nav : iterable, Navigation or None
        The navigation source (NavFix and StreamEvent items), or a known Navigation (a finished recording replayed
        with its navigation table), or None.
    settings : PassiveSettings
        The chain's settings.
    publish : callable
        Takes each display update (thread-safe: called from this thread and the refresh and navigation threads).
    refresh_s : float
        Seconds between refreshes of the targets.
    checkpoint, checkpoint_s : path and float, optional
        Checkpoint file (module doc), and the seconds between checkpoints.
    stop : threading.Event, optional
        Set to end the run (the result is still made).
    ready : callable, optional
        Called with the chain once it is built (the console hooks its track selection there: ``live.select``).
    warm : bool
        Run :func:`warm_up` before the sample source is read (a TCP source connects when read).
    active_settings, active_options : ActiveSettings and dict, optional
        For the stream's pings (systems/live/active.py; default: the defaults with the passive spacing), LiveActive's
        keywords (source_tow_m, array_tow_m: the pings' geometry from the navigation's fixes).
    **options
        LivePassive's keywords (history_s, tow_length_m, nav_timeout_s).

    Returns
    -------
    PassiveResult, ActiveResult or None
        The passive chain's result (a stream of pings alone: the active chain's); None before one window (ping).
    """
    from sonartrack.io.navigation import Navigation

    if isinstance(nav, Navigation):
        nav, options = None, {**options, "nav": nav}
    stop = stop or threading.Event()
    if warm:
        warm_up(settings)
    done, live_ref = threading.Event(), [None]
    active = _ActivePings(settings, active_settings, active_options or {}, active_checkpoint(checkpoint))
    threads = [_nav_thread(nav, live_ref, publish, done, active)]
    start = partial(_start, samples, settings, checkpoint, options, live_ref, publish, refresh_s, done, ready)
    try:
        _read(samples, stop, live_ref, start, threads, publish, active, (checkpoint, checkpoint_s))
    except BaseException as exc:
        _stop(done, threads)
        if isinstance(exc, KeyboardInterrupt) and checkpoint is not None:
            _keep(checkpoint, active, live_ref[0])  # Ctrl-C keeps the state: the same command resumes from here
        raise
    _stop(done, threads)
    active.checkpoint()
    pinged, result = active.finish(publish), _end(live_ref[0], checkpoint, publish)
    return pinged if live_ref[0] is None and pinged is not None else result


def _read(samples, stop, live_ref: list, start, threads: list, publish, active, checkpointing) -> None:
    """The sample source's items through the chains until it ends or ``stop`` is set: pings to the active chain,
    the rest to the passive chain, built (``start``) at the first sample block (a stream of pings alone never builds
    it: its rate is a baseband's); events before then kept (the last few) for it. Checkpoints on their schedule."""
    checkpoint, checkpoint_s = checkpointing
    early = []
    for item in samples:
        if stop.is_set():
            break
        if isinstance(item, PingBlock):
            for u in active.push(item, samples.header):
                publish(u)
            if checkpoint is not None and time.monotonic() - active.saved > checkpoint_s:
                active.checkpoint()
            continue
        if live_ref[0] is None and not isinstance(item, SampleBlock):
            early = [*early[-EARLY_EVENTS + 1:], item]  # a TCP source's events before its first block
            continue
        if live_ref[0] is None:
            threads.append(start())
        for it in [*early, item]:
            _take(live_ref[0], it, publish)
        early = []
        if checkpoint is not None and time.monotonic() - live_ref[1] > checkpoint_s:
            live_ref[0].checkpoint(checkpoint)
            live_ref[1] = time.monotonic()


def _keep(checkpoint, active, live: LivePassive | None) -> None:
    """Write both chains' checkpoints (those built)."""
    active.checkpoint()
    if live is not None:
        live.checkpoint(checkpoint)


def _stop(done: threading.Event, threads: list) -> None:
    """End the navigation and refresh threads (each given 5 s to finish what it is doing)."""
    done.set()
    for th in threads:
        if th is not None:
            th.join(timeout=5.0)


def _start(samples, settings, checkpoint, options, live_ref: list, publish, refresh_s: float, done, ready):
    """Build the chain (restored: its display history published), start its refresh thread (returned)."""
    live, restored = _build(samples, settings, checkpoint, options)
    live_ref[:] = [live, time.monotonic()]
    for u in live.history() if restored else []:
        publish(u)
    if ready is not None:
        ready(live)
    return _refresh_thread(live, publish, refresh_s, done)


def active_checkpoint(checkpoint) -> Path | None:
    """The active chain's checkpoint file beside the passive chain's ``checkpoint`` (None: none)."""
    return None if checkpoint is None else Path(str(checkpoint) + ".active")


class _ActivePings:
    """The stream's pings to the active chain (systems/live/active.py), built at the first ping (restored from
    ``checkpoint`` when that file exists: its display history published first); the navigation's fixes kept until
    then (the newest ``KEPT_FIXES``), then given to it."""

    KEPT_FIXES = 7200

    def __init__(self, settings: PassiveSettings, active_settings, options: dict, checkpoint: Path | None = None):
        self.settings, self.active_settings, self.options, self.chain = settings, active_settings, options, None
        self.fixes: deque = deque(maxlen=self.KEPT_FIXES)
        self.lock = threading.Lock()
        self.path, self.saved = checkpoint, time.monotonic()

    def push(self, ping, header) -> list[dict]:
        with self.lock:
            if self.chain is None:
                from sonartrack.systems.active.settings import ActiveSettings
                from sonartrack.systems.live.active import LiveActive

                out = []
                if self.path is not None and self.path.is_file():
                    self.chain = LiveActive.restore(self.path)
                    out = self.chain.history()
                else:
                    s = self.active_settings or ActiveSettings(spacing_m=self.settings.spacing_m)
                    self.chain = LiveActive(s, header, **self.options)
                out += [u for fix in self.fixes for u in self.chain.push_nav(fix)]
                self.fixes.clear()
                return out + self.chain.push_ping(ping)
        return self.chain.push_ping(ping)

    def checkpoint(self) -> None:
        """Write the active chain's checkpoint (with a file given and a chain built)."""
        if self.path is not None and self.chain is not None:
            self.chain.checkpoint(self.path)
            self.saved = time.monotonic()

    def push_nav(self, fix) -> list[dict]:
        with self.lock:
            if self.chain is None:
                self.fixes.append(fix)
                return []
        return self.chain.push_nav(fix)

    def finish(self, publish):
        """The pings still waiting run; the active chain's result (None without one)."""
        if self.chain is None:
            return None
        result, updates = self.chain.finish()
        for u in updates:
            publish(u)
        return result


def _take(live: LivePassive, item, publish) -> None:
    """One item of the sample source through the passive chain, its updates published."""
    updates = live.push_block(item) if isinstance(item, SampleBlock) else \
        live.note(item) if isinstance(item, StreamEvent) else []
    for u in updates:
        publish(u)


def _end(live: LivePassive | None, checkpoint, publish) -> PassiveResult | None:
    """The last checkpoint, the final result and its targets."""
    if live is None:
        return None
    if checkpoint is not None:
        live.checkpoint(checkpoint)
    result = live.finish() if live.rows else None
    for u in live.refresh() if result is not None else []:
        publish(u)
    for u in live.note(StreamEvent("end", "the stream ended: the picture is final")):
        publish(u)
    return result
