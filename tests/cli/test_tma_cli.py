"""`sonartrack tma` on files synthesised here: outputs, accuracy, options, and bad input."""

import sys
import types

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.io.records import TmaSolution
from sonartrack.models.passive import bf_measurement
from sonartrack.sim.platforms import ManeuveringTrack

KN = 1852.0 / 3600.0


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
    assert stdout.count("\n") == 1 and f"tma {method}" in stdout and "f0 300.0" in stdout
    df = pd.read_csv(out / "tma_solution.csv")
    assert len(df) == len(truth)
    last = df.iloc[-1]
    assert np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1]) < 100.0
    assert last.course_deg == pytest.approx(100.0, abs=1.0) and last.speed_kn == pytest.approx(10.0, abs=0.1)
    assert last.range_std_m > 0 and last.course_std_deg > 0
    png = (out / "tactical_picture.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in out.iterdir()) == ["tactical_picture.png", "tma_solution.csv"]


def test_bearings_only_with_config_file(files, tmp_path, capsys):
    d, truth = files
    cfg = tmp_path / "tma.toml"
    cfg.write_text('method = "mgekf"\nq_single = 1e-8\ninitial_range_m = 8000.0\n')
    code, stdout, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                            "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    assert "tma mgekf" in stdout and "bearings over" in stdout
    last = pd.read_csv(tmp_path / "o" / "tma_solution.csv").iloc[-1]
    assert np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1]) < 200.0


@pytest.mark.parametrize("args,needle", [
    (["--method", "kalman"], "unknown --method"),
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
    cfg.write_text("q_singel = 1e-3\n")
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--config", cfg, "--out", tmp_path / "o")
    assert code == 2 and "q_singel" in err


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


def test_batch_method_missing_gives_clear_error(files, tmp_path, capsys, monkeypatch):
    d, _ = files
    monkeypatch.setitem(sys.modules, "sonartrack.tma.batch", None)  # import fails
    code, _, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                       "--method", "em-map", "--out", tmp_path / "o")
    assert code == 2 and "method 'em-map' is not available in this installation" in err


def test_batch_method_is_called_with_the_shared_interface(files, tmp_path, capsys, monkeypatch):
    d, truth = files
    calls = {}

    def solve_batch(record, ownship, method, *, sigma_bearing_rad, sigma_snr_db=1.0, env=None, sl_db=None,
                    freq_hz=200.0, depth_m=None, **extra):
        calls.update(method=method, sigma=sigma_bearing_rad, env=env, sl=sl_db, n=len(record.time_s),
                     nav=len(ownship.time_s), freq_hz=freq_hz)
        X = np.tile(truth[0], (len(record.time_s), 1))
        return TmaSolution(record.time_s, X, np.tile(np.eye(4), (len(X), 1, 1)), method)

    fake = types.ModuleType("sonartrack.tma.batch")
    fake.solve_batch = solve_batch
    monkeypatch.setitem(sys.modules, "sonartrack.tma.batch", fake)
    code, stdout, err = run(capsys, "tma", "--bearings", d / "bearings.csv", "--ownship", d / "own.parquet",
                            "--method", "ml", "--sigma-bearing-deg", "2", "--env", "east-sea", "--sl", "150",
                            "--out", tmp_path / "o")
    assert code == 0, err
    assert calls == {"method": "ml", "sigma": pytest.approx(np.deg2rad(2.0)), "env": "east-sea", "sl": 150.0,
                     "n": len(truth), "nav": 164, "freq_hz": 200.0}
    assert "tma ml" in stdout and (tmp_path / "o" / "tactical_picture.png").exists()
