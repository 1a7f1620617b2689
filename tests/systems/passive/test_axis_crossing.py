"""A ship that crosses the array's axis (endfire) on a simulated recording: one target, its side per segment, and a
true bearing that stays continuous through the crossing."""

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.sim.passive_scene import scene_geometry
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.studies.passive_chain import Config, run_chain


def test_a_ship_crossing_the_axis_is_one_target_with_the_true_bearing_after_the_crossing():
    # own ship north at 6 kn turning 45 deg to port from 250 s; the array's axis sweeps past a ship astern to
    # starboard at ~350 s (cone angle through 180 deg), which is then on the port side
    scene = PassiveSceneSettings(
        duration_s=700.0, seed=21, ownship={"turn_start_s": 250.0},
        ships=[{"name": "crosser", "x_m": 3000.0, "y_m": -2500.0, "course_deg": 270.0, "speed_kn": 10.0,
                "depth_m": 6.0, "source_level_db": 147.0}])
    result, _ = run_chain(Config(scene=scene), scene)
    assert len(result.targets) == 1, [(t.track.time_s[0], t.track.time_s[-1]) for t in result.targets]
    tg = result.targets[0]
    t = tg.track.time_s
    g = scene_geometry(scene, t)
    truth_side = np.where(np.sin(g.bearing_rad[0] - g.array_heading_rad) >= 0, "starboard", "port")
    crossing = float(t[np.argmax(truth_side != truth_side[0])])
    assert truth_side[0] == "starboard" and truth_side[-1] == "port" and 300.0 < crossing < 400.0
    assert len(tg.side.crossings_s) == 1 and abs(tg.side.crossings_s[0] - crossing) < 20.0, tg.side.crossings_s
    assert np.mean(tg.side.side_at(t) == truth_side) > 0.95
    # the ML's true bearings (the record it solved) after the crossing: within 2 beamwidths of the truth
    err = np.rad2deg(np.abs(wrap_angle(tg.ml.record.bearing_rad - g.bearing_rad[0])))
    after = t > crossing + 20.0
    assert np.max(err[after]) < 2.0 * result.stages.min_separation_deg, np.max(err[after])
