"""The console in a real browser: headless Chromium (Debian's, `make browser`) on a server fed fast on loopback.

Checks that the waterfall and the target table update and a track appears, that a click on a trace reaches
the server as a selection (and brings that track's LOFAR rows), that the page raises no JavaScript error, and
keeps a screenshot with the test's output. The updates come from :class:`sonartrack.console.fake.FakeLive` (the
display updates of LIVE.md drawn from geometry); after the live chain is merged, the same checks can run on a
simulated stream through it by swapping the ``feed`` fixture.
"""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from cdp import Browser, chromium_path  # noqa: E402

from sonartrack.console.fake import FakeLive  # noqa: E402
from sonartrack.console.server import ConsoleServer  # noqa: E402

#: a digest of the waterfall canvas's pixels: changes when the picture does
CANVAS_DIGEST = """(() => { const c = document.getElementById('btr'), d = c.getContext('2d')
  .getImageData(0, 0, c.width, c.height).data; let h = 0, lit = 0;
  for (let i = 0; i < d.length; i += 4) { h = (h * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) | 0;
    if (d[i] + d[i + 1] + d[i + 2] > 60) lit++; } return [h, lit / (d.length / 4)]; })()"""


@pytest.fixture
def feed():
    """A server fed 20 windows a second by the fake chain, which follows the operator's selection."""
    server = ConsoleServer(port=0, history_rows=600)
    fake, stop, selections = FakeLive(seed=3), threading.Event(), []

    def selected(track: int) -> None:
        selections.append(track)
        fake.selected = track

    server.on_select(selected)

    def run():
        while not stop.is_set():
            for update in fake.step():
                server.publish(update)
            time.sleep(0.05)

    server.start()
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    yield server, selections
    stop.set()
    thread.join(5)
    server.stop()


def test_console_in_headless_chromium(feed, tmp_path):
    if chromium_path() is None:
        pytest.fail("chromium is not installed: run `make browser` (apt-get installs Debian's chromium)")
    server, selections = feed
    browser = Browser(tmp_path / "profile")
    try:
        browser.call("Runtime.enable")
        browser.call("Page.enable")
        browser.call("Page.navigate", url=server.url)
        browser.wait_for("window.sonarConsole && sonarConsole.state.conn === 'live' && "
                         "sonarConsole.state.btr.length > 20")
        first, lit = browser.wait_for(f"(r => r[1] > 0.05 && r)({CANVAS_DIGEST})")  # drawn, not a blank canvas
        rows = browser.evaluate("sonarConsole.state.btr.length")
        browser.wait_for(f"sonarConsole.state.btr.length > {rows + 10}")       # rows keep arriving ...
        browser.wait_for(f"({CANVAS_DIGEST})[0] !== {first}")                # ... and the waterfall moves
        assert browser.wait_for("sonarConsole.drawnTracks().length") >= 1     # a track drawn on it
        table = "[...document.querySelectorAll('#targets tbody tr')].map(r => r.innerText)"
        before = browser.wait_for(f"{table}.length === 3 && {table}")
        # the fake ownship turns at 120 s: ranges are determined after it, and the table says so
        browser.wait_for(f"{table}.join() !== {before!r}.join() && !{table}.join().includes('not observable')", 30)

        point = browser.wait_for("sonarConsole.trackPoint(2)")
        browser.click(point["x"], point["y"])
        deadline = time.monotonic() + 10
        while not selections and time.monotonic() < deadline:
            time.sleep(0.02)
        assert selections == [2] and server.selected == 2
        browser.wait_for("(sonarConsole.state.lofar.get(2) || []).length > 5")   # the chain answered with LOFAR
        browser.wait_for("document.getElementById('lofar-title').textContent === 'track T2'")
        browser.wait_for("document.querySelector('#targets tr.sel') && "
                         "document.querySelector('#targets tr.sel').dataset.id === '2'")
        shot = browser.screenshot(tmp_path / "console.png")
        print(f"screenshot: {shot} ({lit:.0%} of the waterfall lit)")
        assert shot.stat().st_size > 10_000
        assert browser.errors == [], f"the page raised: {browser.errors}"
    finally:
        browser.close()
