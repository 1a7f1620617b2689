"""The navigation reader of the passive chain: columns, units, coverage, interpolation."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.navigation import check_navigation_covers, read_navigation


def _write(tmp_path, text, name="nav.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _nav_text(n=10, heading=lambda t: 0.0, array=True):
    head = "time_s,x_m,y_m,heading_deg" + (",array_x_m,array_y_m,array_heading_deg" if array else "")
    rows = []
    for t in range(n):
        row = f"{t},{0.0},{3.0 * t},{heading(t)}"
        if array:
            row += f",{0.0},{3.0 * t - 200},{heading(t)}"
        rows.append(row)
    return head + "\n" + "\n".join(rows) + "\n"


def test_reads_array_columns_and_interpolates(tmp_path):
    nav = read_navigation(_write(tmp_path, _nav_text()))
    xy, h = nav.array_at([2.5])
    assert xy[0] == pytest.approx([0.0, 7.5 - 200])
    assert h[0] == pytest.approx(0.0)


def test_without_array_columns_the_array_is_the_ship(tmp_path):
    nav = read_navigation(_write(tmp_path, _nav_text(array=False)))
    assert np.array_equal(nav.array_x_m, nav.x_m) and np.array_equal(nav.array_heading_rad, nav.heading_rad)


def test_heading_through_north_interpolates_the_short_way(tmp_path):
    # 350 deg then 10 deg: halfway is 0 (= 360), not 180
    nav = read_navigation(_write(tmp_path, _nav_text(n=2, heading=lambda t: 350.0 if t == 0 else 10.0)))
    _, h = nav.array_at([0.5])
    assert np.rad2deg(h[0]) % 360.0 == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(("text", "words"), [
    ("time_s,x_m,y_m\n0,0,0\n1,0,1\n", "lacks column"),
    (_nav_text().replace("0,0.0,0.0,0.0,0.0,-200", "0,0.0,0.0,nan,0.0,-200", 1), "NaN"),
    ("time_s,x_m,y_m,heading_deg,array_x_m\n0,0,0,0,0\n1,0,1,0,0\n", "all of"),
    ("time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,5000,0\n", "m/s"),
    ("time_s,x_m,y_m,heading_deg\n1,0,0,0\n0,0,1,0\n", "sort"),
    ("time_s,x_m,y_m,heading_deg\n" + "".join(f"{t},0,{t},{0.1 * t}\n" for t in range(6)), "radians"),
    ("time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,1,1e6\n", "heading"),
])
def test_bad_navigation_is_one_clear_error(tmp_path, text, words):
    with pytest.raises(InputError, match=words):
        read_navigation(_write(tmp_path, text))


def test_coverage(tmp_path):
    nav = read_navigation(_write(tmp_path, _nav_text(n=10)))
    check_navigation_covers(nav, 0.0, 9.0)
    with pytest.raises(InputError, match="covers 0..9 s"):
        check_navigation_covers(nav, 0.0, 20.0)
