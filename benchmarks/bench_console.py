"""The console's push latency and CPU share (issue 31 item 6): publish -> WebSocket client, publish -> screen.

The server runs here, fed one window of display updates (a bearing-time row, tracks, ownship, targets, health:
LIVE.md's shapes from sonartrack.console.fake) every 50 ms; WebSocket clients run in another process and time
each bearing-time row from publish to arrival (CLOCK_MONOTONIC is one clock for both processes on Linux), with
1 and with 4 clients. The server's CPU is its own thread's (its event loop, from /proc) plus the time spent inside
publish() (the JSON encoding, in the publisher's thread), as a share of one core. Then, where Debian's chromium is
installed (`make browser`), the same feed to the page in headless Chromium: publish -> the row drawn on the
canvas (the page logs when each frame was drawn). Target: <= 1 s median and 99th percentile.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests" / "console"))

from sonartrack.console.fake import FakeLive  # noqa: E402
from sonartrack.console.server import ConsoleServer  # noqa: E402

PERIOD_S = 0.05
RUN_S = 15.0

CLIENTS = r"""
import asyncio, json, sys, time
import tornado.websocket
async def one(url, seconds, out):
    c = await tornado.websocket.websocket_connect(url)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        m = await c.read_message()
        if m is None: break
        u = json.loads(m)
        if u["type"] == "btr" and "sent" in u: out.append(time.monotonic() - u["sent"])
    c.close()
async def main(url, n, seconds):
    out = []
    await asyncio.gather(*(one(url, seconds, out) for _ in range(n)))
    print(json.dumps(out))
asyncio.run(main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3])))
"""


def thread_cpu_s(native_id: int) -> float:
    with open(f"/proc/self/task/{native_id}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Feed:
    """Publishes a window of updates every PERIOD_S; each row carries its publish time ("sent", monotonic)."""

    def __init__(self, server: ConsoleServer):
        self.server, self.fake, self.stop = server, FakeLive(seed=1), threading.Event()
        self.fake.selected = 1
        self.publish_cpu_s = 0.0
        self.sent_unix: dict[float, float] = {}
        self.thread = threading.Thread(target=self.run, daemon=True)

    def run(self) -> None:
        next_t = time.monotonic()
        while not self.stop.is_set():
            for update in self.fake.step():
                if update["type"] == "btr":
                    update["sent"] = time.monotonic()
                    self.sent_unix[update["t_s"]] = time.time()
                c0 = time.thread_time()
                self.server.publish(update)
                self.publish_cpu_s += time.thread_time() - c0
            next_t += PERIOD_S
            time.sleep(max(0.0, next_t - time.monotonic()))


def measure_clients(n: int) -> None:
    with ConsoleServer(port=0) as server:
        feed = Feed(server)
        feed.thread.start()
        time.sleep(1.0)
        cpu0, pub0, t0 = thread_cpu_s(server._thread.native_id), feed.publish_cpu_s, time.monotonic()
        out = subprocess.run([sys.executable, "-c", CLIENTS, server.url.replace("http", "ws") + "ws", str(n),
                              str(RUN_S)], capture_output=True, text=True, check=True)
        wall = time.monotonic() - t0
        cpu = thread_cpu_s(server._thread.native_id) - cpu0 + feed.publish_cpu_s - pub0
        feed.stop.set()
        lat_ms = 1e3 * np.array(json.loads(out.stdout))
    print(f"console push, {n} client(s), 1 window / {PERIOD_S * 1e3:.0f} ms: publish -> WebSocket client latency "
          f"median {np.median(lat_ms):.2f} ms, 99th percentile {np.percentile(lat_ms, 99):.2f} ms "
          f"({lat_ms.size} rows; target 1000 ms: ratio {np.percentile(lat_ms, 99) / 1000:.4f}); "
          f"server CPU {100 * cpu / wall:.1f} % of one core")


def measure_browser() -> None:
    from cdp import Browser, chromium_path

    if chromium_path() is None:
        print("console -> screen: skipped, chromium is not installed (make browser)")
        return
    with ConsoleServer(port=0) as server, tempfile.TemporaryDirectory() as tmp:
        feed = Feed(server)
        browser = Browser(Path(tmp) / "profile")
        try:
            browser.call("Page.navigate", url=server.url)
            browser.wait_for("window.sonarConsole && sonarConsole.state.conn === 'live'")
            feed.thread.start()
            time.sleep(RUN_S)
            feed.stop.set()
            log = browser.evaluate("sonarConsole.state.drawLog")
        finally:
            browser.close()
    drawn_t = np.array([t for t, _ in log])
    drawn_at = np.array([ms / 1e3 for _, ms in log])
    lat = []
    for t_s, sent in feed.sent_unix.items():  # the first frame drawn that holds this row
        k = np.searchsorted(drawn_t, t_s)
        if k < drawn_t.size:
            lat.append(drawn_at[k] - sent)
    lat_ms = 1e3 * np.array(lat)
    print(f"console -> screen (headless Chromium, 1 page): publish -> row drawn median {np.median(lat_ms):.1f} ms, "
          f"99th percentile {np.percentile(lat_ms, 99):.1f} ms ({lat_ms.size} rows; target 1000 ms)")


if __name__ == "__main__":
    measure_clients(1)
    measure_clients(4)
    measure_browser()
