"""Generated files for every reader: the reader returns arrays that keep its contract, or raises
InputError (one line) -- never another exception.

Files are CSV text built from the reader's own column names (sometimes one missing, sometimes a stray or
wrong-unit one) and cells drawn from plausible numbers, edge numbers (0, negative, 1e300, NaN, inf), text and
empty cells; plus arbitrary bytes under the file's name.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sonartrack.core.errors import InputError
from sonartrack.io.contacts import read_contacts
from sonartrack.io.environment import read_profile
from sonartrack.io.peaks import read_peaks_csv
from sonartrack.io.tma_files import read_bearings, read_ownship

SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

CELLS = st.one_of(
    st.integers(-5, 400).map(str),
    st.floats(-1e4, 1e4, allow_nan=False).map(lambda v: f"{v:.6g}"),
    st.sampled_from(["0", "-1", "1e300", "-1e300", "nan", "inf", "-inf", "", "abc", "1,5", '"x"', "0x10", "1e-300",
                     "3.14159", "6.2", "1500", "1.5", "25000"]),
)


def num(lo: float, hi: float):
    return st.floats(lo, hi, allow_nan=False).map(lambda v: f"{v:.6g}")


#: the edge cells a reader most often lets through: negative, absurd, missing, text
EDGES = st.sampled_from(["-1", "-3.5", "-1", "1e300", "nan", "", "abc", "-inf"])
#: plausible cells of each column (a file of these alone is valid, or nearly)
PLAUSIBLE = {
    "x_m": num(-2e4, 2e4), "y_m": num(-2e4, 2e4), "var_x_m2": num(100, 1e5), "var_y_m2": num(100, 1e5),
    "cov_xy_m2": st.sampled_from(["0", "10", "-25.5"]), "bearing_deg": num(0, 180), "amplitude": num(0, 3e4),
    "frequency_hz": num(100, 1000), "snr_db": num(-10, 30), "travel_time_s": num(1, 30),
    "sound_speed_mps": num(1450, 1550), "temperature_c": num(2, 25), "salinity_psu": num(30, 35),
}
#: the ordered column (times or depths) and its step between rows: 0 repeats a value, sign -1 unsorts
ORDERED = {"time_s": 10.0, "depth_m": 20.0}


@st.composite
def csv_text(draw, columns: list[str], extra: tuple[str, ...] = ("note", "x_km", "time_ms", "bearing_rad"),
             plausible: dict | None = None) -> str:
    """Header and rows: plausible cells, ordered times/depths, and (mostly) a few corrupted cells or columns."""
    plausible = {**PLAUSIBLE, **(plausible or {})}
    cols = list(columns)
    if draw(st.integers(0, 5)) == 0 and len(cols) > 1:
        cols.pop(draw(st.integers(0, len(cols) - 1)))
    if draw(st.integers(0, 5)) == 0:
        cols.append(draw(st.sampled_from(extra)))
    n = draw(st.integers(0, 8))
    steps = [draw(st.sampled_from([1.0] * 6 + [0.0, 0.5, -1.0])) for _ in range(n)]
    rows = []
    for i in range(n):
        row = [str(sum(steps[:i]) * ORDERED[c]) if c in ORDERED else draw(plausible.get(c, CELLS)) for c in cols]
        rows.append(row)
    for _ in range(draw(st.sampled_from([0, 1, 1, 2])) if rows else 0):  # corrupt a few cells
        rows[draw(st.integers(0, n - 1))][draw(st.integers(0, len(cols) - 1))] = draw(st.one_of(EDGES, CELLS))
    lines = [",".join(cols), *(",".join(r) for r in rows)]
    return "\n".join(lines) + ("\n" if draw(st.booleans()) else "")


def file_with(body: str | bytes, name: str, folder: Path) -> Path:
    p = folder / name
    p.write_bytes(body if isinstance(body, bytes) else body.encode())
    return p


def read_or_input_error(read, body, name):
    """The reader's result, or None where it refused with a one-line InputError (any other exception fails)."""
    with tempfile.TemporaryDirectory() as d:
        try:
            return read(file_with(body, name, Path(d)))
        except InputError as exc:
            assert "\n" not in str(exc)
            return None


def finite(*arrays) -> bool:
    return all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in arrays)


def bodies(columns, plausible=None):
    return st.one_of(csv_text(columns, plausible=plausible), st.binary(max_size=200))


