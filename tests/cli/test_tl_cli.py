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
    code, out, err = run(capsys, "tl", "--profile", p, "--freq", "150", "--zs", "20", "--rmax", "5",
                         "--out", tmp_path / "o")
    assert code == 0, err
    assert out.startswith("tl ctd")


def test_bad_input(tmp_path, capsys):
    for args, needle in ((["--env", "baltic"], "unknown environment 'baltic'"),
                         (["--env", "yellow-winter", "--zs", "-5"], "inside the water column"),
                         (["--env", "yellow-winter", "--zs", "30", "--zr", "90"], "receiver depth 90 m"),
                         ([], "exactly one of --env"),
                         (["--env", "yellow-winter", "--rmax", "8000"], "kilometres, not metres")):
        code, _, err = run(capsys, "tl", *args, "--out", tmp_path / "o")
        assert code == 2 and needle in err and err.strip().count("\n") == 0, (args, err)
    p = tmp_path / "short.toml"
    p.write_text('depth_m = [0.0, 40.0]\nsound_speed_mps = [1500.0, 1495.0]\nwater_depth_m = 90.0\n')
    code, _, err = run(capsys, "tl", "--profile", p, "--out", tmp_path / "o")
    assert code == 2 and "stops at 40 m" in err


def test_print_config_reads_back_and_options_override_the_file(tmp_path, capsys):
    code, out, err = run(capsys, "tl", "--print-config", "--freq", "150", "--zs", "20")
    assert code == 0, err
    assert "freq_hz = 150.0  # frequency of the tonal" in out and "source_depth_m = 20.0" in out
    cfg = tmp_path / "tl.toml"
    cfg.write_text(out)  # the printed settings are a valid --config file
    code, out2, _ = run(capsys, "tl", "--config", cfg, "--print-config", "--zr", "35")
    assert code == 0 and "freq_hz = 150.0" in out2 and "receiver_depth_m = 35.0" in out2
    cfg.write_text("frequency = 100.0\n")
    code, _, err = run(capsys, "tl", "--config", cfg, "--env", "yellow-winter", "--out", tmp_path / "o")
    assert code == 2 and "frequency" in err and err.strip().count("\n") == 0


def test_config_file_settings_are_used(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(tmp_path / "cache"))
    cfg = tmp_path / "tl.toml"
    cfg.write_text("freq_hz = 100.0\nsource_depth_m = 38.0\nrmax_km = 6.0\nthreshold_db = 3.0\n")
    code, out, err = run(capsys, "tl", "--env", "yellow-winter", "--config", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    assert out.startswith("tl yellow-winter: 100 Hz, source 38 m, receiver 38 m, to 6 km; SNR > 3 dB")
    assert pd.read_csv(tmp_path / "o" / "tl.csv")["range_m"].max() <= 6000
