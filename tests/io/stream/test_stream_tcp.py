"""TcpSampleSource against a tiny scripted server on loopback: reconnect after the server drops, duplicate,
out-of-order and late blocks, a reconnect with another header refused, and close() ending the thread."""

from __future__ import annotations

import socket
import threading
from datetime import UTC, datetime, timedelta

import numpy as np

from sonartrack.io.stream.frames import encode_block, encode_end, encode_header
from sonartrack.io.stream.tcp import TcpSampleSource
from sonartrack.io.stream.types import SampleBlock, StreamEvent, StreamHeader

START = datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC)
HEADER = StreamHeader(2, 1000.0, "int16", START)


def _block(first: int, n: int = 10) -> bytes:
    x = (np.arange(first, first + n)[:, None] % 1000 / 1000.0).repeat(2, axis=1)
    return encode_block(SampleBlock(first, x), "int16")


class _Server:
    """Serves one scripted byte string per connection, then closes that connection."""

    def __init__(self, scripts: list[bytes]):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.scripts = scripts
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        with self.sock:
            for script in self.scripts:
                conn, _ = self.sock.accept()
                with conn:
                    conn.sendall(script)


def _collect(source, limit=200):
    out = []
    with source:
        for item in source:
            out.append(item)
            if len(out) >= limit:
                break
    assert not source.alive  # no thread outlives close()
    return out


def _describe(items):
    return [(i.kind, i.first_index, i.count) if isinstance(i, StreamEvent) else i.first_index for i in items
            if not (isinstance(i, StreamEvent) and i.kind in ("connected", "disconnected"))]


def test_reconnect_after_the_server_drops_and_the_gap_is_named():
    first = encode_header(HEADER) + _block(0) + _block(10) + _block(20)[:15]  # drops inside a frame
    second = encode_header(HEADER) + _block(40) + _block(50) + encode_end(60)
    server = _Server([first, second])
    items = _collect(TcpSampleSource("127.0.0.1", server.port, backoff_s=0.01, max_backoff_s=0.05))
    kinds = [i.kind for i in items if isinstance(i, StreamEvent)]
    assert kinds[:1] == ["connected"] and "disconnected" in kinds and kinds.count("connected") == 2
    assert "bad_frame" in kinds  # the frame cut short by the drop
    assert _describe(items) == [0, 10, ("bad_frame", None, None), ("gap", 20, 20), 40, 50]
    x = np.concatenate([i.samples for i in items if isinstance(i, SampleBlock)][:2])
    assert np.allclose(x[:, 0], np.arange(20) / 1000.0, atol=2**-15)


def test_duplicate_out_of_order_and_late_blocks():
    script = (encode_header(HEADER) + _block(0) + _block(20) + _block(10) + _block(10) + _block(30)
              + _block(50) + _block(60) + _block(70) + _block(40) + encode_end(80))
    server = _Server([script])
    source = TcpSampleSource("127.0.0.1", server.port, reorder_blocks=2, reorder_s=60.0)
    out = _describe(_collect(source))
    assert out == [0, 10, 20, ("duplicate", 10, 10), 30, ("gap", 40, 10), 50, 60, 70, ("late", 40, 10)]


def test_a_reconnect_with_another_header_is_refused_and_a_later_start_is_rebased():
    other = StreamHeader(3, 1000.0, "int16", START)
    later = StreamHeader(2, 1000.0, "int16", START + timedelta(seconds=1))  # its index 0 is our 1000
    scripts = [encode_header(HEADER) + _block(0),
               encode_header(other),
               encode_header(later) + _block(0) + encode_end(10)]
    server = _Server(scripts)
    items = _collect(TcpSampleSource("127.0.0.1", server.port, backoff_s=0.01, max_backoff_s=0.02))
    refused = [i for i in items if isinstance(i, StreamEvent) and i.kind == "refused"]
    assert len(refused) == 1 and "3 channels" in refused[0].detail and "restart" in refused[0].detail
    blocks = [i.first_index for i in items if isinstance(i, SampleBlock)]
    assert blocks == [0, 1000]


def test_close_while_nothing_is_listening_ends_the_thread():
    probe = socket.create_server(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # a port nobody listens on
    source = TcpSampleSource("127.0.0.1", port, backoff_s=0.01, max_backoff_s=0.02, give_up_s=0.2)
    items = _collect(source)
    assert [i.kind for i in items] == ["gave_up"]
