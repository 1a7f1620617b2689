"""A recorder's sample stream over TCP: the live side connects, reads frames (io/stream/frames.py), and reconnects
with backoff when the connection drops.

:class:`TcpSampleSource` yields :class:`~sonartrack.io.stream.types.SampleBlock` in order and contiguous (the
blocks pass through io/stream/reorder.py: held within a small window, duplicates dropped, gaps and late blocks
named) and :class:`~sonartrack.io.stream.types.StreamEvent` for what happened on the wire: "connected",
"disconnected", "bad_frame", "gap", "duplicate", "late", "overlap", "refused", "gave_up".

The stream's header is the first connection's. A reconnect's header is compared with it: other channels, sample
rate or full scale is another recording, which the live chain cannot take in mid-run: the connection is refused
with an event saying so and retried with backoff (a recorder restarted with its former settings is taken again).
A reconnect whose header states another start time has its indices moved onto the first header's axis
(round((start' - start) rate) samples), so that its blocks follow the earlier ones. A connection that drops
without the end frame is a disconnect: the source reconnects after ``backoff_s``, doubling up to
``max_backoff_s``; it gives up (event "gave_up", end of iteration) after ``give_up_s`` without a connection, when
that is set. The end frame ends the iteration.
"""

from __future__ import annotations

import socket
import threading
import time

from sonartrack.core.errors import require
from sonartrack.io.stream._threaded import POLL_S, ThreadedSource
from sonartrack.io.stream.frames import FrameDecoder, StreamEnd
from sonartrack.io.stream.reorder import BlockReorderer
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader

#: bytes asked of the socket per read
RECV_BYTES = 1 << 16
#: first wait (s) before a reconnect, and the longest
BACKOFF_S, MAX_BACKOFF_S = 0.1, 5.0
#: longest wait (s) for a connection to be accepted
CONNECT_TIMEOUT_S = 2.0


class TcpSampleSource(ThreadedSource):
    """Sample blocks from a recorder's TCP stream (module doc); an iterator with ``header`` and ``close()``.

    Parameters
    ----------
    host, port : str, int
        The recorder's address (``sonartrack simulate --stream`` prints its port).
    reorder_blocks : int
        Blocks held to put out-of-order ones back in order (io/stream/reorder.py).
    reorder_s : float
        Longest time (s) a block is held waiting for an earlier one before the gap is declared.
    backoff_s, max_backoff_s : float
        First and longest wait (s) between connection attempts.
    give_up_s : float, optional
        End the iteration after this long (s) without a connection (None: retry for ever).
    """

    _name = "tcp-source"

    def __init__(self, host: str, port: int, *, reorder_blocks: int = 8, reorder_s: float = 1.0,
                 backoff_s: float = BACKOFF_S, max_backoff_s: float = MAX_BACKOFF_S, give_up_s: float | None = None):
        super().__init__()
        require(0 < int(port) < 65536, f"TCP port {port}: give the recorder's port, 1..65535")
        require(backoff_s > 0 and max_backoff_s >= backoff_s, "backoff_s must be > 0 and <= max_backoff_s")
        self.host, self.port = host, int(port)
        self.address = f"tcp://{host}:{int(port)}"
        self.header: StreamHeader | None = None
        self.header_ready = threading.Event()
        self._reorder = BlockReorderer(reorder_blocks, reorder_s)
        self._backoff = (float(backoff_s), float(max_backoff_s))
        self._give_up_s = give_up_s
        self._offset = 0

    def wait_header(self, timeout_s: float | None = None) -> StreamHeader | None:
        """The stream's header once the first one has arrived (starts the reader if needed).

        Parameters
        ----------
        timeout_s : float, optional
            Longest wait (s); None waits until the header arrives or the source is closed.

        Returns
        -------
        StreamHeader or None
            None when it did not arrive in time.
        """
        self.start()
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not self.header_ready.wait(POLL_S):
            if self._stop.is_set() or not self.alive or (deadline is not None and time.monotonic() > deadline):
                return self.header
        return self.header

    def _run(self) -> None:
        wait, down_since = self._backoff[0], time.monotonic()
        while not self._stop.is_set():
            sock = self._connect()
            if sock is None:
                if self._give_up_s is not None and time.monotonic() - down_since > self._give_up_s:
                    self._put(StreamEvent("gave_up", f"{self.address}: no connection for {self._give_up_s:g} s: "
                                                     "the live input stops"))
                    break
                self._stop.wait(wait)
                wait = min(2 * wait, self._backoff[1])
                continue
            self._put(StreamEvent("connected", f"{self.address}: connected"))
            with sock:
                how = self._session(sock)
            if how == "end":
                break
            down_since = time.monotonic()
            if how == "refused":  # the same recorder again soon: wait longer each time
                self._stop.wait(wait)
                wait = min(2 * wait, self._backoff[1])
            else:
                wait = self._backoff[0]
            if not self._stop.is_set():
                self._put(StreamEvent("disconnected", f"{self.address}: connection lost; reconnecting"))
        for item in self._reorder.drain():
            self._put(item)

    def _connect(self) -> socket.socket | None:
        try:
            sock = socket.create_connection((self.host, self.port), timeout=CONNECT_TIMEOUT_S)
        except OSError:
            return None
        sock.settimeout(POLL_S)
        return sock

    def _session(self, sock: socket.socket) -> str:
        """Read one connection until it drops ("lost"), sends the end frame ("end") or a header that is not the
        stream's ("refused")."""
        decoder = FrameDecoder(self.address)
        while not self._stop.is_set():
            try:
                data = sock.recv(RECV_BYTES)
            except TimeoutError:
                self._put_all(self._reorder.expire())
                continue
            except OSError:
                data = b""
            if not data:
                self._put_all(decoder.flush())
                return "lost"
            for item in decoder.feed(data):
                verdict = self._take(item)
                if verdict is not None:
                    return verdict
            self._put_all(self._reorder.expire())
        return "lost"

    def _take(self, item) -> str | None:
        """Handle one decoded item; "end" at the end frame, "refused" to drop the connection, None to go on."""
        if isinstance(item, SampleBlock):
            self._put_all(self._reorder.push(SampleBlock(item.first_index + self._offset, item.samples)))
        elif isinstance(item, StreamHeader):
            return self._take_header(item)
        elif isinstance(item, StreamEnd):
            return "end"
        else:
            self._put(item)
        return None

    def _take_header(self, h: StreamHeader) -> str | None:
        first = self.header
        if first is None:
            self.header = StreamHeader(h.channels, h.rate_hz, h.sample_format, h.start_utc, h.full_scale_v,
                                       self.address)
            self.header_ready.set()
            return None
        if (h.channels, h.rate_hz, h.full_scale_v) != (first.channels, first.rate_hz, first.full_scale_v):
            self._put(StreamEvent("refused", f"{self.address}: the recorder now sends {h.channels} channels at "
                                             f"{h.rate_hz:g} Hz (full scale {h.full_scale_v}), not the stream's "
                                             f"{first.channels} at {first.rate_hz:g} Hz (full scale "
                                             f"{first.full_scale_v}): connection refused; restart the live run for "
                                             "the new settings"))
            return "refused"
        self._offset = round((h.start_utc - first.start_utc).total_seconds() * first.rate_hz)
        return None

    def _put_all(self, items) -> None:
        for item in items:
            self._put(item)
