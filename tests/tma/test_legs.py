"""Leg-wise bearings-only ML (tma/legs.py): exact recovery, Jacobian, CRB against Monte Carlo and a closed form,
agreement with the project's CV ML, observability per leg, bad input. Worlds built here with numpy alone."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.tma.batch_ml import crb, ml_bearings_only
from sonartrack.tma.legs import crb_legs, fisher_information_legs, fit_legs, leg_bearing_model

KN = 1852.0 / 3600.0


def polyline(t, p0, change_times, velocities):
    """Continuous piecewise-constant-velocity positions (n, 2): its own integration, not legs.py's."""
    p = np.empty((len(t), 2))
    v_index = np.searchsorted(np.asarray(change_times, float), t, side="left")  # leg holding each time
    pos, last_t, leg = np.asarray(p0, float).copy(), t[0], 0
    for i, ti in enumerate(t):
        while leg < len(change_times) and change_times[leg] <= ti:
            pos = pos + velocities[leg] * (change_times[leg] - last_t)
            last_t, leg = change_times[leg], leg + 1
        assert leg == v_index[i]
        p[i] = pos + velocities[leg] * (ti - last_t)
    return p


def vel(course_deg, speed_kn):
    c = np.radians(course_deg)
    return speed_kn * KN * np.array([np.sin(c), np.cos(c)])


def world(dt=30.0, span=5400.0):
    """Ownship at 6 kn on four legs (N, E, N, W); target on three legs (200 deg 8 kn, 260 deg 8 kn, 180 deg 10 kn)
    changing at 1815 and 3620 s (between bearings), starting 10.8 km away."""
    t = np.arange(0.0, span + 1e-9, dt) + 3.0
    own = polyline(t, [0.0, 0.0], [1200.0, 2700.0, 4000.0], [vel(0, 6), vel(90, 6), vel(0, 6), vel(270, 6)])
    ct = np.array([1815.0, 3620.0])
    vt = [vel(200, 8), vel(260, 8), vel(180, 10)]
    tgt = polyline(t, [6000.0, 9000.0], ct, vt)
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])
    return t, z, own, ct, np.r_[6000.0, 9000.0, np.ravel(vt)], tgt


def test_noise_free_legs_recover_the_truth_with_change_times_refined():
    t, z, own, ct, theta, tgt = world()
    fit = fit_legs(t, z, own, np.radians(1.0), ct + [150.0, -200.0], refine=True)
    assert fit.converged and fit.refined
    np.testing.assert_allclose(fit.change_times_s, ct, rtol=1e-6)
    for k in range(3):  # each leg's velocity, relative to its speed
        v = theta[2 + 2 * k:4 + 2 * k]
        assert np.linalg.norm(fit.params[2 + 2 * k:4 + 2 * k] - v) <= 1e-6 * np.linalg.norm(v)
    assert np.linalg.norm(fit.params[:2] - theta[:2]) <= 1e-6 * np.linalg.norm(theta[:2])
    assert np.linalg.norm(fit.position_end_m - tgt[-1]) <= 1e-6 * np.linalg.norm(tgt[-1] - own[-1])
    np.testing.assert_allclose([leg.course_deg for leg in fit.legs], [200, 260, 180], atol=1e-5)
    np.testing.assert_allclose([leg.speed_kn for leg in fit.legs], [8, 8, 10], rtol=1e-6)
    assert [leg.start_s for leg in fit.legs] == pytest.approx([t[0], *ct], rel=1e-6)
    assert all(leg.determined and leg.reason == "" for leg in fit.legs)
    assert all(leg.end_sd_s > 0 for leg in fit.legs[:-1])  # the change times' uncertainty is reported


def test_jacobian_and_fisher_information_against_finite_differences():
    t, _, own, ct, theta, _ = world()
    _, J, _ = leg_bearing_model(theta, ct, t, own, t[0], with_change_times=True)
    x = np.r_[theta, ct]
    eps = np.r_[1.0, 1.0, np.full(6, 1e-3), 0.5, 0.5]
    num = np.empty_like(J)
    for i in range(len(x)):
        d = np.eye(len(x))[i] * eps[i]
        hp = leg_bearing_model((x + d)[:8], (x + d)[8:], t, own, t[0])[0]
        hm = leg_bearing_model((x - d)[:8], (x - d)[8:], t, own, t[0])[0]
        num[:, i] = (hp - hm) / (2 * eps[i])
    np.testing.assert_allclose(J, num, rtol=1e-5, atol=1e-9)
    sigma = np.radians(0.7)
    np.testing.assert_allclose(fisher_information_legs(theta, ct, t, own, sigma, t[0], True), num.T @ num / sigma**2,
                               rtol=1e-5)


