"""Bearings / ownship readers and the solution table writer."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.records import OwnshipTrack, TmaSolution
from sonartrack.io.tma_files import read_bearings, read_ownship, write_solution_csv


def write(tmp_path, name, cols, parquet=False):
    path = tmp_path / (name + (".parquet" if parquet else ".csv"))
    df = pd.DataFrame(cols)
    df.to_parquet(path) if parquet else df.to_csv(path, index=False)
    return path


@pytest.mark.parametrize("parquet", [False, True])
def test_bearings_round_trip(tmp_path, parquet):
    t = np.arange(10.0)
    b = np.array([350.0, 355, 0, 5, 10, 15, 20, 25, 30, -170])
    f = np.linspace(300, 301, 10)
    path = write(tmp_path, "b", {"time_s": t, "bearing_deg": b, "frequency_hz": f, "snr_db": np.full(10, 12.0)},
                 parquet)
    rec = read_bearings(path)
    np.testing.assert_allclose(rec.time_s, t)
    np.testing.assert_allclose(rec.bearing_rad[:3], np.deg2rad([-10.0, -5.0, 0.0]))
    assert rec.bearing_rad[-1] == pytest.approx(np.deg2rad(-170.0))
    assert np.all((rec.bearing_rad > -np.pi) & (rec.bearing_rad <= np.pi))
    np.testing.assert_allclose(rec.frequency_hz, f)
    np.testing.assert_allclose(rec.snr_db, 12.0)


def test_empty_frequency_cells_mean_no_frequency(tmp_path):
    path = tmp_path / "b.csv"
    path.write_text("# a comment line\ntime_s,bearing_deg,frequency_hz\n0,10,300.1\n1,11,\n2,12,300.2\n3,13,\n"
                    "4,14,300.0\n")
    rec = read_bearings(path)
    assert np.isnan(rec.frequency_hz[1]) and rec.frequency_hz[2] == 300.2
    path.write_text("time_s,bearing_deg,frequency_hz\n0,10,\n1,11,\n2,12,\n3,13,\n4,14,\n")
    assert read_bearings(path).frequency_hz is None


@pytest.mark.parametrize("cols,needle", [
    ({"time_s": [0, 2, 1, 3, 4], "bearing_deg": [10, 11, 12, 13, 14]}, "sort the file"),
    ({"time_s": [0, 1, 1, 3, 4], "bearing_deg": [10, 11, 12, 13, 14]}, "strictly increasing"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_deg": [0.1, 0.2, 0.25, 0.3, 0.35]}, "radians"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, 720, 13, 14]}, "beyond ±360"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_rad": [0.1, 0.2, 0.25, 0.3, 0.35]}, "bearing_deg"),
    ({"time_ms": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, 12, 13, 14]}, "time_s"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, np.nan, 13, 14]}, "bearing_deg"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, 12, 13, 14], "frequency_hz": [300, -1, 300, 300, 300]},
     "positive"),
    ({"time_s": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, 12, 13, 14], "frequency_hz": [300, "abc", 300, 300, 300]},
     "non-numeric"),
    ({"t": [0, 1, 2, 3, 4], "bearing_deg": [10, 11, 12, 13, 14]}, "lacks column"),
])
def test_bad_bearings_give_one_line_errors(tmp_path, cols, needle):
    path = write(tmp_path, "b", cols)
    with pytest.raises(InputError) as e:
        read_bearings(path)
    msg = str(e.value)
    assert needle in msg and "\n" not in msg


def test_radian_check_can_be_switched_off(tmp_path):
    path = write(tmp_path, "b", {"time_s": [0, 1, 2, 3, 4], "bearing_deg": [0.1, 0.2, 0.25, 0.3, 0.35]})
    rec = read_bearings(path, check_radians=False)
    assert rec.bearing_rad[0] == pytest.approx(np.deg2rad(0.1))


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="not found"):
        read_bearings(tmp_path / "nope.csv")


def test_ownship_reader_and_checks(tmp_path):
    path = write(tmp_path, "o", {"time_s": [0.0, 10, 20], "x_m": [0.0, 25, 50], "y_m": [0.0, 0, 0]})
    own = read_ownship(path)
    np.testing.assert_allclose(own.position_at([5.0, 15.0]), [[12.5, 0.0], [37.5, 0.0]])
    with pytest.raises(InputError, match="m/s"):  # x in km written as m: 2500 m/s
        read_ownship(write(tmp_path, "o2", {"time_s": [0.0, 0.01, 0.02], "x_m": [0.0, 25, 50], "y_m": [0, 0, 0]}))
    with pytest.raises(InputError, match="x_m"):
        read_ownship(write(tmp_path, "o3", {"time_s": [0.0, 1, 2], "x_km": [0.0, 0.1, 0.2], "y_m": [0, 0, 0]}))
    with pytest.raises(InputError, match="at least two"):
        read_ownship(write(tmp_path, "o4", {"time_s": [0.0], "x_m": [0.0], "y_m": [0.0]}))


def test_write_solution_csv_is_atomic_and_complete(tmp_path):
    own = OwnshipTrack(time_s=np.array([0.0, 100.0]), x_m=np.zeros(2), y_m=np.zeros(2))
    sol = TmaSolution(time_s=np.array([0.0, 50.0]),
                      state=np.array([[0.0, 1000.0, 5.0, 0.0], [250.0, 1000.0, 5.0, 0.0]]),
                      covariance=np.stack([np.eye(4)] * 2), method="test")
    path = write_solution_csv(tmp_path / "sub" / "sol.csv", sol, own)
    df = pd.read_csv(path)
    assert list(df.columns[:9]) == ["time_s", "x_m", "y_m", "vx_mps", "vy_mps", "course_deg", "speed_kn", "range_m",
                                    "bearing_deg"]
    assert {"x_std_m", "course_std_deg", "speed_std_kn", "range_std_m", "bearing_std_deg"} <= set(df.columns)
    assert df["range_m"].iloc[1] == pytest.approx(np.hypot(250.0, 1000.0))
    assert [p.name for p in path.parent.iterdir()] == ["sol.csv"]
