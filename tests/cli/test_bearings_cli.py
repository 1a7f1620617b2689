"""`sonartrack bearings` and `sonartrack track --peaks` on a WAV synthesised here; bad input."""

import numpy as np
import pandas as pd
import pytest
from scipy.io import wavfile

from sonartrack.acoustics.signals import SourceSpec, simulate_two_channel
from sonartrack.cli import main


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def wav(tmp_path_factory):
    d = tmp_path_factory.mktemp("wav")
    x = simulate_two_channel(np.random.default_rng(0), duration_s=40, fs_hz=8000, spacing_m=20,
                             sources=[SourceSpec(lambda t: 60 + t, 3.0), SourceSpec(lambda t: 130 - 0.5 * t, 0.0)],
                             band_hz=(100, 1500))
    wavfile.write(d / "rec.wav", 8000, (x.T / np.abs(x).max() * 0.9 * 32767).astype(np.int16))
    wavfile.write(d / "mono.wav", 8000, (x[0] * 1000).astype(np.int16))
    wavfile.write(d / "u8.wav", 8000, ((x.T / np.abs(x).max()) * 100 + 128).astype(np.uint8))
    return d


def test_bearings_then_tracks(wav, tmp_path, capsys):
    code, out, err = run(capsys, "bearings", "--wav", wav / "rec.wav", "--spacing", "20", "--out", tmp_path)
    assert code == 0, err
    peaks = pd.read_csv(tmp_path / "peaks.csv")
    assert list(peaks.columns) == ["time_s", "bearing_deg", "amplitude"] and len(peaks) >= 60
    late = peaks[peaks["time_s"] == 30.5]["bearing_deg"].to_numpy()
    assert np.min(np.abs(late - 90.5)) < 1.0 and np.min(np.abs(late - 114.75)) < 1.5
    for tracker in ("jpda-a", "jpda"):
        code, out, err = run(capsys, "track", "--peaks", tmp_path / "peaks.csv", "--tracker", tracker,
                             "--out", tmp_path / tracker)
        assert code == 0, err
        tr = pd.read_csv(tmp_path / tracker / "bearing_tracks.csv")
        end = tr[(tr["time_s"] == tr["time_s"].max()) & tr["confirmed"]]["bearing_deg"].to_numpy()
        assert np.min(np.abs(end - 99.5)) < 3 and np.min(np.abs(end - 110.25)) < 3
        assert (tmp_path / tracker / "bearing_tracks.png").stat().st_size > 0


@pytest.mark.parametrize("name, args, needle", [
    ("mono.wav", ["--spacing", "20"], "mono"),
    ("u8.wav", ["--spacing", "20"], "uint8"),
    ("rec.wav", ["--spacing", "0"], "0 < spacing_m <= 1000"),
    ("rec.wav", ["--spacing", "-3"], "0 < spacing_m <= 1000"),
    ("rec.wav", [], "'spacing_m': Field required"),
    ("rec.wav", ["--spacing", "20", "--window", "60"], "shorter than one 60 s window"),
    ("missing.wav", ["--spacing", "20"], "not found"),
])
def test_bad_recordings(wav, tmp_path, capsys, name, args, needle):
    code, _, err = run(capsys, "bearings", "--wav", wav / name, *args, "--out", tmp_path / "o")
    assert code == 2 and needle in err and err.strip().count("\n") == 0
    assert not (tmp_path / "o" / "peaks.csv").exists()


def test_bad_peaks_files(tmp_path, capsys):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    code, _, err = run(capsys, "track", "--peaks", empty, "--out", tmp_path / "o")
    assert code == 2 and "empty" in err
    ok = tmp_path / "p.csv"
    ok.write_text("time_s,bearing_deg,amplitude\n0.5,60,12000\n")
    code, _, err = run(capsys, "track", "--peaks", ok, "--tracker", "kalman", "--out", tmp_path / "o")
    assert code == 2 and "jpda or jpda-a" in err


def test_print_config_and_config_file(wav, tmp_path, capsys):
    code, out, err = run(capsys, "bearings", "--print-config", "--spacing", "20", "--threshold", "4000")
    assert code == 0, err
    assert "spacing_m = 20.0  # sensor (or half-array centre) spacing d (m)" in out and "threshold = 4000.0" in out
    cfg = tmp_path / "b.toml"
    cfg.write_text(out)
    code, out, err = run(capsys, "bearings", "--wav", wav / "rec.wav", "--config", cfg, "--max-peaks", "1",
                         "--out", tmp_path / "o")
    assert code == 0, err
    peaks = pd.read_csv(tmp_path / "o" / "peaks.csv")
    assert peaks.groupby("time_s").size().max() == 1  # the option overrode the file's max_peaks = 20
    assert out.startswith("bearings: 40 windows of 1 s at 8000 Hz")


def test_print_config_without_the_spacing_marks_it_not_set(wav, tmp_path, capsys):
    # the spacing has no default; the other settings still print, and the file still needs --spacing to run
    code, out, err = run(capsys, "bearings", "--print-config", "--window", "2")
    assert code == 0, err
    assert "# spacing_m = (not set)  # sensor (or half-array centre) spacing d (m)" in out and "window_s = 2.0" in out
    cfg = tmp_path / "b.toml"
    cfg.write_text(out)
    code, _, err = run(capsys, "bearings", "--wav", wav / "rec.wav", "--config", cfg, "--out", tmp_path / "o")
    assert code == 2 and "spacing_m" in err and not (tmp_path / "o").exists()
    code, _, err = run(capsys, "bearings", "--wav", wav / "rec.wav", "--config", cfg, "--spacing", "20",
                       "--out", tmp_path / "o")
    assert code == 0, err
