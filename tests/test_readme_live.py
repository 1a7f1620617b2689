"""The README's live lines, run as written, each pair together: the recorder (``simulate --stream``) and the console
(``live --tcp``). The console must show the default scene's ships building up (confirmed tracks pushed to a
WebSocket client of the page), and Ctrl-C must stop both with status 130, one line each and no traceback."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

sys.path[:0] = [str(Path(__file__).parent), str(Path(__file__).parent / "console")]
from wsclient import Client  # noqa: E402

from test_readme_commands import _environment, readme_commands  # noqa: E402


def _lines(active: bool = False) -> tuple[str, str]:
    """The README's recorder and console lines: the passive pair, or the active pair (``--kind active``, tows)."""
    commands = readme_commands()
    recorder = [c for c in commands if "--stream" in c and ("--kind active" in c) == active]
    console = [c for c in commands if c.startswith("sonartrack live --tcp") and ("--source-tow" in c) == active]
    assert len(recorder) == 1 and len(console) == 1, (recorder, console)
    return recorder[0], console[0]


def _start(command: str, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=cwd, env=_environment(), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)


def _wait_console(url: str, proc: subprocess.Popen, timeout_s: float = 60.0) -> Client:
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return Client(url)
        except Exception:  # noqa: BLE001 - not listening yet
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the console never answered"
            time.sleep(0.2)


def _ships(messages) -> set[int]:
    """Confirmed track ids the console has been shown."""
    ids = set()
    for m in messages:
        for u in m["updates"] if m["type"] == "history" else [m]:
            if u["type"] == "tracks":
                ids |= {t["id"] for t in u["tracks"] if t.get("status") == "confirmed"}
    return ids


def _active_rows(messages) -> list[dict]:
    """Active target rows the console has been shown."""
    rows = []
    for m in messages:
        for u in m["updates"] if m["type"] == "history" else [m]:
            if u["type"] == "active_targets":
                rows += u["rows"]
    return rows


@contextmanager
def _running(lines: tuple[str, str], tmp_path: Path):
    """The recorder and console lines started as the README says (the console's port from its line, else 8765); a
    WebSocket client of the console while the block runs; then Ctrl-C to both, each exiting 130 with one line."""
    recorder_line, console_line = lines
    port = int(console_line.split("--port")[1].split()[0]) if "--port" in console_line else 8765
    recorder = _start(recorder_line, tmp_path)
    console = None
    try:
        line = recorder.stdout.readline()
        failed = recorder.stderr.read() if recorder.poll() is not None else ""
        assert "waiting for the live side" in line, (line, failed)
        console = _start(console_line, tmp_path)
        client = _wait_console(f"http://127.0.0.1:{port}/", console)
        yield client
        client.close()
    finally:
        procs = [p for p in (console, recorder) if p is not None]
        for proc in procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        outs = [p.communicate(timeout=60) for p in procs]
    for proc, (out, err) in zip(procs, outs, strict=True):
        assert proc.returncode == 130, (proc.returncode, out, err)
        assert "Traceback" not in err and err.strip().splitlines()[-1].startswith("interrupted"), err


def test_readme_live_active_lines_show_a_target(tmp_path):
    """The active pair (its own ports, so that it may run beside the passive pair): the B-scan arrives ping by ping
    and the default active scene's targets appear in the table (a side or an undecided pair, with a range)."""
    with _running(_lines(active=True), tmp_path) as client:
        rows = client.wait(lambda ms: _active_rows(ms), 240)
        assert len({u["ping"] for u in client.of_type("bscan")}) >= 2
    assert all(r["side"] in ("starboard", "port", "undecided") for r in rows), rows
    assert any(r["range_m"] is not None and r["range_m"] > 0 for r in rows), rows  # a target placed, not a bearing
    print(f"active target rows shown: {len(rows)}")


def test_readme_live_lines_show_the_ships(tmp_path):
    with _running(_lines(), tmp_path) as client:
        ships = client.wait(lambda ms: len(_ships(ms)) >= 2 and _ships(ms), 120)
        assert client.of_type("btr")
        client.wait(lambda ms: client.of_type("ownship") and client.of_type("targets"), 120)  # the first refresh
    print(f"confirmed tracks shown: {sorted(ships)}")
