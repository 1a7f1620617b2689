"""The CW clutter map fed the echoes the ridge notch hides (detection/cw_cells.py ``ridge_echoes``,
detection/clutter_map.py ``echo_images``, systems/active/contact_tracker.py ``ridge_map_of`` and ``_ridge_clutter``):
a world-still point hidden under the notch is learned from those echoes, and its skirt and sidelobe images elsewhere
are withheld from unconfirmed tracks; a target crossing the ridge (zero world range rate too, but moving) is not.

The worlds are built here from the geometry alone: an ownship steaming north, a still point or a crossing target,
the hidden echo's contact at the scatterer's place with the stationary sea's range rate there, rdot = -u . (v_T + v_R)
(u the unit vector from the platform to the scatterer: the Doppler of a still point), and an image contact at another
bearing, at the echo's bistatic range + 300 m and range rate + 0.4 m/s (inside the CW ambiguity's skirt)."""

import numpy as np
import pytest

from sonartrack.detection.cells import PingCells
from sonartrack.detection.clutter_map import echo_images
from sonartrack.detection.cw_cells import ridge_echoes
from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of, ridge_map_of
from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.settings import ActiveSettings

PING_S, SPEED = 30.0, 2.5  # ping interval (s), ownship speed north (m/s)
WINDOW = (1500.0, 1.56)  # c tau, 2.5 Doppler cells at 2.4 kHz, 1 s (cw_tracking.py cw_ridge_window)


def geometry(pings: int) -> ActiveGeometry:
    t = np.arange(-1.0, PING_S * pings + 2.0)
    xy = np.stack([np.zeros_like(t), SPEED * t], -1)
    return ActiveGeometry(t, xy, xy, np.zeros_like(t))


def still_rate(g: ActiveGeometry, t: float, xy) -> float:
    """Bistatic range rate of a still scatterer at ``xy`` (monostatic here): -2 u . v (module doc)."""
    d = np.asarray(xy, float) - g.rx_at(t)
    return float(-2.0 * (d / np.hypot(*d)) @ np.array([0.0, SPEED]))


def rows(ping: int, t: float, xy, rate, statistic) -> Contacts:
    """One contact per row (side +1), errors 100 m on both axes."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    return Contacts(np.full(n, ping), np.full(n, t), np.arange(n), np.ones(n, np.int8), xy,
                    np.tile(np.diag([100.0**2, 100.0**2]), (n, 1, 1)), np.asarray(rate, float).reshape(n),
                    np.hypot(*xy.T), np.asarray(statistic, float).reshape(n))


def image_of(g: ActiveGeometry, t: float, xy) -> tuple[np.ndarray, float]:
    """A contact 25 deg round from ``xy`` at its bistatic range + 300 m, range rate + 0.4 m/s."""
    rx = g.rx_at(t)
    d = np.asarray(xy, float) - rx
    r, a = np.hypot(*d) + 150.0, np.arctan2(d[1], d[0]) + np.deg2rad(25.0)
    return rx + r * np.array([np.cos(a), np.sin(a)]), still_rate(g, t, xy) + 0.4


def run(scatterer, pings: int = 24, ridge: bool = True, seed: int = 0, first_image: int = 12, image=None):
    """The tracker's verdict on the image contact at each ping from ``first_image`` on (before it, the hidden echo
    alone: a track confirmed on the images before the map learns the point keeps them, as any confirmed track keeps
    the contacts in its gate), and the tracker's ridge counts."""
    rng = np.random.default_rng(seed)
    g = geometry(pings)
    s = ActiveSettings()
    trk = ContactTracker(s.tracker_settings(), g, None, 0.18, clutter_map=clutter_map_of(s), scan_interval_s=PING_S,
                         ridge_window=WINDOW, ridge_map=ridge_map_of(s))
    kept = []
    for k in range(pings):
        t = PING_S * k
        xy = scatterer(t)
        img, img_rate = (image or image_of)(g, t, xy)
        hidden = rows(k, t, xy + rng.normal(0, 100.0, 2), still_rate(g, t, xy), 300.0)
        seen = rows(k, t, img, img_rate, 40.0).rows(slice(0, int(k >= first_image)))
        verdict = trk.step(t, seen, hidden if ridge else None)
        kept += verdict.tolist()
    return np.array(kept), trk.ridge_counts


