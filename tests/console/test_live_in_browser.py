"""The whole live path in a real browser: a simulated scene streamed as a recorder would (samples over TCP, NMEA
over UDP: systems/simulate/stream.py), read by the live sources (io/stream), run window by window by the live
chain (systems/live) and pushed to the console (console/server.py), watched in headless Chromium.

Checks that the waterfall fills and moves, that the chain's tracks appear on it, that the target table fills with
the ships (a side each), and that the page raised no JavaScript error; keeps a screenshot with the test's output.
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from cdp import Browser, chromium_path  # noqa: E402
from streaming import serve_and_run  # noqa: E402

from sonartrack.console.server import ConsoleServer  # noqa: E402
from sonartrack.io.stream.nav import UdpNmeaSource  # noqa: E402
from sonartrack.io.stream.tcp import TcpSampleSource  # noqa: E402
from sonartrack.sim.scene import PassiveSceneSettings  # noqa: E402
from sonartrack.systems.live import run_live  # noqa: E402
from sonartrack.systems.passive import PassiveSettings  # noqa: E402

#: two ships apart in cone angle, the ownship's turn early (so sides and ranges come within the 150 s)
SCENE = """duration_s = 150.0
seed = 11
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


@pytest.fixture
def live_stream():
    """The console fed by the live chain on a scene streamed at 10x real time; (server, run state)."""
    from sonartrack.systems.simulate.stream import SceneStreamer

    scene = PassiveSceneSettings.model_validate(tomllib.loads(SCENE))
    server = ConsoleServer(port=0)
    server.start()
    nav = UdpNmeaSource(0).start()
    streamer = SceneStreamer(scene, speed=10.0, nav_udp=nav.port)
    samples = TcpSampleSource("127.0.0.1", streamer.port)
    yield from serve_and_run(streamer, samples, nav, server, lambda stop: run_live(
        samples, nav, PassiveSettings(spacing_m=2.5, min_track_s=60.0), server.publish, stop=stop, refresh_s=2.0,
        ready=lambda live: server.on_select(lambda i: [server.publish(u) for u in live.select(i)])))


def test_live_chain_in_headless_chromium(live_stream, tmp_path):
    if chromium_path() is None:
        pytest.fail("chromium is not installed: run `make browser` (apt-get installs Debian's chromium)")
    server, state = live_stream
    browser = Browser(tmp_path / "profile")
    try:
        browser.call("Runtime.enable")
        browser.call("Page.enable")
        browser.call("Page.navigate", url=server.url)
        browser.wait_for("window.sonarConsole && sonarConsole.state.btr.length > 10", 60)
        rows = browser.evaluate("sonarConsole.state.btr.length")
        browser.wait_for(f"sonarConsole.state.btr.length > {rows + 10}", 60)       # the waterfall keeps filling
        assert browser.wait_for("sonarConsole.drawnTracks().length", 60) >= 1     # the chain's tracks on it
        table = "[...document.querySelectorAll('#targets tbody tr')].map(r => r.innerText)"
        text = browser.wait_for(f"{table}.length >= 2 && {table}", 90)            # the ships in the table
        assert all(("starboard" in r) or ("port" in r) or ("undecided" in r) for r in text), text
        shot = browser.screenshot(tmp_path / "console_live.png")
        print(f"screenshot: {shot}")
        assert browser.errors == [], f"the page raised: {browser.errors}"
    finally:
        browser.close()
    assert "error" not in state, state.get("error")
