"""`sonartrack tma` on a zig-zagging target reports its legs (issue 30): the zigs and legs printed, tma_legs.csv
near the truth, no determined constant-velocity row; on a constant-velocity target one leg and a determined answer
with the observer advice. Worlds built here with numpy alone."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main

KN = 1852.0 / 3600.0
CHANGES_S = (1800.0, 3600.0)


def legs(t, p0, change_times, velocities):
    """Continuous piecewise-constant-velocity positions (n, 2)."""
    edges = np.r_[t[0], change_times, np.inf]
    a = np.clip(t[:, None] - edges[:-1], 0.0, edges[1:] - edges[:-1])
    return np.asarray(p0, float) + a @ np.asarray(velocities, float)


def vel(course_deg, speed_kn):
    c = np.radians(course_deg)
    return speed_kn * KN * np.array([np.sin(c), np.cos(c)])


def write_record(folder, zig: bool, seed: int = 4):
    """Bearings every 40 s for 90 min, 0.5 deg noise; ownship at 6 kn on 15-min legs (000/080); target 8 km north
    at 10 kn on 090, then (zig) 180 at 10 kn and 045 at 14 kn. Returns the true course (deg), speed (kn) and
    position at the record's end of each leg."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 5400.0, 40.0)
    own = legs(t, [0.0, 0.0], 900.0 * np.arange(1, 6), [vel(c, 6) for c in (0, 80, 0, 80, 0, 80)])
    courses, speeds = ((90, 180, 45), (10, 10, 14)) if zig else ((90,), (10,))
    changes = CHANGES_S if zig else ()
    V = [vel(c, s) for c, s in zip(courses, speeds, strict=True)]
    tgt = legs(t, [1000.0, 8000.0], changes, V)
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1]) + rng.normal(0, np.radians(0.5), len(t))
    pd.DataFrame({"time_s": t, "bearing_deg": np.degrees(z) % 360}).to_csv(folder / "brg.csv", index=False)
    pd.DataFrame({"time_s": t, "x_m": own[:, 0], "y_m": own[:, 1]}).to_csv(folder / "own.csv", index=False)
    return courses, speeds, tgt[-1]


def run(capsys, folder, *extra):
    code = main(["tma", "--bearings", str(folder / "brg.csv"), "--ownship", str(folder / "own.csv"), "--method",
                 "ml", "--out", str(folder / "out"), *extra])
    out = capsys.readouterr()
    return code, out.out


def angle_diff(a, b):
    return (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0


@pytest.mark.parametrize("extra", [("--sigma-bearing-deg", "0.5"), ()], ids=["sd-given", "sd-estimated"])
def test_a_zig_zag_record_prints_its_legs_near_the_truth_and_no_determined_cv_row(tmp_path, capsys, extra):
    courses, speeds, end_xy = write_record(tmp_path, zig=True)
    code, out = run(capsys, tmp_path, *extra)
    assert code == 0
    assert "target manoeuvred" in out and "legs: 2 zigs" in out
    assert all(f"leg {k}" in out for k in (1, 2, 3)) and "leg 3 (current)" in out
    solution = pd.read_csv(tmp_path / "out" / "tma_solution.csv")
    assert not solution["range_determined"].any()  # the constant-velocity rows: none determined
    table = pd.read_csv(tmp_path / "out" / "tma_legs.csv")
    assert len(table) == 3 and table["current"].tolist() == [False, False, True]
    assert table["determined"].all()
    assert np.all(np.abs(table["zig_lo_s"][1:].to_numpy() - CHANGES_S) < 600.0)
    assert np.all(np.abs(angle_diff(table["course_deg"], courses)) <= 3 * table["course_sd_deg"])
    assert np.all(np.abs(table["speed_kn"] - speeds) <= 3 * table["speed_sd_kn"])
    last = table.iloc[-1]
    assert abs(last["x_m"] - end_xy[0]) <= 3 * last["x_sd_m"] and abs(last["y_m"] - end_xy[1]) <= 3 * last["y_sd_m"]
    assert "current leg (leg-wise ML, since" in out and "advice: turn to" in out


def test_a_constant_velocity_record_prints_one_leg_and_a_determined_answer(tmp_path, capsys):
    courses, speeds, end_xy = write_record(tmp_path, zig=False)
    code, out = run(capsys, tmp_path, "--sigma-bearing-deg", "0.5")
    assert code == 0
    assert "legs: 0 zigs; 1 leg" in out and "leg 1 (current)" in out and "NOT DETERMINED" not in out
    solution = pd.read_csv(tmp_path / "out" / "tma_solution.csv")
    assert solution["range_determined"].iloc[-1]
    table = pd.read_csv(tmp_path / "out" / "tma_legs.csv")
    assert len(table) == 1 and table["determined"].iloc[0]
    assert abs(angle_diff(table["course_deg"].iloc[0], courses[0])) <= 3 * table["course_sd_deg"].iloc[0]
    assert "advice: turn to" in out and "current leg (leg-wise ML" not in out  # the method's own answer stands


def test_no_leg_faster_than_any_ship_is_printed_as_determined(tmp_path, capsys):
    """The shipped zigzag scene's bearings (three zigs, one of them missed by the detector at its stated rate): the
    leg fit ran to 696 kn on its first leg and printed the current leg at 40 ± 16 km for a target at 4-12 km.
    Every leg of a fit with a leg beyond the verdict's speed bound (58 kn) is now not determined."""
    from sonartrack.tma.settings import VerdictSettings

    scene, out = tmp_path / "zz", tmp_path / "tma"
    assert main(["simulate", "--scene", "zigzag", "--only", "samples", "--out", str(scene)]) == 0
    assert main(["tma", "--bearings", str(scene / "brg.csv"), "--ownship", str(scene / "own.csv"), "--method", "ml",
                 "--out", str(out)]) == 0
    legs_table = pd.read_csv(out / "tma_legs.csv")
    fast = legs_table["speed_kn"] * KN > VerdictSettings().max_speed_mps
    if fast.any():
        assert not legs_table["determined"].any()
        assert legs_table["reason"].str.contains("faster than any ship").all()
    assert "current leg (leg-wise ML" not in capsys.readouterr().out or not fast.any()
