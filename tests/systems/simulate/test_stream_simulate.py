"""`simulate --stream`: the decoded stream equals the recording.wav simulate writes for the same scene and seed,
the NMEA over UDP is the scene's navigation, and the command prints its port, ends when the scene ends, and ends
with 130 and its own line on Ctrl-C."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import soundfile as sf

from sonartrack.io.stream.nav import UdpNmeaSource
from sonartrack.io.stream.tcp import TcpSampleSource
from sonartrack.io.stream.types import NavFix, SampleBlock, StreamEvent
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.stream import SceneStreamer

SRC = str(Path(__file__).resolve().parents[3] / "src")


def _scene():
    return PassiveSceneSettings().model_copy(update=dict(duration_s=2.0, seed=7))


def test_stream_equals_the_wav_and_the_nav_is_the_scene(tmp_path):
    scene = _scene()
    nav = UdpNmeaSource(0).start()
    streamer = SceneStreamer(scene, speed=200.0, nav_udp=nav.port)
    done = {}
    server = threading.Thread(target=lambda: done.setdefault("summary", streamer.serve()))
    server.start()
    with TcpSampleSource("127.0.0.1", streamer.port) as source:
        items = list(source)
    server.join()
    fixes = []
    for item in nav:
        fixes.append(item)
        if len(fixes) == 3:
            break
    nav.close()
    assert [i.kind for i in items if isinstance(i, StreamEvent)] == ["connected"]
    blocks = [i for i in items if isinstance(i, SampleBlock)]
    assert np.array_equal([b.first_index for b in blocks], np.cumsum([0] + [b.samples.shape[0] for b in blocks[:-1]]))
    write_scene(scene, tmp_path, only="passive")
    wav, fs = sf.read(tmp_path / "recording.wav", dtype="float32")
    assert fs == scene.sample_rate_hz and source.header.channels == wav.shape[1]
    assert np.array_equal(np.concatenate([b.samples for b in blocks]), wav)  # float32 both: bit for bit
    table = pd.read_csv(tmp_path / "nav.csv")
    assert all(isinstance(f, NavFix) for f in fixes)
    assert [(f.utc - source.header.start_utc).total_seconds() for f in fixes] == list(table["time_s"])
    assert np.allclose([f.heading_deg for f in fixes], table["heading_deg"] % 360, atol=0.006)
    assert done["summary"].connections == 1 and done["summary"].seconds == 2.0


def _start(args):
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "sonartrack.cli", "simulate", "--stream", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    line = proc.stdout.readline()
    port = re.search(r"tcp://127\.0\.0\.1:(\d+)", line)
    assert port, (line, proc.stderr.read() if proc.poll() is not None else "")
    return proc, int(port.group(1)), line


@pytest.mark.skipif(os.name != "posix", reason="signals")
def test_cli_prints_its_port_and_streams_the_scene():
    proc, port, line = _start(["--duration-s", "1", "--speed", "100"])
    assert "waiting for the live side to connect" in line
    with TcpSampleSource("127.0.0.1", port) as source:
        n = sum(i.samples.shape[0] for i in source if isinstance(i, SampleBlock))
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and n == 4000 and "streamed 1 s" in out, err


@pytest.mark.skipif(os.name != "posix", reason="signals")
def test_cli_ctrl_c_ends_with_130_and_its_line():
    proc, port, _ = _start(["--duration-s", "1"])
    proc.send_signal(signal.SIGINT)  # while it waits for the live side
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "interrupted: simulate --stream stopped" in err
    assert "Traceback" not in err


def test_stream_options_without_stream_are_refused():
    from sonartrack.cli import main

    assert main(["simulate", "--port", "5000", "--out", "unused"]) == 2
    # (--stream --kind active is a valid stream of pings now: the file-layout options stay refused with --stream)
    assert main(["simulate", "--stream", "--kind", "active", "--split-s", "60"]) == 2
    assert main(["simulate", "--stream", "--split-s", "60"]) == 2
