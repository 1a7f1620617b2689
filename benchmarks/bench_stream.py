"""Benchmark: the live input's decoder and TCP source (io/stream/), 16 channels x 4 kHz in 0.1 s blocks.

Throughput: the frame decoder alone (bytes fed in 64 KiB pieces, as a socket gives them) and the whole TCP source
(a loopback server sends pre-encoded frames as fast as the socket takes them; the source decodes, checks, orders
and queues them; the consumer counts), in MB/s of wire bytes, blocks/s and x real time of a 16 ch x 4 kHz stream
(float32: 256 kB/s; int24: 192 kB/s). Latency added by the source: a server sends one block every 10 ms with its
send time, the consumer notes when the source yields it (median and 99th percentile over 300 blocks).
"""

from __future__ import annotations

import socket
import threading
import time
from datetime import UTC, datetime

import numpy as np

from sonartrack.io.stream.frames import FrameDecoder, encode_block, encode_end, encode_header
from sonartrack.io.stream.tcp import TcpSampleSource
from sonartrack.io.stream.types import SampleBlock, StreamHeader

CHANNELS, FS, BLOCK = 16, 4000, 400
N_BLOCKS = 3000  # 300 s of stream


def _wire(fmt: str) -> tuple[StreamHeader, bytes, list[bytes]]:
    header = StreamHeader(CHANNELS, float(FS), fmt, datetime(2024, 5, 17, tzinfo=UTC))
    x = (0.1 * np.random.default_rng(0).standard_normal((BLOCK, CHANNELS))).astype(np.float32)
    frames = [encode_block(SampleBlock(k * BLOCK, x), fmt) for k in range(N_BLOCKS)]
    return header, encode_header(header), frames


def _decoder(head: bytes, frames: list[bytes]) -> float:
    data = head + b"".join(frames)
    d = FrameDecoder()
    t0 = time.perf_counter()
    n = 0
    for a in range(0, len(data), 1 << 16):
        n += len(d.feed(data[a:a + (1 << 16)]))
    return time.perf_counter() - t0


def _serve(frames_of_connection, pause_s: float = 0.0, stamps=None) -> int:
    sock = socket.create_server(("127.0.0.1", 0))

    def run():
        conn, _ = sock.accept()
        with conn, sock:
            for k, frame in enumerate(frames_of_connection):
                if stamps is not None:
                    stamps[k] = time.perf_counter()
                conn.sendall(frame)
                if pause_s:
                    time.sleep(pause_s)
    threading.Thread(target=run, daemon=True).start()
    return sock.getsockname()[1]


def _tcp(head: bytes, frames: list[bytes]) -> float:
    port = _serve([head + b"".join(frames[:100]), *frames[100:], encode_end(N_BLOCKS * BLOCK)])
    t0 = time.perf_counter()
    with TcpSampleSource("127.0.0.1", port) as src:
        n = sum(1 for i in src if isinstance(i, SampleBlock))
    assert n == N_BLOCKS
    return time.perf_counter() - t0


def _latency(head: bytes, frames: list[bytes]) -> np.ndarray:
    n = 300
    stamps = np.zeros(n + 2)  # the header, the blocks, the end frame
    port = _serve([head, *frames[:n], encode_end(n * BLOCK)], pause_s=0.01, stamps=stamps)
    got = []
    with TcpSampleSource("127.0.0.1", port) as src:
        for item in src:
            if isinstance(item, SampleBlock):
                got.append((item.first_index // BLOCK + 1, time.perf_counter()))  # frame k+1 is block k
    return np.array([t - stamps[k] for k, t in got])


def main() -> None:
    for fmt in ("float32", "int24"):
        _, head, frames = _wire(fmt)
        mb = (len(head) + sum(map(len, frames))) / 1e6
        dec = min(_decoder(head, frames) for _ in range(3))
        tcp = min(_tcp(head, frames) for _ in range(2))
        lat = _latency(head, frames) * 1e3
        print(f"stream {fmt} 16 ch x 4 kHz: decoder {mb / dec:7.0f} MB/s {N_BLOCKS / dec:8.0f} blocks/s "
              f"({N_BLOCKS * BLOCK / FS / dec:6.0f}x real time); TCP source "
              f"{mb / tcp:6.0f} MB/s {N_BLOCKS / tcp:7.0f} blocks/s ({N_BLOCKS * BLOCK / FS / tcp:5.0f}x real time); "
              f"latency send -> yielded median {np.median(lat):.2f} ms, p99 {np.percentile(lat, 99):.2f} ms "
              "(target: well under the 1 s budget)")


if __name__ == "__main__":
    main()
