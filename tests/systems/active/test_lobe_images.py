"""A still clutter point's grating-lobe image (clutter_map.py ``same_range``): a line array at half a wavelength
steered to one endfire hears the other endfire at nearly full gain, so a strong still point behind the array gives,
ping after ping, a weaker detection at the same travel time on the beam ahead; that image moves with the platform,
not with the world, and the world-frame clutter map cannot call it still.

The detections are written here from the geometry (a ship running north, source towed 150 m ahead of the array, a
point of statistic 150 at cone ~166 deg and its image of statistic 45 at cone 0, both at the point's bistatic travel
time with a 5 ms jitter, and a few uniform false alarms), not by the chain's simulator: measured on the independent
generator's K 1 world (benchmarks/bench_active_defaults.py) 14 of 36 false confirmed tracks in 2 h were such
images. The chain's tracker stage with its defaults confirms no track on the image; with the images not withheld
(``image_range_m`` None, the map of before) it does, which shows the world is hard enough to tell."""

import numpy as np

from sonartrack.detection.cells import Detections
from sonartrack.systems.active.contacts import ActiveGeometry, form_contacts

C_MPS, T_PING_S, PINGS, SPEED_MPS = 1500.0, 30.0, 16, 2.5
POINT_XY = np.array([1000.0, -4000.0])


def geometry() -> ActiveGeometry:
    t = np.arange(0.0, PINGS * T_PING_S + 60.0, 10.0)
    rx = np.stack([np.zeros_like(t), SPEED_MPS * t], -1)
    return ActiveGeometry(t, rx + [0.0, 150.0], rx, np.zeros_like(t))


def ping_detections(k: int, g: ActiveGeometry, rng) -> Detections:
    t = k * T_PING_S
    tx, rx = g.tx_at(t), g.rx_at(t)
    tt = (np.linalg.norm(POINT_XY - tx) + np.linalg.norm(POINT_XY - rx)) / C_MPS + 0.005 * rng.standard_normal()
    d = POINT_XY - rx
    cone = np.degrees(np.arccos(d[1] / np.hypot(*d)))
    n_false = 3
    cones = np.concatenate([[3.0 * np.round(cone / 3.0), 0.0], rng.uniform(0.0, 180.0, n_false)])
    tts = np.concatenate([[tt, tt], rng.uniform(2.0, 8.0, n_false)])
    stat = np.concatenate([[150.0, 45.0], np.full(n_false, 20.0)])
    n = len(cones)
    nan = np.full(n, np.nan)
    return Detections(np.full(n, k), np.full(n, t), cones, tts, nan, nan, stat, np.round(cones / 3.0).astype(int),
                      np.zeros(n, int), np.zeros(n, int))


def image_tracks(image_range_m) -> int:
    """Confirmed tracks within 1 km of the image's positions (either mirror) over the pings."""
    from sonartrack.systems.active.run import ContactTracker, clutter_map_of
    from sonartrack.systems.active.settings import ActiveSettings
    from sonartrack.tracking.tracks import TrackSnapshot

    s, g, rng = ActiveSettings(spacing_m=0.5), geometry(), np.random.default_rng(5)
    cmap = clutter_map_of(s)
    cmap.image_range_m = image_range_m
    trk = ContactTracker(s.tracker_settings(), g, s.range_rate_gate_sigma, 1.0, s.side_turn_deg, s.merge_probability,
                         s.max_range_rate_mps, turns=s.turn_modes(), clutter_area_m2=None, clutter_map=cmap,
                         scan_interval_s=T_PING_S)
    on_image = set()
    for k in range(PINGS):
        det = ping_detections(k, g, rng)
        con = form_contacts(det, [k * T_PING_S], g, C_MPS, s.contacts, 3.0, [k])
        trk.step(k * T_PING_S, con)
        snap = trk.tracker.tracks
        if not len(snap) or not snap.confirmed.any():
            continue
        img = con.xy[con.detection == 1]  # the image's mirror pair (detection row 1 of each ping)
        x = TrackSnapshot.of(k * T_PING_S, snap.select(snap.confirmed))
        near = (np.hypot(*(x.x[:, None, :2] - img[None]).transpose(2, 0, 1)) < 1000.0).any(axis=1)
        on_image |= set(x.track_id[near].tolist())
    return len(on_image)


def test_no_track_is_confirmed_on_a_still_points_lobe_image():
    assert image_tracks(15.0) == 0


def test_without_the_image_test_the_image_is_confirmed():
    assert image_tracks(None) >= 1
