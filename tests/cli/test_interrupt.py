"""Interrupting `sonartrack reproduce`: Ctrl-C and SIGTERM end cleanly and say what was kept; a kill -9 leaves
no child process behind.

The runs use a test-only study whose trials sleep a known time (a file written into tmp_path and registered
by a two-line launcher that then calls the real entry point, :func:`sonartrack.cli.main`): slow enough to be
interrupted mid-run, fast enough for a test. Each trial also appends a line to a log file, so a rerun is seen
to compute exactly the trials that were not kept. Processes are found through /proc by session id: each run
is started in a session of its own, whose id is the parent's pid, and every child it starts stays in it.
"""

import contextlib
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from sonartrack import cli
from sonartrack.experiment import store

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc") or os.name != "posix", reason="needs POSIX and /proc")

RUNS = 40
TOY_STUDY = '''
import os
import time

import numpy as np
from pydantic import BaseModel

STUDY_ID, TITLE, PAPER, TRIAL_VERSION, CHUNK_SIZE = "toy-slow", "A slow toy", "none", 1, 2


class Config(BaseModel):
    runs: int = 40
    trial_s: float = 0.05

    @classmethod
    def quick(cls):
        return cls()


def run_trial(config, rng):
    time.sleep(config.trial_s)
    with open(os.environ["TOY_TRIAL_LOG"], "a") as log:
        log.write("trial\\n")
    return {"x": rng.normal(size=2)}


def summarize(trials, config):
    return {"mean": float(np.mean(trials["x"]))}


def claims(summary, config):
    return []
'''
LAUNCHER = ("import sys; from sonartrack import studies; studies.STUDIES['toy-slow'] = 'toy_slow_study'; "
            "from sonartrack.cli import main; sys.exit(main(sys.argv[1:]))")


def _sigint_default():
    # a job started in the background by a non-interactive shell inherits SIGINT ignored (and keeps it so)
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class ToyRun:
    """`reproduce toy-slow --runs 40 --workers 2` in a session of its own."""

    def __init__(self, tmp_path):
        (tmp_path / "toy_slow_study.py").write_text(TOY_STUDY)
        self.out, self.log = tmp_path / "out", tmp_path / "trials.log"
        self.env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]),
                    "TOY_TRIAL_LOG": str(self.log)}
        self.cmd = [sys.executable, "-c", LAUNCHER, "reproduce", "toy-slow", "--runs", str(RUNS), "--workers", "2",
                    "--out", str(self.out), "--seed", "5"]
        self.proc = None

    def start(self):
        self.log.write_text("")
        self.proc = subprocess.Popen(self.cmd, env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True, start_new_session=True, preexec_fn=_sigint_default)
        return self

    def rerun(self):
        self.log.write_text("")
        return subprocess.run(self.cmd, env=self.env, capture_output=True, text=True, timeout=120)

    def stored(self) -> int:
        return sum(len(store.done_indices(d)) for d in self.out.glob("toy-slow/cache/*"))

    def computed(self) -> int:
        return len(self.log.read_text().splitlines())

    def wait_for(self, condition, timeout=60.0):
        deadline = time.monotonic() + timeout
        while not condition():
            assert self.proc.poll() is None, f"the run ended early: {self.proc.stderr.read()}"
            assert time.monotonic() < deadline, "timed out"
            time.sleep(0.01)

    def session(self) -> list[int]:
        """Live processes (zombies are dead: left out) of the run's session, the parent included."""
        return _live_in_session(self.proc.pid)

    def survivors(self, grace_s=5.0) -> list[int]:
        """The session's processes still alive ``grace_s`` after the parent ended (the fork server and the
        resource tracker end on their own once the parent's pipes close: a few milliseconds)."""
        deadline = time.monotonic() + grace_s
        while self.session() and time.monotonic() < deadline:
            time.sleep(0.01)
        return [f"{pid}: {_cmdline(pid)}" for pid in self.session()]

    def kill_leftovers(self):
        if self.proc is not None:
            for pid in self.session():
                with_suppress_kill(pid)
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()


def with_suppress_kill(pid):
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGKILL)


