"""Contacts of the active chain: hand-worked bistatic positions, the mirror pair, the covariance, range rate."""

from types import SimpleNamespace

import numpy as np
import pytest

from sonartrack.models.bistatic import bistatic_covariance
from sonartrack.systems.active.contacts import (
    ActiveGeometry,
    Contacts,
    ContactSettings,
    form_contacts,
    predicted_range_rate,
    range_rate_gate,
)


def _still(tx=(0.0, 2400.0), rx=(0.0, 0.0), heading_deg=0.0):
    """Source and receiver standing still (array axis along ``heading_deg``)."""
    t = np.array([-100.0, 1000.0])
    return ActiveGeometry(t, np.array([tx, tx], float), np.array([rx, rx], float), np.full(2, np.deg2rad(heading_deg)))


def _det(travel_time_s, cone_deg, ping=0, range_rate=np.nan):
    n = np.size(travel_time_s)
    return SimpleNamespace(ping=np.full(n, ping), travel_time_s=np.atleast_1d(travel_time_s),
                           cone_deg=np.atleast_1d(cone_deg), range_rate_mps=np.full(n, range_rate),
                           statistic=np.ones(n))


def test_hand_worked_position():
    # Rx at the origin, Tx 2400 m ahead on the axis (north), target at (3000, 4000): |T - Rx| = 5000, |T - Tx| =
    # |(3000, 1600)| = 3400, so r_B = 8400 m, t = 5.6 s at 1500 m/s; cone angle atan2(3, 4) = 36.87 deg; by hand
    # r_R = (8400^2 - 2400^2) / (2 (8400 - 0.8 * 2400)) = 64.8e6 / 12960 = 5000.
    c = form_contacts(_det(5.6, np.rad2deg(np.arctan2(3.0, 4.0))), [0.0], _still(), 1500.0)
    assert len(c) == 2
    np.testing.assert_allclose(c.rx_range_m, [5000.0, 5000.0], rtol=1e-12)
    np.testing.assert_allclose(c.xy[c.side == 1][0], [3000.0, 4000.0], atol=1e-8)
    np.testing.assert_allclose(c.xy[c.side == -1][0], [-3000.0, 4000.0], atol=1e-8)


@pytest.mark.parametrize("heading_deg", [0.0, 37.0, -120.0])
def test_mirror_pair_symmetric_about_the_axis(heading_deg):
    h = np.deg2rad(heading_deg)
    axis = np.array([np.sin(h), np.cos(h)])
    rx = np.array([100.0, -50.0])
    tx = rx + 150.0 * axis  # source ahead of the receiver on the array's axis (straight towing)
    geo = _still(tuple(tx), tuple(rx), heading_deg)
    c = form_contacts(_det([8.0, 13.0, 20.0], [20.0, 90.0, 150.0]), [0.0], geo, 1490.0)
    plus, minus = c.xy[c.side == 1], c.xy[c.side == -1]
    # reflection about the line through Rx along the axis: p' = rx + M (p - rx), M = 2 a a^T - I
    M = 2.0 * np.outer(axis, axis) - np.eye(2)
    np.testing.assert_allclose(rx + (plus - rx) @ M.T, minus, atol=1e-7)
    np.testing.assert_allclose(M @ c.R[c.side == 1] @ M.T, c.R[c.side == -1], rtol=1e-9, atol=1e-6)


def test_covariance_is_j_sigma_jt_at_the_measured_inputs():
    s = ContactSettings(sigma_cone_deg=1.0, endfire_limit_deg=None)
    c = form_contacts(_det(12.0, 60.0), [0.0], _still(), 1500.0, s)
    var = s.variances(np.deg2rad(1.0))
    want = bistatic_covariance(12.0, np.deg2rad(60.0), 0.0, 1500.0, np.array([0.0, 2400.0]), np.zeros(2), var)
    np.testing.assert_allclose(c.R[0], want, rtol=1e-12)
    # independent check: Monte Carlo of the noisy inputs through eq. 2 (a linearisation: agree to ~5 %)
    rng = np.random.default_rng(3)
    n = 40_000
    sd = np.sqrt(var)
    from sonartrack.models.bistatic import bistatic_position

    p, _ = bistatic_position(12.0 + sd[0] * rng.standard_normal(n), np.deg2rad(60.0) + sd[1] * rng.standard_normal(n),
                             0.0, 1500.0 + sd[3] * rng.standard_normal(n),
                             np.array([0.0, 2400.0]) + sd[4] * rng.standard_normal((n, 2)),
                             sd[6] * rng.standard_normal((n, 2)))
    np.testing.assert_allclose(np.cov(p.T), c.R[0], rtol=0.08, atol=50.0)


def test_cone_error_default_is_beam_step_or_p4_floor():
    s = ContactSettings()
    assert s.cone_sigma_rad(None) == pytest.approx(np.deg2rad(0.5))
    assert s.cone_sigma_rad(6.0) == pytest.approx(np.deg2rad(6.0 / np.sqrt(12.0)))
    assert ContactSettings(sigma_cone_deg=2.0).cone_sigma_rad(6.0) == pytest.approx(np.deg2rad(2.0))


