"""The navigation reader of the passive chain: columns, units, coverage, interpolation."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.navigation import check_array_fallback, check_navigation_covers, heading_unit, read_navigation


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
    # a ship all but at rest (0.1 m/s): no course made good, so the spread within +-2 pi decides
    ("time_s,x_m,y_m,heading_deg\n" + "".join(f"{t},0,{0.1 * t},{0.1 * t}\n" for t in range(6)), "radians"),
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


def _straight(course_deg, heading, speed_mps=3.0, n=60, array=False):
    """A ship on a straight course at ``speed_mps``; ``heading`` is what the file's heading column holds."""
    t = np.arange(float(n))
    c = np.deg2rad(course_deg)
    x, y = speed_mps * t * np.sin(c), speed_mps * t * np.cos(c)
    head = "time_s,x_m,y_m,heading_deg" + (",array_x_m,array_y_m,array_heading_deg" if array else "")
    rows = [f"{t[i]},{x[i]},{y[i]},{heading}" + (f",{x[i]},{y[i] - 200},{heading}" if array else "")
            for i in range(n)]
    return head + "\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize("course_deg", [10.0, 60.0, 300.0])
def test_radians_on_a_straight_course_are_refused(tmp_path, course_deg):
    # no spread at all: only the course made good between the positions tells radians from degrees
    rad = float(np.deg2rad(course_deg))
    with pytest.raises(InputError, match="radians"):
        read_navigation(_write(tmp_path, _straight(course_deg, rad)))


def test_radians_in_the_array_column_alone_are_refused(tmp_path):
    text = _straight(60.0, 60.0, array=True)
    lines = text.splitlines()
    lines = [lines[0]] + [line.rsplit(",", 1)[0] + f",{np.deg2rad(60.0)}" for line in lines[1:]]
    with pytest.raises(InputError, match="array_heading_deg"):
        read_navigation(_write(tmp_path, "\n".join(lines) + "\n"))


@pytest.mark.parametrize(("course_deg", "heading"), [(3.0, 3.0), (1.0, 4.0), (60.0, 66.0)])
def test_small_headings_in_degrees_that_fit_the_course_are_kept(tmp_path, course_deg, heading):
    # 3 deg on a 3 deg course, a 3 deg drift at 1 deg, a 6 deg drift at 60 deg: degrees, whatever their size
    nav = read_navigation(_write(tmp_path, _straight(course_deg, heading)))
    assert np.rad2deg(nav.heading_rad[0]) == pytest.approx(heading)


def test_a_wandering_small_heading_that_fits_the_course_is_degrees_not_radians(tmp_path):
    # heading 2..4 deg on a course of ~3 deg: the spread alone looked like radians; the course says degrees
    t = np.arange(40.0)
    h = 3.0 + np.sin(t / 5.0)
    x, y = 3.0 * np.cumsum(np.sin(np.deg2rad(h))), 3.0 * np.cumsum(np.cos(np.deg2rad(h)))
    text = "time_s,x_m,y_m,heading_deg\n" + "".join(f"{t[i]},{x[i]},{y[i]},{h[i]}\n" for i in range(40))
    nav = read_navigation(_write(tmp_path, text))
    np.testing.assert_allclose(np.rad2deg(nav.heading_rad), h)


def test_heading_unit_of_a_ship_at_rest_is_unknown():
    t = np.arange(10.0)
    assert heading_unit(np.full(10, 1.0), t, np.zeros(10), 0.1 * t) == "unknown"


def test_array_fallback_is_stated_on_a_straight_course_and_refused_through_a_turn(tmp_path):
    nav = read_navigation(_write(tmp_path, _straight(60.0, 60.0)))
    assert not nav.array_given
    assert "no array columns" in check_array_fallback(nav, "nav.csv")
    turning = _nav_text(n=60, heading=lambda t: 0.0 if t < 30 else min(float(t - 30), 20.0), array=False)
    with pytest.raises(InputError, match="turns 20 deg"):
        check_array_fallback(read_navigation(_write(tmp_path, turning)), "nav.csv")
    assert check_array_fallback(read_navigation(_write(tmp_path, _nav_text()))) is None
