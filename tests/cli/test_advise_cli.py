"""`sonartrack advise` on files synthesised here (numpy, not the project's simulator): the advice line, the outputs,
and one-line errors for bad input."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main


def _ownship(t):
    """20 min east at 5 m/s, then north-east at 5 m/s."""
    ne = np.array([np.sin(np.radians(45.0)), np.cos(np.radians(45.0))])
    return np.where(t[:, None] < 1200, np.c_[5 * t, 0 * t], np.array([6000.0, 0.0]) + 5 * (t[:, None] - 1200) * ne)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("advise")
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 1800.0 + 1e-9, 30.0)
    x0 = np.array([2000.0, 12000.0, -4.0, 1.0])
    rel = x0[:2] + np.outer(t, x0[2:]) - _ownship(t)
    z = np.degrees(np.arctan2(rel[:, 0], rel[:, 1])) + 0.5 * rng.standard_normal(len(t))
    pd.DataFrame({"time_s": t, "bearing_deg": z % 360.0}).to_csv(d / "bearings.csv", index=False)
    tn = np.arange(0.0, 1800.0 + 1e-9, 2.0)
    pos = np.round(_ownship(tn) + 7.0 * rng.standard_normal((len(tn), 2)))
    pd.DataFrame({"time_s": tn, "x_m": pos[:, 0], "y_m": pos[:, 1]}).to_csv(d / "own.csv", index=False)
    # an ownship that never turns: the bearings alone give no range
    pd.DataFrame({"time_s": tn, "x_m": 5.0 * tn, "y_m": 0.0 * tn}).to_csv(d / "straight.csv", index=False)
    pd.DataFrame({"time_s": tn[tn < 1000], "x_m": pos[tn < 1000, 0], "y_m": pos[tn < 1000, 1]}).to_csv(
        d / "short.csv", index=False)
    return d


def _solution_csv(path, **over):
    row = dict(time_s=1800.0, x_m=-5200.0, y_m=13800.0, vx_mps=-4.0, vy_mps=1.0, course_deg=284.0, speed_kn=8.0,
               range_m=15000.0, bearing_deg=310.0, range_std_m=2000.0, bearing_std_deg=0.5, speed_std_kn=1.0,
               course_std_deg=10.0, range_determined=True, undetermined_reason="")
    row.update(over)
    pd.DataFrame([row]).to_csv(path, index=False)
    return path


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_advise_from_bearings_prints_the_advice_and_writes_outputs(files, tmp_path, capsys):
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "advise", "--ownship", files / "own.csv", "--bearings", files / "bearings.csv",
                            "--out", out)
    assert code == 0, err
    assert stdout.count("\n") == 1 and stdout.startswith("advice: turn to ")
    assert "predicted range sd" in stdout and "after 25 min" in stdout and "alternatives: " in stdout
    df = pd.read_csv(out / "advice.csv")
    assert len(df) == 36 * 3 and df.advised.sum() == 1 and df.alternative.sum() == 3
    best = df[df.advised].iloc[0]
    assert best.range_sd_m == df.range_sd_m.min()
    assert f"turn to {best.course_deg:03.0f} deg" in stdout
    assert (out / "advice.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_advise_from_a_solution_table_warns_of_the_missing_correlations(files, tmp_path, capsys):
    sol = _solution_csv(tmp_path / "tma_solution.csv")
    code, stdout, err = run(capsys, "advise", "--ownship", files / "own.csv", "--solution", sol, "--solution", sol,
                            "--out", tmp_path / "o")
    assert code == 0, err
    assert "uncorrelated" in err and "(max over 2 targets)" in stdout


@pytest.mark.parametrize(("case", "needle"), [
    ("no-ownship", "--ownship"),
    ("no-target", "give at least one target"),
    ("undetermined", "not determined (unobservable)"),
    ("missing-column", "lacks column(s) range_std_m"),
    ("zero-sd", "'range_std_m' is 0"),
    ("nav-too-short", "the ownship file spans"),
    ("straight-ownship", "range is unobservable"),
    ("bad-sigma", "sigma_bearing_deg"),
    ("bad-objective", "objective"),
    ("interval-over-horizon", "not shorter than the horizon"),
])
def test_bad_input_gives_one_line(files, tmp_path, capsys, case, needle):
    sol = tmp_path / "sol.csv"
    own = files / "own.csv"
    args = ["--solution", _solution_csv(sol)]
    if case == "no-ownship":
        own = None
    elif case == "no-target":
        args = []
    elif case == "undetermined":
        _solution_csv(sol, range_determined=False, undetermined_reason="unobservable")
    elif case == "missing-column":
        pd.read_csv(_solution_csv(sol)).drop(columns=["range_std_m"]).to_csv(sol, index=False)
    elif case == "zero-sd":
        _solution_csv(sol, range_std_m=0.0)
    elif case == "nav-too-short":
        own = files / "short.csv"
    elif case == "straight-ownship":
        own, args = files / "straight.csv", ["--bearings", files / "bearings.csv"]
    elif case == "bad-sigma":
        args += ["--sigma-bearing-deg", "-1"]
    elif case == "bad-objective":
        args += ["--objective", "median"]
    elif case == "interval-over-horizon":
        args += ["--interval-s", "2000"]
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "advise", *(["--ownship", own] if own else []), *args, "--out", out)
    assert code == 2 and err.startswith("error: ") and err.count("\n") == 1, err
    assert needle in err and "Traceback" not in err
    assert not out.exists()  # nothing half-written
