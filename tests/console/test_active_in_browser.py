"""Active pings live in a real browser: a simulated active scene streamed as a recorder would (ping frames over
TCP, NMEA over UDP: ``simulate --kind active --stream``), run ping by ping by the live active chain (the file
chain's per-ping core, geometry from the fixes) and pushed to the console, watched in headless Chromium.

Checks that the B-scan panel draws the pings, that an active track is drawn over it and an active target row
(A<n>, a side or an undecided pair, a range with its sd) appears in the table, and that the page raised no
JavaScript error; keeps a screenshot with the test's output.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from cdp import Browser, chromium_path  # noqa: E402
from streaming import serve_and_run  # noqa: E402

from sonartrack.console.server import ConsoleServer  # noqa: E402
from sonartrack.io.stream.nav import UdpNmeaSource  # noqa: E402
from sonartrack.io.stream.tcp import TcpSampleSource  # noqa: E402
from sonartrack.systems.active.settings import ActiveSettings  # noqa: E402
from sonartrack.systems.live import run_live  # noqa: E402
from sonartrack.systems.passive import PassiveSettings  # noqa: E402


@pytest.fixture
def active_stream():
    """The console fed by the live active chain on the default active scene (300 s: its maneuvering target is
    confirmed within it) streamed at 20x real time; (server, run state)."""
    from sonartrack.sim.active_scene import ActiveSceneSettings
    from sonartrack.systems.simulate.stream import ActiveSceneStreamer

    scene = ActiveSceneSettings(duration_s=300.0)
    server = ConsoleServer(port=0)
    server.start()
    nav = UdpNmeaSource(0).start()
    streamer = ActiveSceneStreamer(scene, speed=20.0, nav_udp=nav.port)
    samples = TcpSampleSource("127.0.0.1", streamer.port)
    tows = {"source_tow_m": scene.sonar.source_tow_m, "array_tow_m": scene.sonar.array_tow_m}
    yield from serve_and_run(streamer, samples, nav, server, lambda stop: run_live(
        samples, nav, PassiveSettings(spacing_m=0.5), server.publish, stop=stop, warm=False,
        active_settings=ActiveSettings(spacing_m=0.5), active_options=tows))


def test_active_pings_in_headless_chromium(active_stream, tmp_path):
    if chromium_path() is None:
        pytest.fail("chromium is not installed: run `make browser` (apt-get installs Debian's chromium)")
    server, state = active_stream
    browser = Browser(tmp_path / "profile")
    try:
        browser.call("Runtime.enable")
        browser.call("Page.enable")
        browser.call("Page.navigate", url=server.url)
        browser.wait_for("window.sonarConsole && sonarConsole.state.bscan !== null", 120)
        assert browser.evaluate("!document.getElementById('bscan').hidden")                # the panel is shown
        first = browser.evaluate("sonarConsole.state.bscan.ping")
        browser.wait_for(f"sonarConsole.state.bscan.ping > {first}", 120)                 # and follows the pings
        # its pixels are drawn: not all black (the canvas starts black; the image holds the noise and the echoes)
        lit = ("(() => { const c = document.getElementById('bscan'), d = c.getContext('2d')"
               ".getImageData(0, 0, c.width, c.height).data; let n = 0;"
               " for (let i = 0; i < d.length; i += 4) n += (d[i] + d[i + 1] + d[i + 2]) > 30; return n; })()")
        assert browser.evaluate(lit) > 1000
        assert browser.wait_for("sonarConsole.bscanTracks().length", 180) >= 1            # tracks over the B-scan
        table = "[...document.querySelectorAll('#targets tbody tr.active')].map(r => r.innerText)"
        rows = browser.wait_for(f"{table}.length >= 1 && {table}", 240)                    # an active target row
        assert all(r.startswith("A") and ("undecided pair" in r or "starboard" in r or "port" in r) and " ± " in r
                   for r in rows), rows
        shot = browser.screenshot(tmp_path / "console_active.png")
        print(f"screenshot: {shot}")
        assert browser.errors == [], f"the page raised: {browser.errors}"
    finally:
        browser.close()
    assert "error" not in state, state.get("error")
