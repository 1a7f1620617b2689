"""The clutter map (detection/clutter_map.py): recurrence in the world frame, and the stillness test that spares
moving targets, checked against hand-worked least-squares fits and on simulated still points and movers."""

import numpy as np
import pytest
from scipy.stats import chi2

from sonartrack.detection.clutter_map import ClutterMap, _add_point, same_range, speed_bound, velocity_fit


def lstsq_velocity(points, times, R):
    """The fit's velocity and its covariance by numpy lstsq on whitened rows (an independent route)."""
    L = np.linalg.cholesky(np.linalg.inv(R))  # W = L L^T; whitened rows L^T H, L^T z
    A = np.vstack([L.T @ np.hstack([np.eye(2), t * np.eye(2)]) for t in times])
    y = np.concatenate([L.T @ z for z in points])
    theta = np.linalg.lstsq(A, y, rcond=None)[0]
    return theta[2:], np.linalg.inv(A.T @ A)[2:, 2:]


def fit(points, times, R):
    info, vec = np.zeros((1, 4, 4)), np.zeros((1, 4))
    for z, t in zip(points, times, strict=True):
        _add_point(info, vec, np.ones(1, bool), np.asarray(z, float)[None], np.linalg.inv(R)[None], t)
    return info, vec


def test_two_points_give_the_drift_over_the_time_and_its_hand_worked_bound():
    # z0 = 0 at t = 0, z1 = (30, -40) at t = -30 s, R = 25 I: v = (-1, 4/3), C_vv = 2 x 25 / 30^2 I
    info, vec = fit([(0.0, 0.0), (30.0, -40.0)], [0.0, -30.0], 25.0 * np.eye(2))
    ok, v, C = velocity_fit(info, vec)
    assert ok[0] and v[0] == pytest.approx([-1.0, 4.0 / 3.0]) and C[0] == pytest.approx(50.0 / 900.0 * np.eye(2))
    assert speed_bound(info, vec, 9.0)[0] == pytest.approx(50.0 / 30.0 + 3.0 * np.sqrt(50.0 / 900.0))


def test_many_points_match_an_independent_least_squares_fit():
    rng = np.random.default_rng(3)
    R = np.array([[900.0, 300.0], [300.0, 400.0]])
    times = -30.0 * np.arange(6)
    points = rng.normal(0, 40, (6, 2))
    points[0] = 0.0  # the new contact is the origin of the fit
    ok, v, C = velocity_fit(*fit(points, times, R))
    v_ref, C_ref = lstsq_velocity(points, times, R)
    assert v[0] == pytest.approx(v_ref, rel=1e-9) and C[0] == pytest.approx(C_ref, rel=1e-9)


def test_one_point_has_no_velocity_and_no_bound():
    info, vec = fit([(0.0, 0.0)], [0.0], np.eye(2))
    assert speed_bound(info, vec, 4.6)[0] == np.inf


def track(speed_mps, pings=14, sd=(60.0, 8.0), seed=0, **kw):
    """Flags of one point crossing the beam (the large error's axis) at ``speed_mps``, 30 s pings."""
    rng = np.random.default_rng(seed)
    m = ClutterMap(8, 3, **kw)
    R = np.diag(np.square(sd))[None]
    out = []
    for k in range(pings):
        z = np.array([2000.0 + speed_mps * 30.0 * k, 4000.0]) + rng.normal(0, sd)
        out.append(bool(m.update(z[None], R, 30.0 * k)[0]))
    return np.array(out)


def test_a_still_point_is_learned_once_its_fit_shows_it_slow():
    flags = np.array([track(0.0, seed=s) for s in range(20)])
    assert not flags[:, :3].any()  # fewer than 3 remembered hits
    # sigma_v of n points 30 s apart at 60 m: 60 sqrt(12 / (n (n^2 - 1))) / 30; 2.15 sigma_v < 1.5 m/s from n ~ 6
    assert flags[:, 8:].mean() > 0.95


def test_a_target_faster_than_the_slow_speed_is_spared_where_recurrence_alone_marks_it():
    # 2.5 m/s across the beam: 75 m a ping, inside the 3 sqrt(2) x 60 m gate for 3 pings back
    old = np.array([track(2.5, seed=s, still_probability=None)[4:] for s in range(15)]).mean()
    new = np.array([track(2.5, seed=s)[4:] for s in range(15)]).mean()
    assert old > 0.5 and new < 0.05, (old, new)


def test_a_target_along_the_beam_is_spared():
    rng = np.random.default_rng(1)
    m, R = ClutterMap(8, 3), np.diag([8.0**2, 60.0**2])[None]  # along x: the delay's small error
    flags = [bool(m.update((np.array([2000.0 + 2.0 * 30.0 * k, 4000.0]) + rng.normal(0, [8.0, 60.0]))[None], R,
                           30.0 * k)[0]) for k in range(12)]
    assert not any(flags)


def test_the_ellipse_level_is_the_stated_quantile():
    assert ClutterMap(still_probability=0.95).still_gamma == pytest.approx(chi2.ppf(0.95, 2))


def test_same_range_marks_the_weaker_contacts_on_a_recurring_echos_ellipse():
    # Tx (0, 0), Rx (300, 0): the anchor (0, 4000) has r_B = 4000 + hypot(300, 4000) = 8011.23 m; on the x axis
    # beyond Rx, r_B = x + (x - 300), so the same ellipse is at x = 4155.61 m
    x_img = (4000.0 + np.hypot(300.0, 4000.0) + 300.0) / 2.0
    xy = np.array([[0.0, 4000.0],          # the anchor (recurring), statistic 100
                   [x_img + 5.0, 0.0],     # r_B 10 m longer, weaker: an image
                   [x_img - 5.0, 0.0],     # r_B 10 m shorter, stronger: not an image
                   [x_img + 20.0, 0.0],    # r_B 40 m longer: outside the window
                   [0.0, -4000.0],         # the anchor's mirror twin, equal statistic: not an image
                   [-1000.0, 100.0]])      # far off the ellipse, weaker
    stat = np.array([100.0, 40.0, 150.0, 40.0, 100.0, 10.0])
    anchor = np.array([True, False, False, False, False, False])
    got = same_range(xy, [0.0, 0.0], [300.0, 0.0], anchor, stat, 15.0)
    assert got.tolist() == [False, True, False, False, False, False]
    assert not same_range(xy, [0.0, 0.0], [300.0, 0.0], np.zeros(6, bool), stat, 15.0).any()
