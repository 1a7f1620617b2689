"""`sonartrack tl`: a shipped environment, a user profile, the listing and bad input."""

import pandas as pd

from sonartrack.cli import main


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_list(capsys):
    code, out, _ = run(capsys, "tl", "--list")
    assert code == 0 and out.count("\n") == 6 and "east-summer" in out


def test_shipped_shallow_environment(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(tmp_path / "cache"))
    code, out, err = run(capsys, "tl", "--env", "yellow-winter", "--freq", "100", "--zs", "38", "--rmax", "8",
                         "--out", tmp_path / "o")
    assert code == 0, err
    assert out.startswith("tl yellow-winter") and "SNR > 0 dB" in out
    table = pd.read_csv(tmp_path / "o" / "tl.csv")
    assert list(table.columns) == ["range_m", "tl_db", "tl_avg_db", "snr_db"]
    assert table["range_m"].max() <= 8000 and table["tl_db"].between(20, 150).all()
    assert (tmp_path / "o" / "tl_field.png").stat().st_size > 0 and (tmp_path / "o" / "tl_range.png").stat().st_size > 0


def test_user_profile(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(tmp_path / "cache"))
    p = tmp_path / "ctd.csv"
    p.write_text("depth_m,temperature_c,salinity_psu\n0,12,34\n30,10,34.1\n60,9,34.2\n")
    code, out, err = run(capsys, "tl", "--profile", p, "--freq", "150", "--zs", "20", "--rmax", "5", "--out", tmp_path / "o")
    assert code == 0, err
    assert out.startswith("tl ctd")


def test_bad_input(tmp_path, capsys):
    for args, needle in ((["--env", "baltic"], "unknown environment 'baltic'"),
                         (["--env", "yellow-winter", "--zs", "-5"], "inside the water column"),
                         (["--env", "yellow-winter", "--zs", "30", "--zr", "90"], "receiver depth 90 m"),
                         ([], "exactly one of --env"),
                         (["--env", "yellow-winter", "--rmax", "8000"], "kilometres")):
        code, _, err = run(capsys, "tl", *args, "--out", tmp_path / "o")
        assert code == 2 and needle in err and err.strip().count("\n") == 0, (args, err)
    p = tmp_path / "short.toml"
    p.write_text('depth_m = [0.0, 40.0]\nsound_speed_mps = [1500.0, 1495.0]\nwater_depth_m = 90.0\n')
    code, _, err = run(capsys, "tl", "--profile", p, "--out", tmp_path / "o")
    assert code == 2 and "stops at 40 m" in err
