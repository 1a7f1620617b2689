"""The bearings file's optional ``bearing_sd_deg`` column (io/tma_files.py) read and used by ``sonartrack tma``:
each bearing's own sd; a bad value or a second sd (--sigma-bearing-deg) is a one-line error, nothing written."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.errors import InputError
from sonartrack.io.tma_files import read_bearings


def _files(tmp_path, sd_deg):
    """A constant-velocity target, an ownship on two legs, bearings every 30 s with the given sds (deg, noise-free
    bearings rounded to 0.01 deg)."""
    t = np.arange(0.0, 2400.0 + 1e-9, 30.0)
    course = np.deg2rad(np.where(t < 1200.0, 60.0, 150.0))
    own = np.concatenate([[[0.0, 0.0]], np.cumsum(4.0 * 30.0 * np.stack([np.sin(course), np.cos(course)], -1)[:-1],
                                                  axis=0)])
    d = np.array([5000.0, 8000.0]) + np.outer(t, [-2.0, 1.0]) - own
    cols = {"time_s": t, "bearing_deg": np.round(np.rad2deg(np.arctan2(d[:, 0], d[:, 1])) % 360, 2)}
    if sd_deg is not None:
        cols["bearing_sd_deg"] = np.resize(np.asarray(sd_deg, float), len(t))
    pd.DataFrame(cols).to_csv(tmp_path / "brg.csv", index=False)
    pd.DataFrame({"time_s": t, "x_m": own[:, 0], "y_m": own[:, 1]}).to_csv(tmp_path / "own.csv", index=False)
    return tmp_path / "brg.csv", tmp_path / "own.csv"


def test_column_read_in_radians(tmp_path):
    brg, _ = _files(tmp_path, [0.5, 2.0])
    rec = read_bearings(brg)
    np.testing.assert_allclose(rec.bearing_sd_rad[:4], np.deg2rad([0.5, 2.0, 0.5, 2.0]))
    assert read_bearings(_files(tmp_path, None)[0]).bearing_sd_rad is None


@pytest.mark.parametrize("bad", [0.0, -1.0, 200.0])
def test_bad_sd_is_refused(tmp_path, bad):
    brg, _ = _files(tmp_path, [0.5, 0.5, bad, 0.5])
    with pytest.raises(InputError, match="bearing_sd_deg"):
        read_bearings(brg)


def test_cli_uses_the_column_and_refuses_a_second_sd(tmp_path, capsys):
    brg, own = _files(tmp_path, [0.5, 1.0, 2.0])
    assert main(["tma", "--bearings", str(brg), "--ownship", str(own), "--method", "ml", "--out",
                 str(tmp_path / "a")]) == 0
    out = capsys.readouterr().out
    assert "each bearing's own given" in out
    assert main(["tma", "--bearings", str(brg), "--ownship", str(own), "--method", "ml", "--sigma-bearing-deg", "1",
                 "--out", str(tmp_path / "b")]) == 2
    assert "leave out one of the two" in capsys.readouterr().err
    assert not (tmp_path / "b").exists() or not any((tmp_path / "b").iterdir())
