"""``sonartrack simulate --kind active``: the files ``sonartrack active`` reads, the active settings printed, the
passive-only options refused, and the chain run on what it wrote."""

import numpy as np
import pandas as pd

from sonartrack.cli import main


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out + out.err


def test_simulate_active_then_active(tmp_path, capsys):
    out = tmp_path / "scene"
    code, text = run(capsys, "simulate", "--kind", "active", "--duration-s", "90", "--seed", "3", "--out", out)
    assert code == 0, text
    assert "3 pings every 30 s" in text and "--spacing 0.5" in text
    assert sorted(p.name for p in out.iterdir()) == ["nav.csv", "ping_table.csv", "pings", "scene.toml", "truth.csv"]
    table = pd.read_csv(out / "ping_table.csv")
    np.testing.assert_allclose(table["transmit_time_s"], [0.0, 30.0, 60.0])
    assert np.load(out / "pings" / table["file"][0].split("/")[-1]).shape == (16, 6000)
    res = tmp_path / "res"
    code, text = run(capsys, "active", "--pings", out / "pings", "--nav", out / "nav.csv", "--spacing", "0.5",
                     "--out", res)
    assert code == 0, text
    assert (res / "sides.csv").is_file() and (res / "tracks.csv").is_file()


def test_print_config_is_the_active_scene(capsys):
    code, text = run(capsys, "simulate", "--kind", "active", "--print-config")
    assert code == 0
    assert "ping_interval_s = 30.0" in text and "[[targets]]" in text and "maneuvering" in text
    code, text = run(capsys, "simulate", "--print-config")
    assert code == 0 and "[[ships]]" in text and "[[targets]]" not in text


def test_passive_options_and_unknown_kind_are_refused(tmp_path, capsys):
    code, text = run(capsys, "simulate", "--kind", "active", "--nmea", "--out", tmp_path / "x")
    assert code == 2 and "--nmea is an option of the passive scene" in text
    assert not (tmp_path / "x").exists()
    code, text = run(capsys, "simulate", "--kind", "sonar", "--out", tmp_path / "y")
    assert code == 2 and "choose passive or active" in text
