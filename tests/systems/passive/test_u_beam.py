"""A line array's beam in u = cos(theta): the neighbour rules of the passive chain and the ML's noise law.

A line array's beam has one width in u at every steering angle (Van Trees, Optimum Array Processing, 2002,
sec. 2.4), so near endfire a beam spans many degrees of cone angle; and its cone-angle noise is white in u,
sigma_theta = sigma_u / sin(theta).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from sonartrack.systems.passive.measurements import TrackMeasurements, within_one_beam
from sonartrack.systems.passive.shared_scans import drop_unresolved
from sonartrack.systems.passive.targets import endfire_reach_rad, line_array_relative_sigma, u_weighted_fit
from sonartrack.tma.sides import fit_cv_target

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import bearings, leg_turn_leg  # noqa: E402


def track(track_id, t, cone):
    t, cone = np.asarray(t, float), np.asarray(cone, float)
    return TrackMeasurements(track_id, t, cone, np.ones(len(t)), t, cone)


# ------------------------------------------------------------------------------------------------ one beam in u


def test_two_cone_angles_share_a_beam_by_their_direction_cosines():
    # beamwidth 2 deg = 0.034907 rad in u. By hand: cos 10 - cos 13 = 0.984808 - 0.974370 = 0.010438 < 0.0349, one
    # beam although 3 deg apart; cos 88 - cos 91 = 0.034899 + 0.017452 = 0.052351 > 0.0349, resolved (as in degrees)
    assert within_one_beam(10.0, 13.0, 2.0)
    assert not within_one_beam(88.0, 91.0, 2.0)
    # near endfire the beam reaches far: 0 and 10.5 deg (du = 1 - 0.983255 = 0.016745) share a 1 deg beam
    # (0.017453 rad); 0 and 11 deg (du = 0.018369) do not
    np.testing.assert_array_equal(within_one_beam(0.0, np.array([10.5, 11.0]), 1.0), [True, False])
    # u is the same for a cone angle's images through the axis: 10 deg and -13 deg (or 347 deg) share a beam too
    np.testing.assert_array_equal(within_one_beam(10.0, np.array([-13.0, 347.0, 167.0]), 2.0), [True, True, False])


def test_two_tracks_near_endfire_lose_the_scans_they_share_a_beam():
    t = np.arange(20.0)
    a = track(1, t, np.full(20, 10.0))
    b = track(2, t, np.r_[np.full(10, 13.0), np.full(10, 30.0)])  # one beam, then cos 10 - cos 30 = 0.119 apart
    out = drop_unresolved([a, b], min_separation_deg=2.0)
    assert out[0].time_s.tolist() == list(range(10, 20)) and out[1].time_s.tolist() == list(range(10, 20))
    c, d = track(1, t, np.full(20, 88.0)), track(2, t, np.full(20, 91.0))
    assert [len(m.time_s) for m in drop_unresolved([c, d], min_separation_deg=2.0)] == [20, 20]


def test_two_tracks_near_endfire_cross_while_they_share_a_beam():
    # the crossing spans of swap_at_crossings: filtered tracks 3 deg apart near endfire are within one 2 deg beam
    # (0.0104 < 0.0349) until one turns away to 30 deg at t = 10 s; at broadside 3 deg apart they never cross
    from sonartrack.systems.passive.fragments import _close_spans

    t = np.arange(20.0)
    a, b = track(1, t, np.full(20, 10.0)), track(2, t, np.r_[np.full(10, 13.0), np.full(10, 30.0)])
    assert _close_spans(a, b, 2.0) == [(0.0, 9.0)]
    assert _close_spans(track(1, t, np.full(20, 88.0)), track(2, t, np.full(20, 91.0)), 2.0) == []


# ------------------------------------------------------------------------------------------------ the noise law


def test_relative_noise_is_one_over_sin_theta_floored_near_the_axis():
    # 1 / max(|sin theta|, 0.05): at 30 deg (and 150, -30) twice broadside's; on the axis 20; at 2 deg 1 / 0.05 too
    # (sin 2 deg = 0.0349 < 0.05), at 5 deg 1 / sin 5 deg = 11.474
    rel = line_array_relative_sigma(np.deg2rad([90.0, 30.0, 150.0, -30.0, 0.0, 180.0, 2.0, 5.0]))
    np.testing.assert_allclose(rel, [1.0, 2.0, 2.0, 2.0, 20.0, 20.0, 20.0, 11.474], rtol=1e-4)
    # the floor is a parameter: the endfire reach of a 2 deg beam, arccos(1 - 0.017453) = 10.72 deg, has
    # sin = sqrt(du - du^2 / 4) = 0.18602
    reach = endfire_reach_rad(2.0)
    assert np.rad2deg(reach) == pytest.approx(10.72, abs=0.01)
    assert line_array_relative_sigma(np.array([0.0]), np.sin(reach))[0] == pytest.approx(1 / 0.18602, rel=1e-4)


def _record(seed, bias_deg=0.0):
    """A target 1.5 km off a leg-turn-leg ownship over 400 s, its cone angle measured against the ownship's north
    axis (theta = the bearing's angle from north): noise white in u (sigma_u = 0.002), and a bias near the axis."""
    t = np.arange(0.0, 400.0, 1.0)
    own = leg_turn_leg(t)
    x0 = np.array([300.0, 1500.0, 1.0, -3.0])
    truth = bearings(t, own, x0[:2], x0[2:], 0.0, seed)
    rel = line_array_relative_sigma(truth)
    noise = 0.002 * rel * np.random.default_rng(seed).standard_normal(t.size)
    near = rel > 3.0  # within 19.5 deg of the axis (sin theta < 1/3)
    z = truth + noise + np.where(near, np.deg2rad(bias_deg), 0.0)
    end = x0[:2] + x0[2:] * t[-1]
    return t, own, z, rel, near, end


@pytest.mark.parametrize("seed", range(3))
def test_the_weighted_fit_measures_sigma_u_and_weighs_the_scans_near_the_axis_little(seed):
    t, own, z, rel, near, _ = _record(seed)
    assert 40 < near.sum() < 360  # the record holds both
    start = fit_cv_target(z, t, own)
    est, sigma_u = u_weighted_fit(z, t, own, rel, start)
    # sigma_u^2 = J_w / (n - 4), J_w the weighted cost: the noise put in, 0.002 (n = 400: within 10 %)
    assert sigma_u == pytest.approx(0.002, rel=0.1)
    assert est.objective == pytest.approx(np.sum(((z - _h(est, t, own)) / rel) ** 2), rel=1e-9)
    # the covariance is (H^T W H)^-1 sigma_u^2: the inverse of the weighted information at the fit
    H = _jac(est, t, own) / rel[:, None]
    np.testing.assert_allclose(est.covariance, np.linalg.inv(H.T @ H) * sigma_u**2, rtol=1e-6)


def test_a_bias_near_the_axis_moves_the_weighted_fit_less():
    # a 1 deg bias on the scans within 19.5 deg of the axis (the peak pulled by a ship in the endfire beam): the
    # equal-weight fit takes it as motion; weighted by the noise law, those scans count 1 / rel^2 <= 1/9 as much
    # the bias's own effect: each fit of the biased record against the same fit of the record without it
    t, own, z, rel, _, _ = _record(0, bias_deg=1.0)
    z0 = _record(0)[2]

    def end_xy(zz, weighted):
        plain = fit_cv_target(zz, t, own)
        fit = u_weighted_fit(zz, t, own, rel, plain)[0] if weighted else plain
        return fit.state_at(t[-1])[0][0, :2]

    shift = [end_xy(z, w) - end_xy(z0, w) for w in (False, True)]
    assert np.hypot(*shift[1]) < 0.7 * np.hypot(*shift[0])  # measured 76 m against 126 m
    # and it is the weighted least-squares response to the bias, (H^T W H)^-1 H^T W b, carried to the last time
    est = u_weighted_fit(z0, t, own, rel, fit_cv_target(z0, t, own))[0]
    H, w = _jac(est, t, own), 1.0 / rel**2
    dx0 = np.linalg.solve(H.T @ (H * w[:, None]), H.T @ (w * (z - z0)))
    np.testing.assert_allclose(shift[1], dx0[:2] + dx0[2:] * (t[-1] - t[0]), rtol=0.1)


def _h(est, t, own):
    x = est.x0[0] + est.x0[2] * (t - est.t0_s) - own[:, 0]
    y = est.x0[1] + est.x0[3] * (t - est.t0_s) - own[:, 1]
    return np.arctan2(x, y)


def _jac(est, t, own):
    tau = t - est.t0_s
    dx = est.x0[0] + est.x0[2] * tau - own[:, 0]
    dy = est.x0[1] + est.x0[3] * tau - own[:, 1]
    r2 = dx**2 + dy**2
    return np.stack([dy, -dx, tau * dy, -tau * dx], axis=-1) / r2[:, None]


@pytest.mark.parametrize("seed", range(3))
def test_residuals_are_judged_against_each_bearing_s_own_noise(seed):
    # noise white in u: judged with the weights it was fitted with, the residuals agree with sigma_u (the solution
    # is returned as it is); judged as if every bearing had broadside's noise sigma_u, they measure about
    # mean(rel^2) times that (here > 3) and the covariance is inflated
    from sonartrack.systems.passive.targets import determination_checked
    from sonartrack.tma.records import BearingRecord, OwnshipTrack
    from sonartrack.tma.settings import TmaSettings
    from sonartrack.tma.solve import solve_tma

    t, own, z, rel, _, _ = _record(seed)
    assert np.mean(rel**2) > 3.0
    est, sigma_u = u_weighted_fit(z, t, own, rel, fit_cv_target(z, t, own))
    sensor = OwnshipTrack(time_s=t, x_m=own[:, 0], y_m=own[:, 1])
    settings = TmaSettings(method="ml", sigma_bearing_deg=float(np.rad2deg(sigma_u)))
    assert not settings.batch.correlation_inflation
    res = solve_tma(BearingRecord(time_s=t, bearing_rad=z), sensor, settings, ml_fit=est, unobservable="flag",
                    record_checks=False)  # as the chain calls it
    assert res.solution.range_flags()[-1]
    assert determination_checked(res, rel) is res
    equal = determination_checked(res)
    assert equal.solution.range_flags()[-1] and "covariance inflated by" in equal.warnings[-1]
    scale = float(equal.warnings[-1].split("covariance inflated by ")[1].split(" ")[0])
    assert scale > 3.0
