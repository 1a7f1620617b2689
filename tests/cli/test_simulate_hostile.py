"""`sonartrack simulate --kind active` against hostile scenes, rewrites, failures and kill -9 (issue 33).

Scenes are small (2-5 pings of sparse reverberation) and written in the test. Expected: a value that overflows
(1e300 dB, 1e300 m) or a reverberation asking for terabytes is refused in one line with its plausible range or
the memory it would take, before anything is written; a scene written over an earlier one replaces it whole
(its ping files, not the user's); a run that fails, is interrupted or killed leaves the folder as it was.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main

SPARSE = "[reverberation.boundary]\ndensity_per_km2 = {density}\nstrength_db = -50.0\nshape = 1.5\ndepth_m = 150.0\n"
TARGET = ('[[targets]]\nname = "t"\nx_m = {x}\ny_m = 3000.0\ncourse_deg = 0.0\nspeed_kn = 5.0\n'
          'target_strength_db = {ts}\n')


def scene_file(tmp_path, duration_s=60.0, density=1.0, x=3000.0, ts=10.0, extra="") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(f"duration_s = {duration_s}\n{extra}" + SPARSE.format(density=density)
                    + TARGET.format(x=x, ts=ts))
    return path


def simulate(capsys, scene, out):
    code = main(["simulate", "--kind", "active", "--scene", str(scene), "--out", str(out)])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.mark.parametrize("kwargs, needles", [
    ({"ts": "1e300"}, ["target_strength_db", "-100 <= target_strength_db <= 60", "dB re 1 m^2"]),
    ({"x": "1e300"}, ["x_m", "(m)"]),
    ({"extra": "noise_level_db = 1e300\n"}, ["noise_level_db", "dB re 1 uPa^2/Hz"]),
    ({"density": "1e10"}, ["GB of memory", "scatterers", "density_per_km2"]),
], ids=["target-strength-1e300-dB", "target-1e300-m-away", "noise-1e300-dB", "reverberation-of-terabytes"])
def test_a_scene_value_that_overflows_is_refused_before_writing(tmp_path, capsys, kwargs, needles):
    code, _, err = simulate(capsys, scene_file(tmp_path, **kwargs), tmp_path / "out")
    assert code == 2, err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, err
    for needle in needles:
        assert needle in err, (needle, err)
    assert not (tmp_path / "out").exists()


def ours(out: Path) -> dict[str, bytes]:
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def test_a_scene_written_over_an_earlier_one_replaces_it_whole(tmp_path, capsys):
    out = tmp_path / "out"
    assert simulate(capsys, scene_file(tmp_path, duration_s=150.0), out)[0] == 0  # 5 pings
    (out / "notes.txt").write_text("mine")
    (out / "pings" / "my_ping.npy").write_bytes(b"mine")
    code, _, err = simulate(capsys, scene_file(tmp_path, duration_s=60.0), out)  # 2 pings
    assert code == 0, err
    table = pd.read_csv(out / "ping_table.csv")
    assert sorted(p.name for p in (out / "pings").iterdir()) == ["my_ping.npy", "ping_0001.npy", "ping_0002.npy"]
    assert list(table["file"]) == ["pings/ping_0001.npy", "pings/ping_0002.npy"]
    assert (out / "notes.txt").read_text() == "mine"
    assert not [p for p in out.rglob(".*")]  # no temporary left


def test_a_run_failing_half_way_leaves_the_earlier_scene_as_it_was(tmp_path, capsys, monkeypatch):
    from sonartrack.sim import active_signals

    out = tmp_path / "out"
    assert simulate(capsys, scene_file(tmp_path, duration_s=90.0), out)[0] == 0
    before = ours(out)
    real = active_signals.ping_samples

    def fails_at_the_second_ping(settings, plat, k, *args):
        if k == 1:
            raise RuntimeError("disk on fire")
        return real(settings, plat, k, *args)

    monkeypatch.setattr(active_signals, "ping_samples", fails_at_the_second_ping)
    code, _, err = simulate(capsys, scene_file(tmp_path, duration_s=90.0, ts=20.0), out)
    assert code == 1 and "internal error" in err
    assert ours(out) == before


def test_a_run_killed_leaves_no_scene_and_the_next_run_cleans_up(tmp_path):
    out = tmp_path / "out"
    scene = scene_file(tmp_path, duration_s=3000.0, density=100.0)  # 100 pings: killed long before the end
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    proc = subprocess.Popen([sys.executable, "-m", "sonartrack.cli", "simulate", "--kind", "active", "--scene",
                             str(scene), "--out", str(out)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        while proc.poll() is None and not list((out / "pings").glob("*ping_0002*")):
            time.sleep(0.05)  # until the second ping is written (its temporary, then renamed at the end)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before it was killed: the test tests nothing"
    assert not (out / "ping_table.csv").exists()
    assert not list((out / "pings").glob("ping_*.npy"))  # no ping a reader could take for a scene
    assert main(["simulate", "--kind", "active", "--scene", str(scene_file(tmp_path)), "--out", str(out)]) == 0
    assert sorted(ours(out)) == ["nav.csv", "ping_table.csv", "pings/ping_0001.npy", "pings/ping_0002.npy",
                                 "scene.toml", "truth.csv"]  # the killed run's temporaries removed
    assert np.load(out / "pings" / "ping_0001.npy").shape == (16, 6000)


@pytest.fixture
def sigint_default():
    """Python's own SIGINT handler (a test run started in the background inherits an ignored SIGINT)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_an_interrupt_lost_in_a_compiled_call_is_still_an_interrupt(tmp_path, capsys, monkeypatch, sigint_default):
    from sonartrack.sim import active_signals

    def interrupted_in_numba(*args):  # the handler's exception comes out as SystemError without the interrupt
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            pass
        raise SystemError("CPUDispatcher(<function kernel>) returned a result with an exception set")

    monkeypatch.setattr(active_signals, "ping_samples", interrupted_in_numba)
    code, _, err = simulate(capsys, scene_file(tmp_path), tmp_path / "out")
    assert code == 130, err
    assert "interrupted: simulate keeps no part of an unfinished scene" in err and "internal error" not in err
    assert not (tmp_path / "out").exists()