def test_one_leg_is_the_projects_constant_velocity_ml():
    t, _, own, _, _, _ = world()
    x0 = np.array([6000.0, 9000.0, *vel(200, 8)])
    tgt = x0[:2] + (t - t[0])[:, None] * x0[2:]
    rng = np.random.default_rng(5)
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1]) + rng.normal(0, np.radians(1.0), len(t))
    fit = fit_legs(t, z, own, np.radians(1.0), [])
    cv = ml_bearings_only(z, t, own, np.radians(1.0))
    np.testing.assert_allclose(fit.params, cv.x0, rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(fit.covariance, cv.covariance, rtol=1e-5)
    np.testing.assert_allclose(crb_legs(x0, [], t, own, 0.01)[0], crb(x0, t - t[0], own, 0.01), rtol=1e-8)


def test_equal_velocities_reduce_to_the_constant_velocity_information():
    """Two legs with equal velocities are the CV track: J_CV = T^T J_legs T, T = d[p0, v1, v2] / d[p0, v]."""
    t, _, own, _, _, _ = world()
    x0 = np.array([6000.0, 9000.0, *vel(200, 8)])
    T = np.zeros((6, 4))
    T[:2, :2] = np.eye(2)
    T[2:4, 2:] = T[4:6, 2:] = np.eye(2)
    J2 = fisher_information_legs(np.r_[x0, x0[2:]], [2000.0], t, own, 0.01, t[0])
    np.testing.assert_allclose(T.T @ J2 @ T, np.linalg.inv(crb(x0, t - t[0], own, 0.01)), rtol=1e-9)


def test_crb_by_hand_for_a_two_leg_track():
    """Closed form: observers that see only x (from the south, 10 km off) at t = 0, c, 2c and only y (from the
    west) at the same times, of a target that stays near the origin. Each axis is then a linear regression
    x(t_i) = x0 + a_1(t_i) vx_1 + a_2(t_i) vx_2 with rows [1, 0, 0], [1, c, 0], [1, c, c] and noise sd sigma R,
    whose inverse gives var x0 = (sigma R)^2, var vx_1 = var vx_2 = 2 (sigma R / c)^2, cov = -(sigma R / c)^2."""
    R, c, sigma = 10_000.0, 600.0, 0.002
    t = np.array([0.0, 1e-6, c, c + 1e-6, 2 * c, 2 * c + 1e-6])
    own = np.array([[0.0, -R], [-R, 0.0]] * 3)
    B, _ = crb_legs(np.zeros(6), [c + 0.5e-6], t, own, sigma)  # the change just after the bearings at c
    s2 = (sigma * R) ** 2
    for axis in (0, 1):
        idx = [axis, 2 + axis, 4 + axis]
        expected = s2 * np.array([[1, -1 / c, 0], [-1 / c, 2 / c**2, -1 / c**2], [0, -1 / c**2, 2 / c**2]])
        np.testing.assert_allclose(B[np.ix_(idx, idx)], expected, rtol=1e-3, atol=1e-6 * s2 / c)


def test_crb_matches_the_monte_carlo_covariance_of_the_ml():
    """200 noisy records (sigma 0.5 deg): the sample covariance of the ML's final position and leg velocities
    lies within the chi-square sampling interval of the CRB's (99.9 %: variance ratio in [0.70, 1.38] for 200)."""
    t, z0, own, ct, theta, tgt = world(dt=60.0)
    sigma = np.radians(0.5)
    B, leg_crbs = crb_legs(theta, ct, t, own, sigma)
    rng = np.random.default_rng(2004)
    out = []
    for _ in range(200):
        f = fit_legs(t, z0 + rng.normal(0, sigma, len(t)), own, sigma, ct, refine=False, params_init=theta)
        out.append(np.r_[f.position_end_m, f.params[2:]])
    out = np.array(out)
    err = out - np.r_[tgt[-1], theta[2:]]
    var_mc = err.var(axis=0, ddof=1)
    var_crb = np.r_[leg_crbs[-1][0, 0], leg_crbs[-1][1, 1], np.diag(B)[2:]]
    ratio = var_mc / var_crb
    assert np.all((ratio > 0.70) & (ratio < 1.38)), ratio
    assert np.all(np.abs(err.mean(axis=0)) < 4 * np.sqrt(var_crb / 200))  # no bias beyond sampling


def test_a_leg_whose_range_is_not_observed_says_so():
    """Ownship on a straight line at constant speed: scaling the relative track about it keeps every bearing,
    so no leg's range is determined (Nardone & Aidala 1981), even with the target's zig."""
    t = np.arange(0.0, 3600.0, 30.0)
    own = np.column_stack([np.zeros_like(t), 3.0 * t])
    tgt = polyline(t, [7000.0, 8000.0], [1805.0], [vel(250, 9), vel(190, 9)])
    rng = np.random.default_rng(1)
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1]) + rng.normal(0, np.radians(0.5), len(t))
    fit = fit_legs(t, z, own, np.radians(0.5), [1805.0], refine=False)
    assert not any(leg.determined for leg in fit.legs)
    assert all(leg.reason.startswith(f"range not determined on leg {k + 1}") for k, leg in enumerate(fit.legs))
    assert all(leg.information_condition > 1e6 for leg in fit.legs)


@pytest.mark.parametrize("change, match", [
    ([-10.0], "inside the record"), ([2000.0, 1000.0], "increase strictly"), ([20.0], "fewer than 2 bearings"),
    ([np.nan], "finite"),
])
def test_bad_change_times_are_refused_in_one_line(change, match):
    t, z, own, _, _, _ = world()
    with pytest.raises(InputError, match=match) as err:
        fit_legs(t, z, own, 0.01, change)
    assert "\n" not in str(err.value)


def test_bad_records_are_refused_in_one_line():
    t, z, own, ct, _, _ = world()
    z2 = z.copy()
    z2[4] = np.nan
    for args, match in [((t, z2, own, 0.01), "finite"), ((t[::-1], z, own, 0.01), "increase strictly"),
                        ((t, z, own[:, :1], 0.01), "shape"), ((t, z, own, 0.0), "sd must be positive")]:
        with pytest.raises(InputError, match=match) as err:
            fit_legs(*args, ct)
        assert "\n" not in str(err.value)
