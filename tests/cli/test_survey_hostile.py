"""`sonartrack survey` on hostile input and when stopped: one line and the right status, nothing written or removed
outside --out, no half-written recording folder, and a rerun that does exactly the rest.

The interrupt runs are `python -m sonartrack.cli survey --workers 2` in a session of their own (as
tests/cli/test_interrupt.py does for `reproduce`), with TMPDIR pointing at a folder of the test's own so that
anything Dask leaves in the temporary folder is seen; the signal goes to the whole process group, as a terminal's
Ctrl-C or a service manager's SIGTERM does. The recordings are one simulated 20 s recording listed under four
names.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from sonartrack.cli import main

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc") or os.name != "posix", reason="needs POSIX and /proc")

NAMES = [f"leg{i}" for i in range(1, 5)]


def _victim(folder):
    folder.mkdir(parents=True)
    (folder / "marker").write_text("keep me")
    (folder / "status.json").write_text("{}")
    return folder


def test_a_name_leading_out_fails_alone_and_the_folder_outside_is_kept(tmp_path, capsys):
    victim = _victim(tmp_path / "victim")
    (tmp_path / "out" / "recordings").mkdir(parents=True)
    (tmp_path / "m.csv").write_text("name,recording,navigation,spacing_m\n../../victim,nothing.wav,nav.csv,2.5\n")
    for _ in range(2):  # the old code removed the victim on the second run, once OUT/recordings existed
        assert main(["survey", "--manifest", str(tmp_path / "m.csv"), "--out", str(tmp_path / "out")]) == 1
    assert sorted(p.name for p in victim.iterdir()) == ["marker", "status.json"]
    err = capsys.readouterr().err.splitlines()[-1]
    assert err == ("failed: line2: manifest line 2: the name '../../victim' holds '/' (a path, not a name): give a "
                   "plain name like leg1 (one folder name: letters, digits, - and _)")


def test_a_symlinked_recordings_folder_is_refused_in_one_line(tmp_path, capsys):
    victim = _victim(tmp_path / "victim" / "leg1").parent
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "recordings").symlink_to(victim, target_is_directory=True)
    (tmp_path / "m.csv").write_text("name,recording,navigation,spacing_m\nleg1,nothing.wav,nav.csv,2.5\n")
    assert main(["survey", "--manifest", str(tmp_path / "m.csv"), "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == (f"error: {tmp_path}/out/recordings is a symbolic link (to {victim}): a survey "
                                       "writes and removes only inside --out; remove the link (or give another "
                                       "--out)\n")
    assert sorted(p.name for p in (victim / "leg1").iterdir()) == ["marker", "status.json"]


@pytest.mark.parametrize(("args", "text", "words"), [
    (["--scheduler", "notaurl"], "leg1,nothing.wav,nav.csv,2.5\n",
     "error: --scheduler 'notaurl' is not a Dask scheduler address: give it as tcp://host:8786"),
    ([], "leg1,nothing.wav,nav.csv," + "9" * 140_000 + "\n", "line 2: field larger than field limit (131072)"),
])
def test_internal_errors_are_now_one_line(tmp_path, capsys, args, text, words):
    (tmp_path / "m.csv").write_text("name,recording,navigation,spacing_m\n" + text)
    assert main(["survey", "--manifest", str(tmp_path / "m.csv"), "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "internal error" not in err


# ---- interrupts -------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("survey-inputs")
    assert main(["simulate", "--duration-s", "20", "--only", "passive", "--out", str(d / "sim")]) == 0
    rows = ["name,recording,navigation,spacing_m"] + [f"{n},sim/recording.wav,sim/nav.csv,2.5" for n in NAMES]
    (d / "survey.csv").write_text("\n".join(rows) + "\n")
    return d


def _sigint_default():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _live_in_session(sid: int) -> list[int]:
    pids = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        state, _ppid, _pgrp, session = stat[stat.rfind(")") + 2:].split()[:4]
        if int(session) == sid and state not in "ZX":
            pids.append(int(entry))
    return pids


class SurveyRun:
    """`survey --workers 2` over the module's four recordings, into OUT, with TMPDIR of its own."""

    def __init__(self, inputs, tmp_path):
        self.out, self.tmp = tmp_path / "out", tmp_path / "tmp"
        self.tmp.mkdir()
        self.env = {**os.environ, "TMPDIR": str(self.tmp)}
        self.cmd = [sys.executable, "-m", "sonartrack.cli", "survey", "--manifest", str(inputs / "survey.csv"),
                    "--out", str(self.out), "--workers", "2"]
        self.proc = None

    def start(self):
        self.proc = subprocess.Popen(self.cmd, env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True, start_new_session=True, preexec_fn=_sigint_default)
        return self

    def wait_for(self, condition, timeout=120.0):
        deadline = time.monotonic() + timeout
        while not condition():
            assert self.proc.poll() is None, f"the run ended early: {self.proc.stderr.read()}"
            assert time.monotonic() < deadline, "timed out"
            time.sleep(0.005)

    def signal_group(self, signum) -> str:
        os.killpg(self.proc.pid, signum)
        return self.proc.communicate(timeout=60)[1]

    def recordings(self) -> list:
        folder = self.out / "recordings"
        return sorted(folder.iterdir()) if folder.is_dir() else []

    def done(self) -> list[str]:
        return [p.name for p in self.recordings() if (p / "status.json").is_file()
                and json.loads((p / "status.json").read_text())["status"] == "ok"]

    def survivors(self, grace_s=5.0) -> list[int]:
        deadline = time.monotonic() + grace_s
        while _live_in_session(self.proc.pid) and time.monotonic() < deadline:
            time.sleep(0.01)
        return _live_in_session(self.proc.pid)

    def kill_leftovers(self):
        if self.proc is not None:
            for pid in _live_in_session(self.proc.pid):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()


