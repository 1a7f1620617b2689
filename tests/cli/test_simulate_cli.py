"""`sonartrack simulate`: outputs, one summary line, --print-config round trip, --only, shipped scenes, bad input."""

import pandas as pd
import pytest

from sonartrack.cli import main

PASSIVE = {"recording.wav", "pair.wav", "nav.csv", "truth.csv"}
SAMPLES = {"contacts.csv", "raw.csv", "raw_nav.csv", "frames.npy", "brg.csv", "own.csv", "ctd.csv"}


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_simulate_writes_every_file_and_one_line(tmp_path, capsys):
    code, out, err = run(capsys, "simulate", "--out", tmp_path, "--duration-s", "30")
    assert code == 0, err
    assert out.count("\n") == 1 and out.startswith("simulate: 30 s at 4000 Hz, 16 elements 2.5 m apart")
    assert "submarine" in out and "SNR per element" in out
    assert {p.name for p in tmp_path.iterdir()} == PASSIVE | SAMPLES | {"scene.toml"}
    truth = pd.read_csv(tmp_path / "truth.csv")
    assert len(truth) == 31 * 4 and set(truth["ship"]) == {"merchant", "trawler", "submarine", "tanker"}


def test_print_config_reads_back(tmp_path, capsys):
    code, text, err = run(capsys, "simulate", "--print-config", "--duration-s", "90", "--seed", "5")
    assert code == 0, err
    assert "[[ships]]" in text and "duration_s = 90.0" in text and "seed = 5" in text
    cfg = tmp_path / "my.toml"
    cfg.write_text(text)
    code, again, err = run(capsys, "simulate", "--scene", cfg, "--print-config")
    assert code == 0, err
    assert again == text
    # the resolved scene written beside the outputs reads back to the same scene too
    code, out, err = run(capsys, "simulate", "--scene", cfg, "--only", "samples", "--out", tmp_path / "o")
    assert code == 0, err
    assert (tmp_path / "o" / "scene.toml").read_text() == text
    assert not any((tmp_path / "o" / name).exists() for name in PASSIVE)


def test_own_scene_with_one_ship_and_no_tonal(tmp_path, capsys):
    cfg = tmp_path / "one.toml"
    cfg.write_text('duration_s = 10.0\n[[ships]]\nname = "buoy"\nx_m = 1000.0\ny_m = 0.0\ncourse_deg = 0.0\n'
                   'speed_kn = 0.0\nsource_level_db = 120.0\n')
    code, out, err = run(capsys, "simulate", "--scene", cfg, "--out", tmp_path / "o", "--only", "passive")
    assert code == 0, err
    assert "1 ship(s) (SNR per element, dB: buoy" in out
    truth = pd.read_csv(tmp_path / "o" / "truth.csv")
    assert truth["tonal_hz"].isna().all() and len(truth) == 11


def test_noise_only_scene(tmp_path, capsys):
    cfg = tmp_path / "noise.toml"
    cfg.write_text("duration_s = 5.0\nships = []\n")
    code, out, err = run(capsys, "simulate", "--scene", cfg, "--out", tmp_path / "o")
    assert code == 0, err
    assert "noise only" in out
    assert not (tmp_path / "o" / "brg.csv").exists()  # no ship to take bearings of
    assert (tmp_path / "o" / "contacts.csv").exists()  # clutter only


def test_shipped_scene_by_name_and_ram_propagation(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(tmp_path / "cache"))
    code, out, err = run(capsys, "simulate", "--scene", "passive", "--duration-s", "5", "--propagation", "ram",
                         "--only", "passive", "--out", tmp_path / "o")
    assert code == 0, err
    assert "ram TL" in out
    assert any((tmp_path / "cache" / "tl").glob("*.npz"))  # the RAM fields were cached


@pytest.mark.parametrize("args, needle", [
    (["--scene", "nowhere"], "shipped scenes"),
    (["--scene", "missing.toml"], "not found"),
    (["--propagation", "bellhop"], "propagation"),
    (["--duration-s", "-5"], "duration_s"),
    (["--only", "everything"], "--only"),
])
def test_bad_input_is_one_line(tmp_path, capsys, args, needle):
    code, out, err = run(capsys, "simulate", "--out", tmp_path / "o", *args)
    assert code == 2
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err


def test_unknown_key_in_scene_file(tmp_path, capsys):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("duration = 10.0\n")
    code, out, err = run(capsys, "simulate", "--scene", cfg, "--out", tmp_path / "o")
    assert code == 2 and "duration" in err and err.count("\n") == 1
