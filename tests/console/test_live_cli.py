"""``sonartrack live``: its options checked before anything starts, and its wiring source -> chain -> console,
with stand-ins for the stream sources and the live chain (io/stream and systems/live are other helpers' work)."""

from __future__ import annotations

import json
import sys
import time
import types
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from wsclient import Client  # noqa: E402

from sonartrack.cli import main  # noqa: E402
from sonartrack.console.fake import FakeLive  # noqa: E402


@pytest.mark.parametrize("argv, message", [
    ([], "give one sample source"),
    (["--tcp", "h:1", "--wav", "x.wav", "--nav", "n.csv"], "not --tcp and --wav"),
    (["--tcp", "nohost", "--nav", "n.csv"], "HOST:PORT"),
    (["--tcp", "h:99999", "--nav", "n.csv"], "HOST:PORT"),
    (["--tcp", "h:5555"], "give one navigation source"),
    (["--tcp", "h:5555", "--nav", "n.csv", "--nav-udp", "10110"], "give one navigation source"),
    (["--tcp", "h:5555", "--nav", "n.csv", "--speed", "20"], "--speed replays a finished --wav"),
    (["--wav", "missing.wav", "--nav", "n.csv"], "is not a file"),
    (["--folder", "missing-folder", "--nav", "n.csv"], "is not a folder"),
    (["--tcp", "h:5555", "--nav", "n.csv", "--config", "mftd.toml"], "cannot run [btr_mftd]"),
    (["--tcp", "h:5555", "--nav", "n.csv", "--calibration", "bad.toml"], "sensitivity"),
    (["--tcp", "h:5555", "--nav", "n.csv", "--source-tow", "300"], "give both --source-tow and --array-tow"),
])
def test_bad_options_are_one_line_and_status_2(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mftd.toml").write_text("spacing_m = 2.5\n[btr_mftd]\nenabled = true\n")
    (tmp_path / "bad.toml").write_text("sensitivity_db = -20.0\n")  # dB re 1 V/Pa given for re 1 V/uPa
    assert main(["live", "--port", "0", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and len(err.splitlines()) == 1


class _Source:
    def __init__(self, *args, **kwargs):
        self.args, self.closed = args, False
        opened.append(self)

    def close(self):
        self.closed = True


opened: list[_Source] = []


def _fake_modules(monkeypatch, run_live) -> None:
    sources = types.ModuleType("sonartrack.io.stream.sources")
    for name in ("TcpSampleSource", "FolderSampleSource", "ReplaySampleSource", "UdpNmeaSource", "FileNavSource"):
        setattr(sources, name, type(name, (_Source,), {}))
    import sonartrack.io.stream as real_stream
    import sonartrack.systems.live as real_live

    stream = types.ModuleType("sonartrack.io.stream")
    stream.sources = sources
    stream.__path__ = real_stream.__path__  # its other submodules (types, frames) are the real ones, run alone too

    live = types.ModuleType("sonartrack.systems.live")
    live.run_live = run_live
    live.__path__ = real_live.__path__  # its submodules (the settings' check) are the real ones
    monkeypatch.setitem(sys.modules, "sonartrack.io.stream", stream)
    monkeypatch.setitem(sys.modules, "sonartrack.io.stream.sources", sources)
    monkeypatch.setitem(sys.modules, "sonartrack.systems.live", live)


def test_wiring_source_chain_console_and_ctrl_c(monkeypatch, capsys, tmp_path):
    seen = {}

    class Chain:  # the live chain's face the console uses: select(track) -> that track's LOFAR rows
        def __init__(self):
            self.selected = None

        def select(self, track):
            self.selected = track
            return []

    def run_live(samples, nav, settings, publish, *, checkpoint=None, stop=None, ready=None, **kw):
        server = publish.__self__  # the console's publish
        assert server.url.startswith("http://127.0.0.1:")
        chain = Chain()
        ready(chain)
        client = Client(server.url)
        fake = FakeLive()
        for _ in range(5):
            for update in fake.step():
                publish(update)
        client.wait(lambda m: len(client.of_type("btr")) == 5, 60)  # generous: the test machine may be loaded
        client.send(json.dumps({"select": 2}))
        client.wait(lambda m: client.of_type("selected"), 60)
        deadline = time.monotonic() + 60
        while chain.selected is None and time.monotonic() < deadline:  # the callback runs on its own thread
            time.sleep(0.02)
        seen.update(selected=chain.selected, samples=samples, nav=nav, checkpoint=checkpoint, stopped=stop.is_set())
        client.close()
        raise KeyboardInterrupt

    opened.clear()
    _fake_modules(monkeypatch, run_live)
    nav = tmp_path / "nav.csv"
    nav.write_text("time_s,x_m,y_m,heading_deg\n")
    status = main(["live", "--tcp", "127.0.0.1:5555", "--nav", str(nav), "--port", "0", "--spacing", "0.5",
                   "--checkpoint", str(tmp_path / "state.ckpt")])
    err = capsys.readouterr().err
    assert status == 130, err
    assert "interrupted: the live run stopped" in err and "state.ckpt" in err and "Traceback" not in err
    assert seen["selected"] == 2 and not seen["stopped"]
    assert type(seen["samples"]).__name__ == "TcpSampleSource" and seen["samples"].args == ("127.0.0.1", 5555)
    assert type(seen["nav"]).__name__ == "FileNavSource"
    assert all(s.closed for s in opened) and len(opened) == 2  # the sources are closed on the way out


def test_keep_open_serves_the_last_picture_after_the_stream_ends(monkeypatch, capsys, tmp_path):
    """--keep-open: the stream ended, the console still serves its history to a client that comes then, until
    Ctrl-C, which closes it with status 0."""
    import threading

    seen = {}

    def run_live(samples, nav, settings, publish, *, checkpoint=None, stop=None, ready=None, **kw):
        seen["url"] = publish.__self__.url
        fake = FakeLive()
        for _ in range(5):
            for update in fake.step():
                publish(update)
        return None  # the stream ended before a result: said, and the console kept

    real_sleep = time.sleep

    def sleep(seconds):
        if threading.current_thread() is threading.main_thread() and "rows" not in seen:
            client = Client(seen["url"])  # a client that comes after the end of the stream
            client.wait(lambda m: len(client.of_type("btr")) == 5)
            seen["rows"] = len(client.of_type("btr"))
            client.close()
            raise KeyboardInterrupt
        real_sleep(seconds)

    opened.clear()
    _fake_modules(monkeypatch, run_live)
    monkeypatch.setattr(time, "sleep", sleep)
    nav = tmp_path / "nav.csv"
    nav.write_text("time_s,x_m,y_m,heading_deg\n")
    status = main(["live", "--tcp", "127.0.0.1:5555", "--nav", str(nav), "--port", "0", "--spacing", "0.5",
                   "--keep-open"])
    err = capsys.readouterr().err
    assert status == 0 and seen["rows"] == 5
    assert "no passive result" in err and "stays open" in err and "console closed" in err and "Traceback" not in err