@pytest.fixture
def run(inputs, tmp_path):
    """A survey run, with Dask's default HTTP port 8787 held by another listener where it is free (another
    cluster on the machine): the survey's cluster must neither need it nor warn about it."""
    import socket

    holder = socket.socket()
    with contextlib.suppress(OSError):
        holder.bind(("127.0.0.1", 8787))
        holder.listen()
    r = SurveyRun(inputs, tmp_path)
    yield r
    r.kill_leftovers()
    holder.close()


def _the_one_line(err: str, run: SurveyRun) -> int:
    """N from the survey's one line; nothing else on stderr."""
    assert "Traceback" not in err and "Error" not in err, err
    assert len(err.splitlines()) == 1, err
    m = re.fullmatch(rf"interrupted: (\d) of {len(NAMES)} recordings done and kept in {re.escape(str(run.out))}; "
                     rf"rerun the same command to do the other (\d)\n", err)
    assert m and int(m[1]) + int(m[2]) == len(NAMES), err
    return int(m[1])


def _clean(run: SurveyRun) -> None:
    """No half folder, no hidden leftover in OUT, nothing in the temporary folder, no process left."""
    assert all((p / "status.json").is_file() and not p.name.startswith(".") for p in run.recordings())
    assert not [p.name for p in run.out.iterdir() if p.name.startswith(".")] if run.out.is_dir() else True
    assert list(run.tmp.iterdir()) == []
    assert run.survivors() == []


def _writing(run: SurveyRun) -> bool:
    """A recording is being stored: a hidden folder (this code) or a folder without its status yet (the old)."""
    return any(p.name.startswith(".") or not (p / "status.json").is_file() for p in run.recordings())


def test_ctrl_c_while_a_recording_is_stored_keeps_whole_folders_and_a_rerun_does_the_rest(run):
    run.start()
    run.wait_for(lambda: len(run.done()) >= 1 and _writing(run))
    err = run.signal_group(signal.SIGINT)
    assert run.proc.returncode == 130, err
    kept = _the_one_line(err, run)
    assert kept == len(run.done()) and 1 <= kept < len(NAMES)
    _clean(run)
    stamps = {n: (run.out / "recordings" / n / "status.json").stat().st_mtime_ns for n in run.done()}
    again = subprocess.run(run.cmd, env=run.env, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"survey: {len(NAMES) - kept} ran, {kept} already done, 0 failed" in again.stdout
    assert {n: (run.out / "recordings" / n / "status.json").stat().st_mtime_ns for n in stamps} == stamps
    assert list(run.tmp.iterdir()) == []


@pytest.mark.parametrize(("signum", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_the_cluster_starts_ends_in_one_line(run, signum, status):
    """The old code: `AssertionError: Status.init` and `Nanny failed to start` tracebacks, and the workers'
    KeyboardInterrupt tracebacks; dask-scratch-space left in the temporary folder."""
    run.start()
    run.wait_for(lambda: any(run.tmp.iterdir()) or any(run.out.glob(".dask-scratch-*")))
    err = run.signal_group(signum)
    assert run.proc.returncode == status, err
    assert _the_one_line(err, run) == 0
    _clean(run)
