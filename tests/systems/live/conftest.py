"""A short simulated towed-array scene for the live chain's tests: two ships apart in cone angle, the turn early."""

from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.cli import main

SCENE_TOML = """duration_s = 150.0
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

#: the stream's UTC start (any: the recording's clock is the stream's index)
START = datetime(2026, 12, 7, 12, 0, tzinfo=UTC)


@pytest.fixture(scope="session")
def scene(tmp_path_factory):
    """(folder, samples (n, channels) float32, fs) of the scene."""
    import soundfile as sf

    out = tmp_path_factory.mktemp("live_scene")
    (out / "scene_in.toml").write_text(SCENE_TOML)
    assert main(["simulate", "--scene", str(out / "scene_in.toml"), "--only", "passive", "--out", str(out)]) == 0
    x, fs = sf.read(out / "recording.wav", dtype="float32")
    return out, np.ascontiguousarray(x), float(fs)
