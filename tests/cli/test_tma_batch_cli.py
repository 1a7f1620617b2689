"""`sonartrack tma --method ml|em-map` on files synthesised here (paper P3's scenario, South Sea summer)."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.units import KNOT_MPS as KN
from sonartrack.sim.platforms import ManeuveringTrack


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    import os

    d = tmp_path_factory.mktemp("batch")
    os.environ["SONARTRACK_CACHE_DIR"] = str(d / "cache")
    from sonartrack.io.environment import TLDiskCache
    from sonartrack.tma.batch import snr_model

    xi_bar, _, _ = snr_model("south-summer", 140.0, 200.0, 50.0, 63_000.0, tl_store=TLDiskCache())
    t = np.arange(100) * 8.0
    rng = np.random.default_rng(7)
    out = {}
    zigzag = ((250.0, 280.0, np.deg2rad(-3.0)), (520.0, 550.0, np.deg2rad(3.0)))
    for name, turns in (("turning", zigzag), ("straight", ())):
        po, _, _ = ManeuveringTrack(0.0, 0.0, 6 * KN, np.deg2rad(90.0), turns).state(t)
        b = np.deg2rad(160.0)
        pt, _, _ = ManeuveringTrack(8000 * np.sin(b), 8000 * np.cos(b), 6 * KN, np.deg2rad(270.0)).state(t)
        dd = pt - po
        r = np.linalg.norm(dd, axis=1)
        brg = np.rad2deg(np.arctan2(dd[:, 0], dd[:, 1]) + rng.normal(0, np.deg2rad(0.5), len(t))) % 360
        pd.DataFrame({"time_s": t, "bearing_deg": brg, "snr_db": xi_bar(r) + rng.normal(0, 1.0, len(t))}).to_csv(
            d / f"{name}_brg.csv", index=False)
        pd.DataFrame({"time_s": t, "x_m": po[:, 0], "y_m": po[:, 1]}).to_csv(d / f"{name}_own.csv", index=False)
        out[name] = r[-1]
    yield d, out
    del os.environ["SONARTRACK_CACHE_DIR"]


@pytest.mark.parametrize("method", ["ml", "em-map"])
def test_batch_methods_find_the_target(files, tmp_path, capsys, method):
    d, r_end = files
    extra = ["--env", "south-summer", "--sl", "140"] if method == "em-map" else []
    cfg = tmp_path / "c.toml"
    cfg.write_text("sigma_bearing_deg = 0.5\n[batch]\ndepth_m = 50.0\n")
    code, out, err = run(capsys, "tma", "--bearings", d / "turning_brg.csv", "--ownship", d / "turning_own.csv",
                         "--method", method, *extra, "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    sol = pd.read_csv(tmp_path / "o" / "tma_solution.csv")
    assert abs(sol["range_m"].iloc[-1] - r_end["turning"]) < (0.25 if method == "ml" else 0.1) * r_end["turning"]
    assert f"tma {method}" in out


def test_no_maneuver(files, tmp_path, capsys):
    d, r_end = files
    args = ["tma", "--bearings", d / "straight_brg.csv", "--ownship", d / "straight_own.csv", "--out", tmp_path / "o"]
    code, _, err = run(capsys, *args, "--method", "ml")
    assert code == 2 and "unobservable" in err and err.strip().count("\n") == 0
    code, out, err = run(capsys, *args, "--method", "em-map", "--env", "south-summer", "--sl", "140",
                         "--config", _cfg(tmp_path))
    assert code == 0 and err.startswith("warning: ") and "unobservable" in err
    sol = pd.read_csv(tmp_path / "o" / "tma_solution.csv")
    assert abs(sol["range_m"].iloc[-1] - r_end["straight"]) < 0.15 * r_end["straight"]  # the SNR gives range


def _cfg(tmp_path):
    p = tmp_path / "c2.toml"
    p.write_text("sigma_bearing_deg = 0.5\n[batch]\ndepth_m = 50.0\n")
    return p


def test_em_map_needs_a_model_and_snr(files, tmp_path, capsys):
    d, _ = files
    base = ["tma", "--bearings", d / "turning_brg.csv", "--ownship", d / "turning_own.csv", "--method", "em-map",
            "--out", tmp_path / "o"]
    code, _, err = run(capsys, *base)
    assert code == 2 and "--env" in err
    code, _, err = run(capsys, *base, "--env", "atlantis", "--sl", "140")
    assert code == 2 and "unknown environment 'atlantis'" in err
    nosnr = tmp_path / "b.csv"
    pd.read_csv(d / "turning_brg.csv").drop(columns="snr_db").to_csv(nosnr, index=False)
    code, _, err = run(capsys, "tma", "--bearings", nosnr, "--ownship", d / "turning_own.csv", "--method", "em-map",
                       "--env", "south-summer", "--sl", "140", "--out", tmp_path / "o")
    assert code == 2 and "snr_db" in err


def test_sequential_ekf_from_the_batch_estimate(files, tmp_path, capsys):
    d, r_end = files
    cfg = tmp_path / "c.toml"
    cfg.write_text("sigma_bearing_deg = 0.5\n[batch]\ndepth_m = 50.0\nwindow_s = 600.0\n")
    code, out, err = run(capsys, "tma", "--bearings", d / "turning_brg.csv", "--ownship", d / "turning_own.csv",
                         "--method", "em-map", "--env", "south-summer", "--sl", "140", "--config", cfg,
                         "--out", tmp_path / "o")
    assert code == 0, err
    assert "then a sequential EKF" in out
    sol = pd.read_csv(tmp_path / "o" / "tma_solution.csv")
    assert abs(sol["range_m"].iloc[-1] - r_end["turning"]) < 0.1 * r_end["turning"]
    # the filter starts from the batch covariance and does not blow up
    assert sol["range_std_m"].iloc[-1] < 0.2 * r_end["turning"]


def test_em_map_says_whether_the_propagation_model_explains_the_snr(files, tmp_path, capsys):
    """The SNRs follow South Sea summer; a model of the same sea explains them, one of the East Sea (deep water,
    another TL curve) does not: with the zig-zag the bearings alone give the range, without it none is printed."""
    d, r_end = files
    cfg = _cfg(tmp_path)
    out = {}
    for name in ("turning", "straight"):
        for env in ("south-summer", "east-summer"):
            code, stdout, err = run(capsys, "tma", "--bearings", d / f"{name}_brg.csv", "--ownship",
                                    d / f"{name}_own.csv", "--method", "em-map", "--env", env, "--sl", "140",
                                    "--config", cfg, "--out", tmp_path / f"{name}-{env}")
            assert code == 0, err
            out[name, env] = stdout, pd.read_csv(tmp_path / f"{name}-{env}" / "tma_solution.csv")
    for name in ("turning", "straight"):
        line, sol = out[name, "south-summer"]
        assert "the propagation model explains the SNR" in line and " km" in line
        assert sol["range_determined"].all()
        line, sol = out[name, "east-summer"]
        assert "the propagation model does not explain the SNR (chi2 = " in line
    line, sol = out["turning", "east-summer"]
    assert "range from the bearings alone (ML)" in line and sol["range_determined"].iloc[-1]
    assert abs(sol["range_m"].iloc[-1] - r_end["turning"]) < 0.25 * r_end["turning"]
    line, sol = out["straight", "east-summer"]
    assert "range NOT DETERMINED (SNR not explained by the propagation model)" in line and " km" not in line
    assert not sol["range_determined"].any()
    assert set(sol["undetermined_reason"]) == {"SNR not explained by the propagation model"}


def test_em_map_level_uncertainty_widens_the_stated_range_sd(files, tmp_path, capsys):
    # the level's uncertainty (a consider parameter) adds to the observed-information covariance: 0 dB gives the
    # bare covariance, the default 1 dB a wider one, the same point estimate
    d, _ = files
    sds, ranges = {}, {}
    for level in (0.0, 1.0):
        cfg = tmp_path / f"l{level}.toml"
        cfg.write_text(f"sigma_bearing_deg = 0.5\n[batch]\ndepth_m = 50.0\nsigma_level_db = {level}\n")
        code, _, err = run(capsys, "tma", "--bearings", d / "turning_brg.csv", "--ownship", d / "turning_own.csv",
                           "--method", "em-map", "--env", "south-summer", "--sl", "140", "--config", cfg,
                           "--out", tmp_path / f"o{level}")
        assert code == 0, err
        sol = pd.read_csv(tmp_path / f"o{level}" / "tma_solution.csv")
        sds[level], ranges[level] = sol["range_std_m"].iloc[-1], sol["range_m"].iloc[-1]
    assert ranges[0.0] == ranges[1.0]
    assert sds[1.0] > 1.2 * sds[0.0], sds
