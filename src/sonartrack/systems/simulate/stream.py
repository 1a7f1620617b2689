"""A passive scene played as a recorder plays it (``sonartrack simulate --stream``): its samples over TCP in the
framing of io/stream/frames.py, the ship's navigation as NMEA 0183 over UDP, at real time x ``speed``.

The server listens on ``host:port`` (127.0.0.1 by default; port 0 picks a free one, :attr:`SceneStreamer.port`)
and waits for the live side to connect: the scene's clock starts at the first connection, so nothing is lost
to a console started a moment later. Every connection gets the header (channels = the array's elements, the
scene's sample rate, float32 samples in pascals: full scale not stated, UTC start = the layout's start time)
and then the blocks from the scene's current position, as a recorder's live output: one that reconnects
misses what was sent meanwhile (the live side names it as a gap). A block of ``block_s`` seconds is sent when
its last sample is due, t0 + (first + n) / (rate x speed); at the end every connection gets the end frame.

The samples are those ``simulate`` writes to recording.wav for the same scene and seed: the same blocks of the
same generator (run.py :meth:`PassiveSimulation.recording_blocks`), cast to float32 as the WAV writer casts them.
Navigation: per second of nav.csv's ownship, GGA, RMC and HDT (one sentence a datagram) to ``udp://host:nav_udp``,
positions through recording_layout.py's projection about :data:`~recording_layout.ORIGIN_DEG` (what
``--nmea``'s nav.nmea holds), sent when their time is due.

Active pings (``--kind active --stream``, :class:`ActiveSceneStreamer`): the header states the array's elements
and the baseband rate; each ping goes as one ping frame (io/stream/frames.py, kind 4: its listening window as
complex64, number, transmit time and pulse) when its window is complete, transmit time + T; the samples are those
``simulate --kind active`` writes to ping_NNNN.npy (the same generator, child stream k for ping k); the ownship's
NMEA as for the passive scene, from nav.csv's ownship columns.
"""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass
from datetime import datetime

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.stream.frames import encode_block, encode_end, encode_header, encode_ping
from sonartrack.io.stream.types import PingBlock, SampleBlock, StreamHeader
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.systems.simulate.recording_layout import ORIGIN_DEG, START_UTC

#: seconds of samples per data frame (0.1 s: a window's last sample reaches the live side within 0.1 s)
BLOCK_S = 0.1
#: longest wait (s) for a slow client to take a frame before it is dropped
SEND_TIMEOUT_S = 5.0
#: how often (s) the server looks for a new connection or a stop while it waits
_POLL_S = 0.05


@dataclass(frozen=True, slots=True)
class StreamSummary:
    """What was streamed: seconds of the scene, data frames, connections served, NMEA sentences sent."""

    seconds: float
    blocks: int
    connections: int
    sentences: int


def nav_sentences(nav: dict, start_utc: datetime) -> list[tuple[float, list[str]]]:
    """The ownship's NMEA sentences per fix: (time since the start (s), [RMC, GGA, HDT]).

    Parameters
    ----------
    nav : dict of str to ndarray
        time_s, x_m, y_m, heading_deg (m east and north of :data:`ORIGIN_DEG`).
    start_utc : datetime
        UTC time of time_s = 0.

    Returns
    -------
    list of (float, list of str)
        Each fix's time (s) and its sentences, ``$...*hh`` with checksums.
    """
    from sonartrack.io.nmea import LocalProjection, _degrees_minutes, nmea_checksum, nmea_lines

    t, x, y, h = (np.asarray(nav[k], float) for k in ("time_s", "x_m", "y_m", "heading_deg"))
    lat, lon = LocalProjection(*ORIGIN_DEG).latlon(x, y)
    vx, vy = (np.gradient(v, t) for v in (x, y)) if t.size > 1 else (np.zeros_like(t), np.zeros_like(t))
    unix = start_utc.timestamp() + t
    lines = nmea_lines(unix, lat, lon, h, np.hypot(vx, vy) * 3600.0 / 1852.0, np.rad2deg(np.arctan2(vx, vy)) % 360)
    out = []
    for k in range(t.size):
        rmc, hdt = lines[2 * k], lines[2 * k + 1]
        body = (f"GPGGA,{rmc.split(',')[1]},{_degrees_minutes(lat[k], 2, 'NS')},{_degrees_minutes(lon[k], 3, 'EW')},"
                "1,08,1.0,0.0,M,0.0,M,,")
        out.append((float(t[k]), [rmc, f"${body}*{nmea_checksum(body):02X}", hdt]))
    return out


