"""A headless Chromium driven by the DevTools protocol, for the console's browser test.

The DevTools protocol directly (over tornado's WebSocket client, already installed) rather than selenium +
chromedriver: no new dependency and no driver whose version must match the browser's, and it reports every
JavaScript exception and console error the page raises, which the test turns into a failure.
"""

from __future__ import annotations

import asyncio
import base64
import json
import shutil
import subprocess
import threading
import time
import urllib.request
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
#: flags that work on this machine (and in CI): no sandbox (root), no GPU, nothing fetched from the internet
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars"]


def chromium_path() -> str | None:
    return CHROMIUM if Path(CHROMIUM).exists() else shutil.which("chromium")


class Browser:
    """A headless Chromium with one page; :meth:`call` sends a DevTools command and waits for its result."""

    def __init__(self, profile: Path, width: int = 1600, height: int = 900, timeout_s: float = 60.0):
        exe = chromium_path()
        if exe is None:
            raise RuntimeError("chromium is not installed: run `make browser`")
        profile.mkdir(parents=True, exist_ok=True)
        self.proc = subprocess.Popen([exe, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-port=0",
                                      f"--window-size={width},{height}", "about:blank"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.errors: list[str] = []
        self._next_id = 0
        self._waiting: dict[int, asyncio.Future] = {}
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._thread.start()
        try:
            port = self._devtools_port(profile, timeout_s)
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=timeout_s) as r:
                page = next(t for t in json.load(r) if t["type"] == "page")
            self._run(self._connect(page["webSocketDebuggerUrl"]), timeout_s)
        except BaseException:
            self.close()
            raise

    def _devtools_port(self, profile: Path, timeout_s: float) -> int:
        file, t0 = profile / "DevToolsActivePort", time.monotonic()
        while time.monotonic() - t0 < timeout_s:
            if self.proc.poll() is not None:
                raise RuntimeError(f"chromium exited with status {self.proc.returncode} at start")
            if file.exists() and file.read_text().strip():
                return int(file.read_text().split()[0])
            time.sleep(0.05)
        raise RuntimeError("chromium did not open its DevTools port")

    def _run(self, coro, timeout_s: float = 30.0):
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(timeout_s)

    async def _connect(self, url: str) -> None:
        import tornado.websocket

        self._ws = await tornado.websocket.websocket_connect(url, max_message_size=256 * 2**20)
        self._loop.create_task(self._read())

    async def _read(self) -> None:
        while (text := await self._ws.read_message()) is not None:
            msg = json.loads(text)
            if "id" in msg and msg["id"] in self._waiting:
                self._waiting.pop(msg["id"]).set_result(msg)
            elif msg.get("method") == "Runtime.exceptionThrown":
                d = msg["params"]["exceptionDetails"]
                self.errors.append(d.get("exception", {}).get("description") or d.get("text", "exception"))
            elif msg.get("method") == "Runtime.consoleAPICalled" and msg["params"]["type"] == "error":
                self.errors.append(" ".join(str(a.get("value", a.get("description"))) for a in msg["params"]["args"]))

    async def _call(self, method: str, params: dict) -> dict:
        self._next_id += 1
        future = self._loop.create_future()
        self._waiting[self._next_id] = future
        await self._ws.write_message(json.dumps({"id": self._next_id, "method": method, "params": params}))
        msg = await future
        if "error" in msg:
            raise RuntimeError(f"{method}: {msg['error']}")
        return msg["result"]

    def call(self, method: str, **params) -> dict:
        return self._run(self._call(method, params))

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (JSON-able); RuntimeError if it throws."""
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression!r} threw: {r['exceptionDetails'].get('text')}")
        return r["result"].get("value")

    def wait_for(self, expression: str, timeout_s: float = 20.0, poll_s: float = 0.05):
        """Poll a JavaScript expression until it is truthy; its value, or TimeoutError saying which."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout_s:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(poll_s)
        raise TimeoutError(f"the page never made {expression!r} true within {timeout_s} s")

    def click(self, x: float, y: float) -> None:
        """A real left click at page coordinates (mouse down and up, as the user's)."""
        for kind in ("mouseMoved", "mousePressed", "mouseReleased"):
            self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=1)

    def screenshot(self, path: Path) -> Path:
        path.write_bytes(base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"]))
        return path

    def close(self) -> None:
        if getattr(self, "_ws", None) is not None:
            self._loop.call_soon_threadsafe(self._ws.close)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
