"""`sonartrack tma` on files synthesised here: outputs, accuracy, options, and bad input."""

import re
import tomllib

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.units import KNOT_MPS as KN
from sonartrack.models.passive import bf_measurement
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.records import TmaSolution


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Noise-free bearings + frequencies of a CV target (10 kn, 10 km) from a zig-zagging ownship,
    ownship navigation every 10 s (wider span than the record), bearings in 0..360."""
    d = tmp_path_factory.mktemp("tma")
    t = np.arange(0.0, 1600.0 + 1e-9, 4.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KN, np.deg2rad(45), ((500.0, 540.0, np.deg2rad(-2.25)),
                                                             (1100.0, 1140.0, np.deg2rad(2.25))))
    tgt = ManeuveringTrack(-3000.0, 9500.0, 10 * KN, np.deg2rad(100))
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    z = bf_measurement(np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)]))
    pd.DataFrame({"time_s": t, "bearing_deg": np.rad2deg(z[:, 0]) % 360.0, "frequency_hz": z[:, 1]}).to_csv(
        d / "bearings.csv", index=False)
    tn = np.arange(-20.0, 1620.0, 10.0)
    pn, _, _ = obs.state(tn)
    pd.DataFrame({"time_s": tn, "x_m": pn[:, 0], "y_m": pn[:, 1]}).to_parquet(d / "own.parquet")
    return d, np.column_stack([pt, vt])


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("method", ["ekf", "mgekf", "imm-mgekf"])
def test_tma_tracks_the_target_and_writes_outputs(files, tmp_path, capsys, method):
    d, truth = files
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                            "--frequency", "--method", method, "--out", out)
    assert code == 0, err
    lines = stdout.splitlines()  # the summary, then the zigs and legs (issue 30), one line each
    assert f"tma {method}" in lines[0] and "f0 300.0" in lines[0]
    assert lines[1].startswith("legs: 0 zigs; 1 leg") and lines[2].startswith("  leg 1 (current)")
    df = pd.read_csv(out / "tma_solution.csv")
    assert len(df) == len(truth)
    last = df.iloc[-1]
    assert np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1]) < 100.0
    assert last.course_deg == pytest.approx(100.0, abs=1.0) and last.speed_kn == pytest.approx(10.0, abs=0.1)
    assert last.range_std_m > 0 and last.course_std_deg > 0
    png = (out / "tactical_picture.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in out.iterdir()) == ["tactical_picture.png", "tma_legs.csv", "tma_solution.csv"]


def test_bearings_only_with_config_file(files, tmp_path, capsys):
    d, truth = files
    cfg = tmp_path / "tma.toml"
    cfg.write_text('method = "mgekf"\n[sequential]\nq_single = 1e-8\ninitial_range_m = 8000.0\n')
    code, stdout, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                            "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    assert "tma mgekf" in stdout and "bearings over" in stdout
    last = pd.read_csv(tmp_path / "o" / "tma_solution.csv").iloc[-1]
    assert np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1]) < 200.0


@pytest.mark.parametrize("args,needle", [
    (["--method", "kalman"], "'method'"),
    (["--method", "ekf", "--env", "east-sea"], "--env and --sl"),
    (["--method", "ml", "--frequency"], "--frequency applies"),
    (["--sigma-bearing-deg", "-1"], "sigma_bearing_deg"),
])
def test_bad_options(files, tmp_path, capsys, args, needle):
    d, _ = files
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--out", tmp_path / "o", *args)
    assert code == 2 and err.startswith("error: ") and needle in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_unknown_config_key(files, tmp_path, capsys):
    d, _ = files
    cfg = tmp_path / "tma.toml"
    cfg.write_text("[sequential]\nq_singel = 1e-3\n")
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--config", cfg, "--out", tmp_path / "o")
    assert code == 2 and "q_singel" in err
    cfg.write_text("q_single = 1e-3\n")  # a key of the [sequential] table at the top level
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--config", cfg, "--out", tmp_path / "o")
    assert code == 2 and "q_single" in err


def test_bad_files(files, tmp_path, capsys):
    d, _ = files
    b = pd.read_csv(d / "bearings.csv")
    unsorted = tmp_path / "unsorted.csv"
    b.iloc[[1, 0] + list(range(2, len(b)))].to_csv(unsorted, index=False)
    code, _, err = run(capsys, "tma", "--bearings", unsorted, "--ownship", d / "own.parquet", "--out", tmp_path / "o")
    assert code == 2 and "sort the file by time" in err
    radians = tmp_path / "rad.csv"
    b.assign(bearing_deg=np.deg2rad(b.bearing_deg) - np.pi).to_csv(radians, index=False)
    code, _, err = run(capsys, "tma", "--bearings", radians, "--ownship", d / "own.parquet", "--out", tmp_path / "o")
    assert code == 2 and "radians" in err
    short_own = tmp_path / "own.csv"
    pd.read_parquet(d / "own.parquet").iloc[:100].to_csv(short_own, index=False)
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", short_own, "--out", tmp_path / "o")
    assert code == 2 and "outside the ownship file's span" in err
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--method", "ekf", "--frequency", "--out", tmp_path / "o")
    assert code == 0  # the same files are fine
    nofreq = tmp_path / "nofreq.csv"
    b.drop(columns="frequency_hz").to_csv(nofreq, index=False)
    code, _, err = run(capsys, "tma", "--bearings", nofreq, "--ownship", d / "own.parquet", "--frequency",
                       "--out", tmp_path / "o2")
    assert code == 2 and "frequency_hz column" in err
    assert not (tmp_path / "o2").exists()


def test_print_config_shows_defaults_then_config_then_options(tmp_path, capsys):
    cfg = tmp_path / "tma.toml"
    cfg.write_text('method = "ml"\nsigma_bearing_deg = 0.5\n[batch]\nsl_db = 140.0\ndepth_m = 50.0\n')
    code, out, err = run(capsys, "tma", "--config", cfg, "--sigma-bearing-deg", "2", "--env", "east-summer",
                         "--print-config")
    assert code == 0, err
    data = tomllib.loads(out)  # valid TOML, which --config reads back
    assert data["method"] == "ml" and data["sigma_bearing_deg"] == 2.0  # the option beats the file
    assert data["batch"] == {**data["batch"], "env": "east-summer", "sl_db": 140.0, "depth_m": 50.0}
    assert data["imm"]["q_values"] == [1e-5, 1e-3, 1e-1]  # untouched defaults
    line = next(row for row in out.splitlines() if row.startswith("sigma_bearing_deg"))
    assert "# bearing noise standard deviation" in line and "deg" in line.split("#")[1]  # doc and unit
    again = tmp_path / "again.toml"
    again.write_text(out)
    code, out2, _ = run(capsys, "tma", "--config", again, "--print-config")
    assert code == 0 and out2 == out


def test_missing_inputs(tmp_path, capsys):
    code, _, err = run(capsys, "tma", "--out", tmp_path / "o")
    assert code == 2 and "--bearings FILE --ownship FILE" in err


def test_the_command_calls_the_library_with_the_resolved_settings(files, tmp_path, capsys, monkeypatch):
    """The face only wires: options and config become TmaSettings, the tma system's solve (tma/solve.py
    solve_tma) gets the files' records and the environment, and what it returns is written and summarised."""
    import sonartrack.systems.tma.run as run_mod
    import sonartrack.tma.solve as solve_mod

    d, truth = files
    calls = {}

    def fake_solve_tma(record, ownship, settings, **kw):
        calls.update(settings=settings, n=len(record.time_s), nav=len(ownship.time_s), env=kw["environment"])
        X = np.tile(truth[0], (len(record.time_s), 1))
        sol = TmaSolution(time_s=record.time_s, state=X, covariance=np.tile(np.eye(4), (len(X), 1, 1)), method="ml")
        return solve_mod.TmaResult(solution=sol, record=record, ownship=ownship, settings=settings,
                                   warnings=("a warning",))

    monkeypatch.setattr(run_mod, "solve_tma", fake_solve_tma)
    cfg = tmp_path / "c.toml"
    cfg.write_text("[batch]\nsl_db = 140.0\nfreq_hz = 300.0\n")
    code, stdout, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                            "--method", "ml", "--sigma-bearing-deg", "2", "--sl", "150", "--env", "east-summer",
                            "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    s = calls["settings"]
    assert (s.method, s.sigma_bearing_deg, s.batch.sl_db, s.batch.freq_hz) == ("ml", 2.0, 150.0, 300.0)
    assert calls["n"] == len(truth) and calls["nav"] == 164 and calls["env"].name == "east-summer"
    assert err == "warning: a warning\n" and stdout.startswith("tma ml: ") and "\nlegs: " in stdout
    assert len(pd.read_csv(tmp_path / "o" / "tma_solution.csv")) == len(truth)
    assert (tmp_path / "o" / "tactical_picture.png").exists()