def test_cone_error_grows_as_one_over_sine_off_broadside():
    s = ContactSettings(sigma_cone_deg=1.0, endfire_limit_deg=10.0)
    cone = np.deg2rad([90.0, 30.0, 150.0, 5.0, 178.0])
    want = np.deg2rad(1.0) / np.array([1.0, 0.5, 0.5, np.sin(np.deg2rad(10.0)), np.sin(np.deg2rad(10.0))])
    np.testing.assert_allclose(s.cone_sigmas_rad(cone, None), want, rtol=1e-12)
    # independent: a direction cosine measured with a constant error, turned into an angle (Monte Carlo)
    rng = np.random.default_rng(0)
    u = np.cos(np.deg2rad(40.0)) + np.deg2rad(1.0) * rng.standard_normal(200_000)
    assert np.std(np.arccos(u)) == pytest.approx(s.cone_sigmas_rad(np.deg2rad([40.0]), None)[0], rel=0.02)
    # the contacts carry it: at 30 deg the covariance is the constant model's with sigma / sin 30 = 2 deg
    c = form_contacts(_det(12.0, 30.0), [0.0], _still(), 1500.0, s)
    const = form_contacts(_det(12.0, 30.0), [0.0], _still(), 1500.0,
                          ContactSettings(sigma_cone_deg=2.0, endfire_limit_deg=None))
    np.testing.assert_allclose(c.R, const.R, rtol=1e-12)


def test_direct_blast_detection_is_dropped_and_counted():
    # r_B = 1500 * 1.0 = 1500 m < baseline 2400 m: no ellipse through the target
    c = form_contacts(_det([1.0, 5.6], [30.0, 30.0]), [0.0], _still(), 1500.0)
    assert len(c) == 2 and c.dropped == 2 and set(c.detection) == {1}


def test_platforms_taken_at_the_transmit_time():
    # the receiver moves north at 10 m/s; the ping at t0 = 20 s uses it at (0, 200) (stop and hop)
    t = np.array([0.0, 100.0])
    geo = ActiveGeometry(t, np.array([[0.0, 2400.0], [0.0, 3400.0]]), np.array([[0.0, 0.0], [0.0, 1000.0]]),
                         np.zeros(2))
    c = form_contacts(_det(5.6, 30.0, ping=1), [0.0, 20.0], geo, 1500.0)
    still = form_contacts(_det(5.6, 30.0), [0.0], _still(tx=(0.0, 2600.0), rx=(0.0, 200.0)), 1500.0)
    np.testing.assert_allclose(c.xy, still.xy, atol=1e-9)
    np.testing.assert_array_equal(c.time_s, [20.0, 20.0])


def test_predicted_range_rate_is_the_derivative_of_the_bistatic_range():
    rng = np.random.default_rng(0)
    xy, v = rng.uniform(-5e3, 5e3, (5, 2)), rng.normal(0, 3, (5, 2))
    tx, txv, rx, rxv = np.array([0.0, 300.0]), np.array([0.0, 2.5]), np.array([0.0, 150.0]), np.array([0.5, 2.4])
    rb = lambda s: (np.linalg.norm(xy + s * v - (tx + s * txv), axis=-1)  # noqa: E731
                    + np.linalg.norm(xy + s * v - (rx + s * rxv), axis=-1))
    rate, g = predicted_range_rate(xy, v, tx, txv, rx, rxv)
    np.testing.assert_allclose(rate, (rb(1e-3) - rb(-1e-3)) / 2e-3, rtol=1e-6, atol=1e-8)
    # gradient w.r.t. velocity: finite difference on one component
    dv = np.array([1e-3, 0.0])
    r2, _ = predicted_range_rate(xy, v + dv, tx, txv, rx, rxv)
    np.testing.assert_allclose((r2 - rate) / 1e-3, g[:, 0], rtol=1e-6)


def _contacts_at(xy, rate):
    n = len(xy)
    return Contacts(np.zeros(n, np.int64), np.zeros(n), np.arange(n), np.ones(n, np.int8), np.asarray(xy, float),
                    np.broadcast_to(np.eye(2) * 100.0**2, (n, 2, 2)).copy(), np.asarray(rate, float), np.ones(n),
                    np.ones(n))


def test_range_rate_gate():
    # a track at (0, 10 km) heading north at 3 m/s, source and receiver at the origin, still: rdot_hat = +6 m/s
    x = np.array([[0.0, 10_000.0, 0.0, 3.0]])
    P = np.diag([100.0**2, 100.0**2, 0.1**2, 0.1**2])[None]
    c = _contacts_at([[0, 10_050], [0, 10_050], [0, 10_050], [5000, 0]], [6.1, 0.0, np.nan, 0.0])
    still = (np.zeros(2), np.zeros(2))
    keep = range_rate_gate(c, 0.2, x, P, still, still)
    # consistent in gate: kept; wrong Doppler in gate: refused; no Doppler: kept; out of every gate: kept
    np.testing.assert_array_equal(keep, [True, False, True, True])
    assert range_rate_gate(c, 0.2, np.zeros((0, 4)), np.zeros((0, 4, 4)), still, still).all()


def test_resolved_track_drops_the_mirror_of_its_detections():
    from sonartrack.systems.active.contacts import resolve_mirrors

    c = form_contacts(_det([5.6, 5.6, 9.0], [36.87, 36.87, 80.0], ping=0), [0.0], _still(), 1500.0)
    # detections 0 and 1 are the same echo twice; a resolved track sits on the starboard contact (3000, 4000)
    x = np.array([[3000.0, 4000.0, 0.0, 0.0]])
    P = np.diag([200.0**2, 200.0**2, 1.0, 1.0])[None]
    keep = resolve_mirrors(c, x, P)
    dropped = c.rows(~keep)
    assert set(dropped.detection) == {0, 1} and set(dropped.side) == {-1}  # the port mirrors of the gated echo
    assert keep[c.detection == 2].all()  # an echo no resolved track gates keeps both sides
    assert resolve_mirrors(c, np.zeros((0, 4)), np.zeros((0, 4, 4))).all()
