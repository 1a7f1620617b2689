"""The clutter map (detection/clutter_map.py): recurrence in the world frame, and the stillness test that spares
slow targets, checked against hand-worked least-squares fits and against simulated still points and movers."""

import numpy as np
import pytest
from scipy.stats import chi2

from sonartrack.detection.clutter_map import ClutterMap, _add_point, still_statistic


def fit_stat(points, times, R):
    """The statistic by the normal equations written out (an independent route: numpy lstsq on whitened rows)."""
    L = np.linalg.cholesky(np.linalg.inv(R))  # W = L L^T; whitened rows L^T H, L^T z
    rows, rhs = [], []
    for z, t in zip(points, times, strict=True):
        H = np.hstack([np.eye(2), t * np.eye(2)])
        rows.append(L.T @ H)
        rhs.append(L.T @ z)
    A, y = np.vstack(rows), np.concatenate(rhs)
    theta = np.linalg.lstsq(A, y, rcond=None)[0]
    C = np.linalg.inv(A.T @ A)
    v = theta[2:]
    return float(v @ np.linalg.solve(C[2:, 2:], v))


def test_two_points_give_the_squared_drift_over_twice_the_variance():
    # z0 = 0 at t = 0, z1 = d at t = -T, R = s^2 I: v = -d / T, C_vv = 2 s^2 / T^2 I -> |d|^2 / (2 s^2)
    info, vec = np.zeros((1, 4, 4)), np.zeros((1, 4))
    W = np.eye(2)[None] / 25.0
    _add_point(info, vec, np.ones(1, bool), np.zeros((1, 2)), W, 0.0)
    _add_point(info, vec, np.ones(1, bool), np.array([[30.0, -40.0]]), W, -30.0)
    assert still_statistic(info, vec)[0] == pytest.approx(50.0**2 / (2 * 25.0))


def test_many_points_match_an_independent_least_squares_fit():
    rng = np.random.default_rng(3)
    R = np.array([[900.0, 300.0], [300.0, 400.0]])
    times = -30.0 * np.arange(6)
    points = rng.normal(0, 40, (6, 2))
    points[0] = 0.0  # the new contact is the origin of the fit
    info, vec = np.zeros((1, 4, 4)), np.zeros((1, 4))
    for z, t in zip(points, times, strict=True):
        _add_point(info, vec, np.ones(1, bool), z[None], np.linalg.inv(R)[None], t)
    assert still_statistic(info, vec)[0] == pytest.approx(fit_stat(points, times, R), rel=1e-9)


def track(speed_mps, pings=14, sd=(60.0, 8.0), seed=0, still_probability=0.99):
    """Flags of one point crossing the beam (the large error's axis) at ``speed_mps``, 30 s pings."""
    rng = np.random.default_rng(seed)
    m = ClutterMap(8, 3, still_probability=still_probability)
    R = np.diag(np.square(sd))[None]
    out = []
    for k in range(pings):
        z = np.array([2000.0 + speed_mps * 30.0 * k, 4000.0]) + rng.normal(0, sd)
        out.append(bool(m.update(z[None], R, 30.0 * k)[0]))
    return np.array(out)


def test_a_still_point_is_clutter_from_its_fourth_ping_on_nearly_always():
    flags = np.array([track(0.0, seed=s) for s in range(40)])
    assert not flags[:, :3].any()  # fewer than 3 remembered hits
    assert flags[:, 3:].mean() > 0.95  # called moving on ~1 % of its pings (chi2_2 at 0.99), gate misses rarer


def test_the_stillness_test_is_chi2_with_two_degrees_of_freedom_on_a_still_point():
    # the fraction of a still point's recurring contacts called moving is 1 - still_probability
    called_moving = np.array([~track(0.0, pings=12, seed=s, still_probability=0.8)[4:] for s in range(60)])
    assert called_moving.mean() == pytest.approx(0.2, abs=0.06)


def test_a_slow_target_is_spared_where_recurrence_alone_marks_it():
    # 1.5 m/s across the beam: 45 m a ping, inside the 3 sqrt(2) x 60 m gate for 5 pings back
    old = np.array([track(1.5, seed=s, still_probability=None)[6:] for s in range(30)]).mean()
    new = np.array([track(1.5, seed=s)[6:] for s in range(30)]).mean()
    assert old > 0.9 and new < 0.3, (old, new)


def test_a_target_along_the_beam_is_spared_at_a_few_tenths_of_a_metre_a_second():
    rng = np.random.default_rng(1)
    m, R = ClutterMap(8, 3), np.diag([8.0**2, 60.0**2])[None]  # along x: the delay's small error
    flags = [bool(m.update((np.array([2000.0 + 0.4 * 30.0 * k, 4000.0]) + rng.normal(0, [8.0, 60.0]))[None], R,
                           30.0 * k)[0]) for k in range(12)]
    assert sum(flags[5:]) <= 1


def test_the_chi2_threshold_is_the_stated_quantile():
    assert ClutterMap(still_probability=0.95).still_gamma == pytest.approx(chi2.ppf(0.95, 2))