@SETTINGS
@given(body=bodies(["time_s", "x_m", "y_m", "var_x_m2", "var_y_m2", "cov_xy_m2"]))
def test_contacts_reader(body):
    c = read_or_input_error(lambda p: read_contacts(p, default_sigma_m=100.0), body, "contacts.csv")
    if c is not None:
        k = len(c.time_s)
        assert k >= 1 and c.z.shape == (k, 2) and c.R.shape == (k, 2, 2)
        assert finite(c.time_s, c.z, c.R) and np.all(np.diff(c.time_s) >= 0)
        assert np.all(np.linalg.eigvalsh(c.R) > 0) and np.allclose(c.R, np.swapaxes(c.R, 1, 2))


NAV = "time_s,tx_x_m,tx_y_m,rx_x_m,rx_y_m,array_heading_deg\n-10,0,0,1000,0,0\n1000,0,0,1000,0,0\n"


@SETTINGS
@given(body=bodies(["time_s", "travel_time_s", "bearing_deg", "sound_speed_mps"]))
def test_raw_bistatic_contacts_reader(body):
    def read(p):
        nav = p.parent / "nav.csv"
        nav.write_text(NAV)
        return read_contacts(p, nav_path=nav)

    c = read_or_input_error(read, body, "raw.csv")
    if c is not None:
        assert finite(c.time_s, c.z, c.R) and np.all(np.diff(c.time_s) >= 0)
        assert np.all(np.hypot(*c.z.T) < 2e5)  # within twice the default maximum range of the receiver


@SETTINGS
@given(body=bodies(["time_s", "bearing_deg", "amplitude"]))
def test_peaks_reader(body):
    r = read_or_input_error(read_peaks_csv, body, "peaks.csv")
    if r is not None:
        assert len(r.time_s) == len(r.bearing_deg) == len(r.amplitude) >= 1
        assert finite(r.time_s, r.bearing_deg, r.amplitude) and np.all(np.diff(r.time_s) >= 0)
        assert np.all((r.bearing_deg >= 0) & (r.bearing_deg <= 180)) and np.all(r.amplitude >= 0)


@SETTINGS
@given(body=bodies(["time_s", "bearing_deg", "frequency_hz", "snr_db"]))
def test_tma_bearings_reader(body):
    r = read_or_input_error(read_bearings, body, "brg.csv")
    if r is not None:
        assert finite(r.time_s, r.bearing_rad) and np.all(np.diff(r.time_s) > 0)
        assert np.all(np.abs(r.bearing_rad) <= np.pi)
        if r.frequency_hz is not None:
            f = r.frequency_hz[np.isfinite(r.frequency_hz)]
            assert f.size >= 1 and np.all(f > 0) and len(r.frequency_hz) == len(r.time_s)
        if r.snr_db is not None:
            assert finite(r.snr_db) and len(r.snr_db) == len(r.time_s)


@SETTINGS
@given(body=bodies(["time_s", "x_m", "y_m"], {"x_m": num(-150, 150), "y_m": num(-150, 150)}))  # < 40 m/s
def test_ownship_reader(body):
    o = read_or_input_error(read_ownship, body, "own.csv")
    if o is not None:
        assert len(o.time_s) >= 2 and finite(o.time_s, o.x_m, o.y_m) and np.all(np.diff(o.time_s) > 0)


@pytest.mark.parametrize("columns", [["depth_m", "sound_speed_mps"], ["depth_m", "temperature_c", "salinity_psu"]])
@SETTINGS
@given(data=st.data())
def test_profile_reader(columns, data):
    body = data.draw(bodies(columns))
    e = read_or_input_error(read_profile, body, "ctd.csv")
    if e is not None:
        assert finite(e.depth_m, e.sound_speed_mps) and np.all(np.diff(e.depth_m) > 0)
        assert np.all((e.sound_speed_mps > 1300) & (e.sound_speed_mps < 1700)) and e.water_depth_m > 0


@SETTINGS
@given(body=st.one_of(st.binary(max_size=200), st.text(max_size=200)))
def test_profile_toml_reader(body):
    e = read_or_input_error(read_profile, body if isinstance(body, bytes) else body.encode(), "p.toml")
    if e is not None:
        assert finite(e.depth_m, e.sound_speed_mps)