def test_an_undetermined_range_is_printed_as_such_with_its_reason(tmp_path, capsys):
    """An ownship on one straight leg: the bearings do not observe range, and the IMM-MGEKF's range sd never
    leaves its prior's; the line says so and gives no range, the CSV says why on every row."""
    t = np.arange(0.0, 1200.0 + 1e-9, 8.0)
    po, vo, _ = ManeuveringTrack(0.0, 0.0, 5 * KN, np.deg2rad(45)).state(t)
    pt, vt, _ = ManeuveringTrack(-3000.0, 9500.0, 10 * KN, np.deg2rad(100)).state(t)
    z = bf_measurement(np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)]))[:, 0]
    z = z + np.random.default_rng(5).normal(0.0, np.deg2rad(0.5), len(t))
    pd.DataFrame({"time_s": t, "bearing_deg": np.rad2deg(z) % 360.0}).to_csv(tmp_path / "b.csv", index=False)
    pd.DataFrame({"time_s": t, "x_m": po[:, 0], "y_m": po[:, 1]}).to_csv(tmp_path / "o.csv", index=False)
    code, stdout, err = run(capsys, "tma", "--bearings", tmp_path / "b.csv", "--ownship", tmp_path / "o.csv",
                            "--method", "imm-mgekf", "--sigma-bearing-deg", "0.5", "--out", tmp_path / "out")
    assert code == 0, err
    assert "range NOT DETERMINED (unobservable)" in stdout
    line = stdout.split("; wrote ")[0]
    assert " km" not in line and not re.search(r"(course|speed) \d", line)
    df = pd.read_csv(tmp_path / "out" / "tma_solution.csv")
    assert not df["range_determined"].any() and set(df["undetermined_reason"]) == {"unobservable"}
