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


def _contacts(rng, xy0, v, R, t):
    """One noisy contact of a point at xy0 + v t (m), its error drawn from R (m^2): the data the map sees."""
    return (np.asarray(xy0, float) + np.asarray(v, float) * t + rng.multivariate_normal([0.0, 0.0], R))[None], R[None]


def test_longer_fit_shows_a_point_still_whose_contacts_are_wide_across_the_beam():
    # sigma 150 m across the beam, 30 s pings: 8 pings give sigma_v = 150 sqrt(12 / (8 * 63)) / 30 = 0.77 m/s, the
    # bound |v| + sqrt(chi2_2(0.9) = 4.6) 0.77 = 1.65 m/s > 1 m/s: never still; 24 pings: sigma_v 0.15, still
    R = np.diag([150.0**2, 30.0**2])
    verdicts = {}
    for fit_span in (None, 24):
        rng = np.random.default_rng(3)
        m = ClutterMap(8, 3, slow_mps=1.0, fit_span=fit_span, keep_pings=None)
        verdicts[fit_span] = [bool(m.update(*_contacts(rng, [5000.0, 2000.0], [0.0, 0.0], R, 30.0 * k), 30.0 * k)[0])
                              for k in range(40)]
    assert not any(verdicts[None])
    assert all(verdicts[24][30:])
    # a target at 3 m/s along the wide axis is not shown still however long the fit
    rng = np.random.default_rng(4)
    m = ClutterMap(8, 3, slow_mps=1.0, fit_span=24, keep_pings=None)
    assert not any(m.update(*_contacts(rng, [5000.0, 2000.0], [3.0, 0.0], R, 30.0 * k), 30.0 * k)[0]
                   for k in range(40))


def test_known_point_stays_clutter_until_it_is_not_seen():
    R = np.diag([40.0**2, 40.0**2])
    rng = np.random.default_rng(5)
    m = ClutterMap(8, 3, slow_mps=1.0, fit_span=8, keep_pings=5)
    got = [bool(m.update(*_contacts(rng, [0.0, 0.0], [0.0, 0.0], R, 30.0 * k), 30.0 * k)[0]) for k in range(12)]
    assert got[-1] and len(m.known[0]) >= 1
    # the same place seen with 20 times wider errors: no new fit passes, the known point still marks it
    wide = R * 400.0
    m2 = ClutterMap(8, 3, slow_mps=1.0, fit_span=8, keep_pings=None)
    for k in range(12):
        m2.update(*_contacts(rng, [0.0, 0.0], [0.0, 0.0], R, 30.0 * k), 30.0 * k)
    later = [(bool(m.update(*_contacts(rng, [0.0, 0.0], [0.0, 0.0], wide, 30.0 * k), 30.0 * k)[0]),
              bool(m2.update(*_contacts(rng, [0.0, 0.0], [0.0, 0.0], wide, 30.0 * k), 30.0 * k)[0]))
             for k in range(12, 16)]
    assert all(a for a, _ in later) and not all(b for _, b in later)
    # pings without a contact there: forgotten after keep_pings of them
    for k in range(16, 23):
        m.update(np.array([[9000.0, 9000.0]]), R[None], 30.0 * k)
    assert not (np.hypot(*m.known[0].T) < 1000.0).any()