def _cmdline(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline") as f:
            return f.read().replace("\0", " ")[:120]
    except OSError:
        return "?"


def _live_in_session(sid: int) -> list[int]:
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
        except OSError:  # ended meanwhile
            continue
        state, _ppid, _pgrp, session = stat[stat.rfind(")") + 2:].split()[:4]
        if int(session) == sid and state not in "ZX":
            pids.append(int(entry))
    return pids


@pytest.fixture
def toy(tmp_path):
    run = ToyRun(tmp_path)
    yield run
    run.kill_leftovers()


def _interrupt_line(stderr: str, out) -> int:
    """N from the one line the run ends with; nothing else may look like an error."""
    assert "Traceback" not in stderr and "Error" not in stderr, stderr
    lines = [ln for ln in stderr.splitlines() if ln.startswith("interrupted:")]
    assert len(lines) == 1, stderr
    m = re.fullmatch(rf"interrupted: (\d+) trials kept \(of {RUNS}\) in {re.escape(str(out))}; "
                     r"run the same command to resume", lines[0])
    assert m, lines[0]
    return int(m.group(1))


def test_ctrl_c_keeps_the_stored_trials_and_a_rerun_computes_only_the_rest(toy):
    """SIGINT to the process group, as a terminal sends it on Ctrl-C."""
    toy.start()
    toy.wait_for(lambda: toy.stored() >= 2)
    os.killpg(toy.proc.pid, signal.SIGINT)
    _, err = toy.proc.communicate(timeout=30)
    assert toy.proc.returncode == 130, err
    kept = _interrupt_line(err, toy.out)
    assert kept == toy.stored() and 0 < kept < RUNS
    assert not list(toy.out.rglob(".*tmp*")), "a half-written file was left"
    assert toy.survivors() == []

    res = toy.rerun()
    assert res.returncode == 0, res.stderr
    assert toy.computed() == RUNS - kept  # the kept trials are not computed again
    assert f"{RUNS} runs ({RUNS - kept} computed, {kept} from disk)" in res.stderr


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_to_the_parent_alone_ends_it_cleanly_with_its_workers(toy, signum, status):
    """`kill -INT pid` / `kill pid`: the workers never see the signal; the parent stops them."""
    toy.start()
    toy.wait_for(lambda: toy.stored() >= 2)
    os.kill(toy.proc.pid, signum)
    _, err = toy.proc.communicate(timeout=30)
    assert toy.proc.returncode == status, err
    assert _interrupt_line(err, toy.out) == toy.stored()
    assert toy.survivors() == []


def test_sigterm_to_the_group_ends_cleanly(toy):
    """As a service manager stops a job: SIGTERM to every process of the group."""
    toy.start()
    toy.wait_for(lambda: toy.stored() >= 2)
    os.killpg(toy.proc.pid, signal.SIGTERM)
    _, err = toy.proc.communicate(timeout=30)
    assert toy.proc.returncode == 143, err
    assert _interrupt_line(err, toy.out) == toy.stored()


def test_no_child_outlives_a_parent_killed_with_sigkill(toy):
    """kill -9 of the parent: workers, fork server and resource tracker are all gone within seconds."""
    toy.start()
    # the parent, the resource tracker, the fork server and the 2 workers, and trials under way
    toy.wait_for(lambda: len(toy.session()) >= 5 and toy.stored() >= 2)
    os.kill(toy.proc.pid, signal.SIGKILL)
    toy.proc.wait()
    assert toy.survivors() == []


@pytest.fixture
def signalling_app(monkeypatch):
    """A stand-in app whose command signals its own process, as a terminal or `kill` would."""
    import typer

    app = typer.Typer(add_completion=False, pretty_exceptions_enable=False)

    @app.command()
    def hit(sig: str):
        os.kill(os.getpid(), getattr(signal, sig))
        time.sleep(5)  # the handler interrupts this at once
        raise AssertionError("not interrupted")

    @app.command()
    def ignored():
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN

    monkeypatch.setattr(cli, "app", app)


@pytest.fixture
def sigint_default():
    """Python's own SIGINT handler for the test: a test run started as a background job inherits an ignored SIGINT,
    which main() rightly keeps ignored (test_an_ignored_sigint_stays_ignored)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


@pytest.mark.parametrize("sig, status", [("SIGINT", 130), ("SIGTERM", 143)])
def test_other_commands_get_the_generic_line(signalling_app, sigint_default, capsys, sig, status):
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    assert cli.main(["hit", sig]) == status
    assert capsys.readouterr().err == cli.INTERRUPTED + "\n"
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before  # handlers given back


def test_an_ignored_sigint_stays_ignored(signalling_app, monkeypatch):
    """A job started in the background by a shell script ignores SIGINT; main() must not undo that."""
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert cli.main(["ignored"]) == 0
    finally:
        signal.signal(signal.SIGINT, old)
