"""Live latency end to end (issue 31 item 6): a window's last sample arriving at the source -> its bearing-time row
drawn in headless Chromium.

The whole live path at real-time rate: a simulated scene streamed as a recorder streams it (systems/simulate/
stream.py: samples over TCP in blocks of 0.1 s, NMEA over UDP), read by TcpSampleSource and UdpNmeaSource (io/stream),
run window by window by the live chain with its refresh thread (systems/live/run.py), pushed by the console server
(console/server.py) to the page in headless Chromium (Debian's chromium, `make browser`). Two clocks on one machine,
read as Unix time: the source's blocks are timed as the source yields them (the wrapper below, after the frame's
checks and the reorder window), the page logs when each frame was drawn (``sonarConsole.state.drawLog``: the newest
row's t_s and Date.now()). Window k's latency: from the arrival of the block holding its last sample to the first
frame drawn with row k on screen. Target: median and 99th percentile <= 1 s.

    python benchmarks/bench_live_latency.py              # a 120 s scene at real time (~2.5 min)
    python benchmarks/bench_live_latency.py --seconds 60 --speed 2
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests" / "console"))

from sonartrack.console.server import ConsoleServer  # noqa: E402
from sonartrack.io.stream.nav import UdpNmeaSource  # noqa: E402
from sonartrack.io.stream.tcp import TcpSampleSource  # noqa: E402
from sonartrack.io.stream.types import SampleBlock  # noqa: E402
from sonartrack.sim.scene import PassiveSceneSettings  # noqa: E402
from sonartrack.systems.live import run_live  # noqa: E402
from sonartrack.systems.passive import PassiveSettings  # noqa: E402

SCENE = """seed = 11
[ownship]
turn_start_s = 30.0
[[ships]]
name = "merchant"
x_m = 4700.0
y_m = 6900.0
course_deg = 140.0
speed_kn = 12.0
source_level_db = 151.0
tonal_hz = 120.0
tonal_level_db = 165.0
[[ships]]
name = "trawler"
x_m = 4000.0
y_m = -1000.0
course_deg = 325.0
speed_kn = 8.0
source_level_db = 142.0
tonal_hz = 175.0
tonal_level_db = 152.0
"""


class TimedSource:
    """The sample source, each block's arrival (Unix s) and end index noted as the source yields it."""

    def __init__(self, source):
        self.source, self.arrivals = source, []

    @property
    def header(self):
        return self.source.header

    def __iter__(self):
        for item in self.source:
            if isinstance(item, SampleBlock):
                self.arrivals.append((item.first_index + len(item.samples), time.time()))
            yield item

    def close(self):
        self.source.close()


def run(seconds: float, speed: float) -> tuple[np.ndarray, int]:
    """Stream the scene through the live path into headless Chromium; the latencies (s) and the windows."""
    from cdp import Browser, chromium_path

    from sonartrack.systems.simulate.stream import SceneStreamer

    if chromium_path() is None:
        print("live latency end to end: skipped, chromium is not installed (make browser)")
        return np.zeros(0), 0
    scene = PassiveSceneSettings.model_validate({**tomllib.loads(SCENE), "duration_s": seconds})
    settings = PassiveSettings(spacing_m=2.5, min_track_s=60.0)
    with ConsoleServer(port=0) as server, tempfile.TemporaryDirectory() as tmp:
        nav = UdpNmeaSource(0).start()
        streamer = SceneStreamer(scene, speed=speed, nav_udp=nav.port)
        samples = TimedSource(TcpSampleSource("127.0.0.1", streamer.port))
        browser = Browser(Path(tmp) / "profile")
        stop, threads = threading.Event(), []
        try:
            browser.call("Page.navigate", url=server.url)
            browser.wait_for("window.sonarConsole && sonarConsole.state.conn === 'live'")
            threads = [threading.Thread(target=streamer.serve, args=(stop,), daemon=True),
                       threading.Thread(target=run_live, args=(samples, nav, settings, server.publish),
                                        kwargs={"stop": stop}, daemon=True)]
            for th in threads:
                th.start()
            threads[1].join(seconds / speed + 60.0)
            time.sleep(1.0)
            log = browser.evaluate("sonarConsole.state.drawLog")
            fs = samples.header.rate_hz
        finally:
            stop.set()
            browser.close()
            for source in (samples, nav):
                source.close()
            for th in threads:
                th.join(10)
            streamer.close()
    return latencies(samples.arrivals, log, fs, settings.window_s), int(seconds / settings.window_s)


def latencies(arrivals: list, log: list, fs_hz: float, window_s: float) -> np.ndarray:
    """Per window drawn: the first frame showing it minus the arrival of the block that held its last sample (s)."""
    ends = np.array([e for e, _ in arrivals])
    at = np.array([t for _, t in arrivals])
    drawn_t = np.array([t for t, _ in log])
    drawn_at = np.array([ms / 1e3 for _, ms in log])
    n = int(round(window_s * fs_hz))
    out = []
    for k in range(int(ends[-1] // n) if ends.size else 0):
        i = np.searchsorted(ends, (k + 1) * n, side="left")  # the first block ending at or after the last sample
        j = np.searchsorted(drawn_t, (k + 0.5) * window_s - 1e-9, side="left")  # the first frame with row k on it
        if i < ends.size and j < drawn_t.size:
            out.append(drawn_at[j] - at[i])
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=120.0)
    ap.add_argument("--speed", type=float, default=1.0)
    a = ap.parse_args()
    lat, windows = run(a.seconds, a.speed)
    if lat.size == 0:
        return
    med, p99 = np.median(lat), np.quantile(lat, 0.99)
    print(f"live latency end to end (TCP source -> chain -> console -> headless Chromium), {a.seconds:g} s scene at "
          f"{a.speed:g}x real time: window's last sample -> row drawn median {1e3 * med:.0f} ms, 99th percentile "
          f"{1e3 * p99:.0f} ms, max {1e3 * lat.max():.0f} ms ({lat.size} of {windows} windows; target 1000 ms: "
          f"ratio {p99:.2f})")


if __name__ == "__main__":
    main()
