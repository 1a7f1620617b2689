"""A slow track newly confirmed in the skirt of a recurring hidden CW ridge echo waits for its speed
(systems/active/contact_tracker.py ``_ridge_places``, ``skirt_covariance``; tracking/deleters.py ``StillHold``).

The worlds are built here from the geometry alone (as tests/systems/active/test_cw_ridge_map.py's): an ownship
steaming north at 2.5 m/s, pinging every 30 s; a scatterer whose echo hides under its beam's ridge notch on every
other ping only (an intermittent hidden echo: 4 hits of 8 by ping 8, its place recurring, but with 250 m errors not
yet shown still), and contacts on its delay-Doppler skirt 600 m further down the line of sight (r_B + 1200 m)."""

import numpy as np
import pytest

from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of, ridge_map_of
from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.ridge_skirt import skirt_covariance, skirt_density
from sonartrack.systems.active.settings import ActiveSettings

PING_S, SPEED = 30.0, 2.5
WINDOW = (1500.0, 1.56)  # c tau, 2.5 Doppler cells at 2.4 kHz, 1 s (cw_tracking.py cw_ridge_window)
AREA_M2 = 1.6e9  # a CW's listening disc: the tracker's clutter density is its contacts' mean over it (CWCONF)


def geometry(pings: int) -> ActiveGeometry:
    t = np.arange(-1.0, PING_S * pings + 2.0)
    xy = np.stack([np.zeros_like(t), SPEED * t], -1)
    return ActiveGeometry(t, xy, xy, np.zeros_like(t))


def rows(ping: int, t: float, xy, rate_mps: float, sd_m: float, statistic: float) -> Contacts:
    """One contact (side +1), ``sd_m`` on both axes."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    return Contacts(np.full(n, ping), np.full(n, t), np.arange(n), np.ones(n, np.int8), xy,
                    np.tile(np.diag([sd_m**2, sd_m**2]), (n, 1, 1)), np.full(n, rate_mps), np.hypot(*xy.T),
                    np.full(n, statistic))


def run(scatterer, skirt_pings, pings: int = 24, ridge: bool = True, seed: int = 3):
    """The tracker on the world; returns (ids of the confirmed tracks, the ridge map's still count). Range rates:
    the scatterer's own, rdot = 2 u . (v - v_own) (monostatic, u the unit vector to it), on the hidden echo; that
    plus 1.2 m/s (two Doppler cells) on the skirt."""
    rng = np.random.default_rng(seed)
    g = geometry(pings)
    s = ActiveSettings()
    trk = ContactTracker(s.tracker_settings(), g, None, 0.18, max_range_rate_mps=s.max_range_rate_mps,
                         clutter_map=clutter_map_of(s), scan_interval_s=PING_S, clutter_area_m2=AREA_M2,
                         ridge_window=WINDOW, ridge_map=ridge_map_of(s))
    for k in range(pings):
        t = PING_S * k
        xy = scatterer(t)
        u = (xy - g.rx_at(t)) / np.hypot(*(xy - g.rx_at(t)))
        rate = float(2.0 * u @ ((scatterer(t + 1.0) - xy) - np.array([0.0, SPEED])))
        hidden = rows(k, t, xy + rng.normal(0, 250.0, 2), rate, 250.0, 300.0).rows(slice(0, int(k % 2 == 0)))
        seen = rows(k, t, xy + 600.0 * u + rng.normal(0, 60.0, 2), rate + 1.2, 100.0, 40.0).rows(
            slice(0, int(k in skirt_pings)))
        trk.step(t, seen, hidden if ridge else None)
    tr = trk.result().tracks
    return set(tr.track_id[tr.confirmed].tolist()), trk.ridge_counts[0]


def still_point(t):
    return np.array([4000.0, 6000.0])


def test_a_pair_of_skirt_contacts_of_a_recurring_hidden_echo_confirms_no_track():
    confirmed, shown_still = run(still_point, {9, 10})
    assert confirmed == set() and shown_still == 0  # held by the recurrence, not the map's stillness verdict


def test_without_the_hidden_echoes_the_same_pair_confirms_a_track():
    confirmed, _ = run(still_point, {9, 10}, ridge=False)
    assert len(confirmed) == 1


def test_a_target_crossing_the_ridge_is_confirmed_on_its_skirt():
    # 5 m/s east across the line of sight: its echo under the notch recurs too (150 m a ping in 250 m errors), its
    # skirt gives a contact every ping; its speed shows it moving, so the hold lets its track stand
    def crossing(t):
        return np.array([4000.0 + 5.0 * t, 6000.0 + SPEED * t])

    confirmed, shown_still = run(crossing, set(range(4, 24)))
    assert shown_still == 0 and len(confirmed) == 1


def test_skirt_covariance_widens_along_the_gradient_of_the_bistatic_range():
    # monostatic at the origin, echo due east: grad r_B = 2 x (1, 0), so +-1500 m of r_B is +-750 m east:
    # variance 750^2 / 3 added on x only
    R = np.array([[[100.0, 0.0], [0.0, 400.0]]])
    wide = skirt_covariance(np.array([[5000.0, 0.0]]), R, np.zeros(2), np.zeros(2), 1500.0)
    assert wide[0] == pytest.approx(np.array([[100.0 + 750.0**2 / 3.0, 0.0], [0.0, 400.0]]))
    # bistatic, echo on the perpendicular bisector of a 2 km baseline at 1 km: u_T + u_R = (0, 2 / sqrt(2))
    wide = skirt_covariance(np.array([[0.0, 1000.0]]), np.zeros((1, 2, 2)), [-1000.0, 0.0], [1000.0, 0.0], 1500.0)
    assert wide[0] == pytest.approx(np.array([[0.0, 0.0], [0.0, (1500.0 / np.sqrt(2.0)) ** 2 / 3.0]]), abs=1e-6)


def test_skirt_density_is_one_contact_over_the_gate_area_inside_the_gate_only():
    # R_j + R_place = diag(300^2, 400^2): the gate d^2 <= gamma is an ellipse of area pi gamma 300 x 400
    gamma, lam = 9.21, 1e-9
    place, Rp = np.array([[0.0, 0.0]]), np.array([np.diag([200.0**2, 300.0**2])])
    xy = np.array([[100.0, -200.0], [0.0, 1500.0]])  # d^2 = 100^2/300^2 + 200^2/400^2 = 0.36; 1500^2/400^2 = 14
    Rc = np.tile(np.diag([np.sqrt(300.0**2 - 200.0**2) ** 2, np.sqrt(400.0**2 - 300.0**2) ** 2]), (2, 1, 1))
    rho = skirt_density(xy, Rc, place, Rp, lam, gamma)
    assert rho == pytest.approx([1.0 / (np.pi * gamma * 300.0 * 400.0), lam])
    assert skirt_density(xy[1:], Rc[1:], place, Rp, lam, gamma) is None  # none raised
    assert skirt_density(xy, Rc, place[:0], Rp[:0], lam, gamma) is None  # no place