def test_a_still_points_images_are_withheld_once_its_hidden_echo_is_shown_still():
    # 100 m errors, 30 s pings: the fit's speed bound 2.15 x 100 sqrt(12 / (n (n^2 - 1))) / 30 < 1 m/s from n ~ 10
    kept, (still, images) = run(lambda t: np.array([4000.0, 6000.0]))
    assert len(kept) == 12 and not kept.any(), kept
    assert still >= 12 and images == 12


def test_a_contact_at_the_known_point_itself_is_withheld_whatever_its_range_rate():
    # the point's own echo detected off the notch (the notch's edge), 3 m/s off its range rate: outside the echo's
    # window, inside the known point's gate
    def at_point(g, t, xy):
        return np.asarray(xy, float) + np.array([60.0, -40.0]), still_rate(g, t, xy) + 3.0

    kept, (still, marked) = run(lambda t: np.array([4000.0, 6000.0]), image=at_point)
    assert len(kept) == 12 and not kept.any() and marked == 12


def test_without_the_hidden_echoes_the_images_are_kept():
    kept, counts = run(lambda t: np.array([4000.0, 6000.0]), ridge=False)
    assert len(kept) == 12 and kept.all() and counts == [0, 0]


def test_a_target_crossing_the_ridge_keeps_its_skirt():
    # 5 m/s east, across the line of sight from the ownship (at ~x = 0): on the ridge too, but moving in the world
    kept, (still, images) = run(lambda t: np.array([4000.0 + 5.0 * t, 6000.0 + SPEED * t]))
    assert still == 0 and images == 0 and len(kept) == 12 and kept.all()


def test_echo_images_are_the_contacts_within_both_windows():
    tx = rx = np.zeros(2)
    echo = np.array([[3000.0, 4000.0]])  # r_B = 10 km
    xy = np.array([[0.0, 5000.0 + 700.0], [0.0, 5000.0 + 800.0], [5000.0, 0.0], [0.0, -5000.0]])  # r_B +1400, +1600
    rate = np.array([1.0, 1.0, 2.6, np.nan])
    assert echo_images(xy, rate, tx, rx, echo, np.array([1.0]), 1500.0, 1.5).tolist() == [True, False, False, False]
    assert not echo_images(xy, rate, tx, rx, echo[:0], np.zeros(0), 1500.0, 1.5).any()


def ping_cells(power: np.ndarray, notch: np.ndarray, keep_power: bool = True) -> PingCells:
    """Cells of one ping with unit level: s = power outside the notch, 0 in it (as cw_ping_cells sets)."""
    B, D, J = power.shape
    stat = np.where(notch[:, None, :], 0.0, power).astype(np.float32)
    return PingCells(0, 0.0, np.linspace(0.0, 180.0, B), 0.1 * np.arange(D), np.arange(J) - J // 2.0,
                     0.6 * (np.arange(J) - J // 2.0), stat, True, np.ones_like(stat),
                     None, power.astype(np.float32) if keep_power else None)


def test_ridge_echoes_are_the_peaks_under_the_notch_only():
    rng = np.random.default_rng(5)
    power = rng.exponential(1.0, (5, 40, 21))
    notch = np.zeros((5, 21), bool)
    notch[2, 9:12] = True
    power[2, 20, 10] = 200.0  # a still point under its beam's notch
    power[4, 30, 5] = 200.0  # an echo off the notch: the single-ping detector's, not the map's
    det = ridge_echoes(ping_cells(power, notch), 30.0)
    assert list(zip(det.beam, det.delay_cell, det.doppler_cell, strict=True)) == [(2, 20, 10)]
    assert det.statistic[0] == pytest.approx(200.0)
    assert ridge_echoes(ping_cells(power, notch, keep_power=False), 30.0) is None
