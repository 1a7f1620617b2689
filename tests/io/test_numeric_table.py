"""Plain numeric CSVs read without pandas (io/tables.py ``read_numeric_table``): the values pandas' ``read_csv``
gives, to the bit, on numbers written every way a user's tool writes them; every other file (comments, quotes,
NaN, blanks, non-ASCII, ragged rows, a -0 integer, a large file) goes to pandas; and a navigation file's errors
are the same words either way."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io import tables
from sonartrack.io.navigation import read_navigation
from sonartrack.io.tables import NumericTable, read_numeric_table


def _number_texts(rng, n):
    v = rng.normal(0.0, 1.0, n) * 10.0 ** rng.integers(-12, 12, n)
    forms = [repr, lambda x: f"{x:.7g}", lambda x: f"{x:.6f}", lambda x: f"{x:.17g}", lambda x: f"{x:+.3e}",
             lambda x: str(int(round(x))) if abs(x) < 1e12 and round(x) != 0 else "7",
             lambda x: f"{x:.3f}".replace("0.", ".", 1) if abs(x) < 1 and x >= 0 else f"{abs(x):.1f}".rstrip("0")]
    return [forms[i % len(forms)](float(x)) for i, x in enumerate(v)]


@pytest.mark.parametrize("seed", range(4))
def test_plain_csv_values_are_pandas_values_to_the_bit(tmp_path, seed):
    rng = np.random.default_rng(seed)
    names = ["time_s", " x_m", "y_m ", "heading_deg"]
    cells = np.array(_number_texts(rng, 4 * 300)).reshape(300, 4)
    body = "\n".join(",".join(row) for row in cells)
    text = ",".join(names) + "\n" + body + "\n"
    if seed == 1:
        text = text.replace("\n", "\r\n")
    if seed == 2:
        text = text.replace("\n", "\n\n", 5)  # blank lines are skipped, as pandas skips them
    p = tmp_path / "t.csv"
    p.write_text(text, newline="")
    ours = read_numeric_table(p, "test")
    ref = pd.read_csv(p, comment="#")
    assert isinstance(ours, NumericTable) and ours.columns == [c.strip() for c in names] and len(ours) == len(ref)
    for c, name in zip(ours.columns, names, strict=True):
        np.testing.assert_array_equal(ours[c].view(np.int64), ref[name].to_numpy(float).view(np.int64))


@pytest.mark.parametrize("text", [
    "a,b\n1,2\n# note\n3,4\n",            # a comment
    '"a",b\n1,2\n',                         # quotes
    "a,b\n1,nan\n",                          # NaN
    "a,b\n1,inf\n",                          # infinity
    "a,b\n1,\n",                             # an empty cell
    "a,b\n1,2,3\n",                          # a ragged row
    "a,b\n-0,2\n",                           # an integer -0 (pandas: 0; float(): -0.0)
    "a,b\n12345678901234567,2\n",           # an integer beyond float's exact ones
    "\ufeffa,b\n1,2\n",                      # a byte-order mark
    "a,b\n1, 2\n",                           # a space in a cell
    "a,b\n1_000,2\n",                        # a thousands separator
    "a,a\n1,2\n",                            # a repeated name
    "a,b\n",                                 # no rows
    "a;b\n1;2\n",                            # another separator: one column named "a;b", text cells
    "a,b\n1,2\r3,4\n",                       # a lone carriage return
])
def test_other_files_go_to_pandas(tmp_path, text):
    p = tmp_path / "t.csv"
    p.write_bytes(text.encode())
    try:
        out = read_numeric_table(p, "test")
    except InputError:
        return  # pandas read it and refused it (no rows): its own message
    assert not isinstance(out, NumericTable)


def test_a_large_file_goes_to_pandas(tmp_path, monkeypatch):
    p = tmp_path / "t.csv"
    p.write_text("a,b\n1,2\n3,4\n")
    assert isinstance(read_numeric_table(p, "test"), NumericTable)
    monkeypatch.setattr(tables, "PLAIN_CSV_MAX_BYTES", 5)
    assert not isinstance(read_numeric_table(p, "test"), NumericTable)


@pytest.mark.parametrize("text", [
    "time_s,x_m,y_m\n0,0,0\n1,0,1\n",
    "time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,5000,0\n",
    "time_s,x_m,y_m,heading_deg\n1,0,0,0\n0,0,1,0\n",
    "time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,1,1e6\n",
    "time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,1,1e999\n",
    "time_s,x_km,y_m,heading_deg\n0,0,0,0\n1,0,1,0\n",
])
def test_navigation_errors_are_the_same_either_way(tmp_path, monkeypatch, text):
    p = tmp_path / "nav.csv"
    p.write_text(text)
    with pytest.raises(InputError) as plain:
        read_navigation(p)
    monkeypatch.setattr(tables, "PLAIN_CSV_MAX_BYTES", 0)
    with pytest.raises(InputError) as through_pandas:
        read_navigation(p)
    assert str(plain.value) == str(through_pandas.value)


def test_navigation_is_the_same_either_way(tmp_path, monkeypatch):
    p = tmp_path / "nav.csv"
    t = np.arange(50.0)
    rows = "".join(f"{a},{0.1 * a:.6f},{3.086667 * a},{(2.5 * a) % 360},{-1.3},{3.086667 * a - 200:.4f},{2.5 * a}\n"
                   for a in t)
    p.write_text("time_s,x_m,y_m,heading_deg,array_x_m,array_y_m,array_heading_deg\n" + rows)
    a = read_navigation(p)
    monkeypatch.setattr(tables, "PLAIN_CSV_MAX_BYTES", 0)
    b = read_navigation(p)
    for f in ("time_s", "x_m", "y_m", "heading_rad", "array_x_m", "array_y_m", "array_heading_rad"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