class SceneStreamer:
    """The scene's samples on a TCP server and its navigation over UDP (module doc).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The passive scene.
    port : int
        TCP port to listen on (0: a free one, then :attr:`port`).
    nav_udp : int, optional
        UDP port the NMEA sentences go to (None: no navigation sent).
    speed : float
        Real time x speed (> 0).
    start_utc : datetime
        UTC time of the first sample.
    host : str
        Address to listen on and send the NMEA to (loopback by default).
    block_s : float
        Seconds per data frame.
    """

    def __init__(self, scene: PassiveSceneSettings, *, port: int = 0, nav_udp: int | None = None, speed: float = 1.0,
                 start_utc: datetime = START_UTC, host: str = "127.0.0.1", block_s: float = BLOCK_S):
        require(np.isfinite(speed) and speed > 0, f"--speed {speed:g}: give a positive factor (1 = real time)")
        require(0 <= int(port) < 65536, f"--port {port}: give 0 (any free port) or 1..65535")
        require(nav_udp is None or 0 < int(nav_udp) < 65536, f"--nav-udp {nav_udp}: give a UDP port, 1..65535")
        self.scene, self.speed, self.host, self.nav_udp = scene, float(speed), host, nav_udp
        self.frames_per_block = max(1, round(block_s * scene.sample_rate_hz))
        self.header = StreamHeader(scene.array.elements, float(scene.sample_rate_hz), "float32", start_utc, None)
        self._listener = socket.create_server((host, int(port)))
        self._listener.settimeout(_POLL_S)
        self.port = self._listener.getsockname()[1]
        self._clients: list[socket.socket] = []
        self._connections = 0

    def close(self) -> None:
        """Close the listening socket and every connection."""
        for c in self._clients:
            c.close()
        self._clients.clear()
        self._listener.close()

    def serve(self, stop: threading.Event | None = None, store=None) -> StreamSummary:
        """Wait for the first connection, then play the scene to the end (or until ``stop`` is set).

        Parameters
        ----------
        stop : threading.Event, optional
            Set to end the stream early.
        store : FieldStore, optional
            Cache of RAM transmission-loss fields.

        Returns
        -------
        StreamSummary
            Seconds and frames sent, connections served, sentences sent.
        """
        from sonartrack.systems.simulate.run import simulate_passive

        stop = stop or threading.Event()
        sim = simulate_passive(self.scene, store)
        fixes = nav_sentences(sim.nav, self.header.start_utc) if self.nav_udp is not None else []
        try:
            while not self._clients and not stop.is_set():
                self._accept()
            self._listener.setblocking(False)  # later connections are picked up between blocks, without a wait
            sent = self._play(sim.recording_blocks(), fixes, stop)
        finally:
            self.close()
        return StreamSummary(sent[0] / self.scene.sample_rate_hz, sent[1], self._connections, sent[2])

    def _play(self, blocks, fixes, stop: threading.Event) -> tuple[int, int, int]:
        """Send the blocks and the sentences as they fall due; (samples, frames, sentences) sent."""
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM) if fixes else None
        fs, t0 = self.scene.sample_rate_hz, time.monotonic()
        index = frames = k_fix = 0
        try:
            for block in blocks:
                x = np.asarray(block).T.astype(np.float32)  # as the WAV writer casts (io/wav_writer.py)
                for a in range(0, x.shape[0], self.frames_per_block):
                    part = x[a:a + self.frames_per_block]
                    end_s = (index + part.shape[0]) / fs
                    k_fix = self._send_nav(udp, fixes, k_fix, end_s)
                    if stop.wait(max(0.0, t0 + end_s / self.speed - time.monotonic())):
                        return index, frames, 3 * k_fix
                    self._accept()
                    self._broadcast(encode_block(SampleBlock(index, part), "float32"))
                    index, frames = index + part.shape[0], frames + 1
            k_fix = self._send_nav(udp, fixes, k_fix, np.inf)
            self._broadcast(encode_end(index))
        finally:
            if udp is not None:
                udp.close()
        return index, frames, 3 * k_fix

    def _send_nav(self, udp, fixes, k: int, until_s: float) -> int:
        while k < len(fixes) and fixes[k][0] <= until_s:
            for line in fixes[k][1]:
                udp.sendto((line + "\r\n").encode("ascii"), (self.host, int(self.nav_udp)))
            k += 1
        return k

    def _accept(self) -> None:
        try:
            conn, _ = self._listener.accept()
        except (TimeoutError, BlockingIOError):
            return
        except OSError as exc:
            raise InputError(f"the stream's server on {self.host}:{self.port} failed ({exc})") from None
        conn.settimeout(SEND_TIMEOUT_S)
        try:
            conn.sendall(encode_header(self.header))
        except OSError:
            conn.close()
            return
        self._clients.append(conn)
        self._connections += 1

    def _broadcast(self, frame: bytes) -> None:
        for c in list(self._clients):
            try:
                c.sendall(frame)
            except OSError:  # the client went away or stalled: a recorder goes on without it
                c.close()
                self._clients.remove(c)


