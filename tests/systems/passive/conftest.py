"""A short simulated towed-array scene (the default ships, the ownship's turn early) for the chain's tests."""

import pytest

from sonartrack.cli import main

#: three ships well apart in cone angle (the default scene's merchant and tanker, a trawler abeam to starboard),
#: so that every target's bearings are clean of the others' beams and each ML can be judged against the truth
SCENE_TOML = """duration_s = 300.0
[ownship]
turn_start_s = 40.0

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

[[ships]]
name = "tanker"
x_m = -14300.0
y_m = -5000.0
course_deg = 20.0
speed_kn = 13.0
source_level_db = 149.0
tonal_hz = 90.0
tonal_level_db = 160.0
"""


@pytest.fixture(scope="session")
def scene_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("passive_scene")
    (out / "scene_in.toml").write_text(SCENE_TOML)
    assert main(["simulate", "--scene", str(out / "scene_in.toml"), "--only", "passive", "--out", str(out)]) == 0
    return out
