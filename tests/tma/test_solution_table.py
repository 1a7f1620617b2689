"""The solution table: derived quantities and first-order standard deviations on hand-worked cases."""

import numpy as np
import pytest

from sonartrack.tma.records import OwnshipTrack, TmaSolution
from sonartrack.tma.solution_table import solution_columns

OWN = OwnshipTrack(time_s=np.array([0.0, 100.0]), x_m=np.zeros(2), y_m=np.zeros(2))


def test_solution_columns_hand_case():
    """Target 1 km due north of an ownship at the origin, moving east at 5 m/s."""
    P = np.diag([400.0, 900.0, 0.04, 0.09])
    sol = TmaSolution(time_s=np.array([0.0]), state=np.array([[0.0, 1000.0, 5.0, 0.0]]), covariance=P[None],
                      method="test")
    c = solution_columns(sol, OWN)
    assert c["range_m"][0] == pytest.approx(1000.0) and c["bearing_deg"][0] == pytest.approx(0.0)
    assert c["course_deg"][0] == pytest.approx(90.0) and c["speed_kn"][0] == pytest.approx(5 * 3600 / 1852)
    assert c["range_std_m"][0] == pytest.approx(30.0)  # along y: sqrt(900)
    assert c["bearing_std_deg"][0] == pytest.approx(np.rad2deg(20.0 / 1000.0))  # across: sqrt(400) / r
    assert c["speed_std_kn"][0] == pytest.approx(0.2 * 3600 / 1852)  # along vx
    assert c["course_std_deg"][0] == pytest.approx(np.rad2deg(0.3 / 5.0))  # across: sqrt(0.09) / s
    assert c["x_std_m"][0] == pytest.approx(20.0) and c["vy_std_mps"][0] == pytest.approx(0.3)


def test_bearing_and_course_are_clockwise_from_north_in_0_360():
    """Target south-west of the ownship heading north-west: bearing 225, course 315."""
    sol = TmaSolution(time_s=np.array([0.0]), state=np.array([[-1000.0, -1000.0, -1.0, 1.0]]),
                      covariance=np.eye(4)[None], method="test")
    c = solution_columns(sol, OWN)
    assert c["bearing_deg"][0] == pytest.approx(225.0) and c["course_deg"][0] == pytest.approx(315.0)
    assert c["range_m"][0] == pytest.approx(np.hypot(1000.0, 1000.0))


def test_course_std_saturates_at_zero_speed():
    sol = TmaSolution(time_s=np.array([0.0]), state=np.array([[0.0, 1000.0, 0.0, 0.0]]), covariance=np.eye(4)[None],
                      method="test")
    assert solution_columns(sol, OWN)["course_std_deg"][0] == 180.0