class ActiveSceneStreamer(SceneStreamer):
    """An active scene's pings on a TCP server as ping frames and its navigation over UDP (module doc).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The active scene.
    port, nav_udp, speed, start_utc, host
        As :class:`SceneStreamer`.
    """

    def __init__(self, scene, *, port: int = 0, nav_udp: int | None = None, speed: float = 1.0,
                 start_utc: datetime = START_UTC, host: str = "127.0.0.1"):
        require(np.isfinite(speed) and speed > 0, f"--speed {speed:g}: give a positive factor (1 = real time)")
        require(0 <= int(port) < 65536, f"--port {port}: give 0 (any free port) or 1..65535")
        require(nav_udp is None or 0 < int(nav_udp) < 65536, f"--nav-udp {nav_udp}: give a UDP port, 1..65535")
        self.scene, self.speed, self.host, self.nav_udp = scene, float(speed), host, nav_udp
        self.header = StreamHeader(scene.sonar.elements, float(scene.sample_rate_hz), "float32", start_utc, None)
        self._listener = socket.create_server((host, int(port)))
        self._listener.settimeout(_POLL_S)
        self.port = self._listener.getsockname()[1]
        self._clients, self._connections = [], 0

    def serve(self, stop: threading.Event | None = None, store=None) -> StreamSummary:
        """Wait for the first connection, then play the pings to the end (or until ``stop`` is set); the summary's
        ``blocks`` are the pings sent."""
        from sonartrack.sim.active_scene import nav_columns, ping_geometry, platforms, transmission_loss_model

        stop = stop or threading.Event()
        sc = self.scene
        t_nav = np.arange(0.0, np.floor(sc.duration_s) + 1.0)
        fixes = nav_sentences(nav_columns(platforms(sc, t_nav)), self.header.start_utc) if self.nav_udp else []
        tl, plat = transmission_loss_model(sc, store), ping_geometry(sc)
        try:
            while not self._clients and not stop.is_set():
                self._accept()
            self._listener.setblocking(False)
            pings, sentences = self._play_pings(tl, plat, fixes, stop)
        finally:
            self.close()
        return StreamSummary(pings * sc.ping_interval_s, pings, self._connections, sentences)

    def _play_pings(self, tl, plat, fixes, stop: threading.Event) -> tuple[int, int]:
        """Send each ping when its listening window is complete, the sentences as they fall due; (pings,
        sentences) sent."""
        from sonartrack.core.random import trial_rng
        from sonartrack.sim.active_signals import ping_samples

        sc, w = self.scene, self.scene.waveform
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM) if fixes else None
        t0, k_fix, sent = time.monotonic(), 0, 0
        try:
            for k, t_tx in enumerate(sc.ping_times_s):
                x = ping_samples(sc, plat, k, tl, trial_rng(sc.seed, k))  # before its time: it takes a while
                due = float(t_tx) + sc.samples_per_ping / sc.sample_rate_hz
                k_fix = self._send_nav(udp, fixes, k_fix, due)
                if stop.wait(max(0.0, t0 + due / self.speed - time.monotonic())):
                    return sent, 3 * k_fix
                self._accept()
                self._broadcast(encode_ping(PingBlock(k + 1, float(t_tx), float(w.carrier_hz),
                                                      float(w.bandwidth_hz) if w.kind == "lfm" else 0.0,
                                                      float(w.duration_s), float(sc.sample_rate_hz), x)))
                sent += 1
            k_fix = self._send_nav(udp, fixes, k_fix, np.inf)
            self._broadcast(encode_end(0))
        finally:
            if udp is not None:
                udp.close()
        return sent, 3 * k_fix
