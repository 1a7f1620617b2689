"""A still clutter point's grating image (contact_tracker.py ``EndfireAlias.clutter_range_m``, ContactTracker
``_not_clutter``): at 0.75 wavelength spacing the array factor repeats in u = cos(cone) with period lambda / d = 4/3,
so a still point at cone 60 deg (u = 0.5) is also heard at u = -0.833 (cone 146 deg) at its travel time, give or take
the image's own delay resolution c / B_i (the image passes only the band where it lies in the beam's main lobe,
B_i = min(B, f_0 / N)). The image moves in the world as the array moves, so the clutter map never shows it still.
Measured on study active-chain trial 18 (48 x 0.75 m, LFM 50 Hz at 1.5 kHz): the image's r_B 1-32 m off the point's
contact, a mirror pair confirmed on it. The worlds here are written from the geometry (array heading north at 2.5 m/s,
receiver at the origin at t = 0, source 150 m ahead), not by our simulator: each ping's detections are the point, its
image 13 ms late (19.5 m in r_B, outside the old 15 m window, inside c / B_i = 48 m), a crossing target at 2 m/s and
its own image, and 3 uniform false alarms."""

import numpy as np

from sonartrack.acoustics.matched_filter import Waveform
from sonartrack.detection.cells import Detections
from sonartrack.systems.active.contact_tracker import endfire_alias_of
from sonartrack.systems.active.contacts import ActiveGeometry, form_contacts
from sonartrack.systems.active.settings import ActiveSettings

C_MPS, T_PING_S, PINGS, IMAGE_FROM, PERIOD_U = 1500.0, 30.0, 44, 24, 4.0 / 3.0
TARGET_MPS = 3.0
POINT = 10000.0 * np.array([np.sin(np.deg2rad(20.0)), np.cos(np.deg2rad(20.0))])  # cone 20 deg at t = 0


def settings() -> ActiveSettings:
    return ActiveSettings(spacing_m=0.75, elements=48)


def geometry() -> ActiveGeometry:
    t = np.arange(0.0, PINGS * T_PING_S + 60.0, 10.0)
    rx = np.stack([np.zeros_like(t), 2.5 * t], -1)
    return ActiveGeometry(t, rx + [0.0, 150.0], rx, np.zeros_like(t))


def target_xy(t: float) -> np.ndarray:
    """A target crossing the point's place at ``TARGET_MPS`` east (there at ping 30)."""
    return POINT + np.array([TARGET_MPS * (t - 30 * T_PING_S), 0.0])


def echo(xy, g: ActiveGeometry, t: float) -> tuple[float, float]:
    """(cone deg, travel time s) of a point at ``xy``: the array's axis is north."""
    tx, rx = g.tx_at(t), g.rx_at(t)
    d = xy - rx
    return float(np.degrees(np.arccos(d[1] / np.hypot(*d)))), float((np.hypot(*(xy - tx)) + np.hypot(*d)) / C_MPS)


def image_cone(cone_deg: float) -> float:
    """The grating image's cone: u - lambda / d (u > 0 here), or NaN when it falls off the visible [-1, 1]."""
    u = np.cos(np.deg2rad(cone_deg)) - PERIOD_U
    return float(np.degrees(np.arccos(u))) if u >= -1.0 else np.nan


def ping_detections(k: int, g: ActiveGeometry, rng, target: bool, point_image: bool) -> Detections:
    """Rows: 0 the point (statistic 400), 1 its image (200, from ping ``IMAGE_FROM``: the map knows the point by
    then), 2 the target (200) and 3 its image (120) when ``target``, then 3 false alarms (20)."""
    t = k * T_PING_S
    rows = [(*echo(POINT, g, t), 400.0, 0.0)]
    if point_image and k >= IMAGE_FROM:
        c, tt = echo(POINT, g, t)
        rows.append((image_cone(c), tt, 200.0, 0.013))
    if target:
        c, tt = echo(target_xy(t), g, t)
        rows += [(c, tt, 200.0, 0.0), (image_cone(c), tt, 120.0, 0.013)]
    rows = [r for r in rows if np.isfinite(r[0])]
    cones = np.array([r[0] for r in rows] + list(rng.uniform(0.0, 180.0, 3)))
    tts = np.array([r[1] + r[3] for r in rows] + list(rng.uniform(2.0, 8.0, 3)))
    cones[:len(rows)] += 0.3 * rng.standard_normal(len(rows))
    tts[:len(rows)] += 0.002 * rng.standard_normal(len(rows))
    stat = np.array([r[2] for r in rows] + [20.0] * 3)
    n, nan = len(cones), np.full(len(cones), np.nan)
    return Detections(np.full(n, k), np.full(n, t), cones, tts, nan, nan, stat, np.round(cones / 3.0).astype(int),
                      np.zeros(n, int), np.zeros(n, int))


def run(window_m: float | None, target: bool, point_image: bool = True, seed: int = 5) -> dict:
    """Confirmed track ids near the point's image and near the target per ping (1 km), the alias test's clutter
    window ``window_m`` (None: the chain's, endfire_alias_of)."""
    from dataclasses import replace

    from sonartrack.systems.active.contact_tracker import ContactTracker, clutter_map_of
    from sonartrack.tracking.tracks import TrackSnapshot

    s, g, rng = settings(), geometry(), np.random.default_rng(seed)
    al = endfire_alias_of(s, Waveform("lfm", 1.0, 1500.0, 50.0))
    if window_m is not None:
        al = replace(al, clutter_range_m=window_m)
    trk = ContactTracker(s.tracker_settings(), g, s.range_rate_gate_sigma, 1.0, s.side_turn_deg, s.merge_probability,
                         s.max_range_rate_mps, turns=s.turn_modes(), clutter_map=clutter_map_of(s),
                         scan_interval_s=T_PING_S, endfire_alias=al)
    out = {"image": set(), "target_pings": 0}
    for k in range(PINGS):
        t = k * T_PING_S
        det = ping_detections(k, g, rng, target, point_image)
        trk.step(t, form_contacts(det, [t], g, C_MPS, s.contacts, 3.0, [k]))
        T = trk.tracker.tracks
        if not len(T) or not T.confirmed.any():
            continue
        x = TrackSnapshot.of(t, T.select(T.confirmed))
        c, tt = echo(POINT, g, t)
        ic = np.deg2rad(image_cone(c))
        r = 0.5 * C_MPS * tt
        img = np.array([[r * np.sin(ic), r * np.cos(ic)], [-r * np.sin(ic), r * np.cos(ic)]]) + g.rx_at(t)
        near_img = (np.hypot(*(x.x[:, None, :2] - img[None]).transpose(2, 0, 1)) < 1000.0).any(axis=1)
        if k >= IMAGE_FROM and point_image:
            out["image"] |= set(x.track_id[near_img].tolist())
        if target:
            out["target_pings"] += int((np.hypot(*(x.x[:, :2] - target_xy(t)).T) < 1000.0).any())
    return out


def test_the_clutter_window_is_the_grating_images_delay_resolution():
    al = endfire_alias_of(settings(), Waveform("lfm", 1.0, 1500.0, 50.0))
    assert np.isclose(al.range_m, 15.0)  # c / (B sqrt 12) = 8.7 m: the map's 15 m
    assert np.isclose(al.clutter_range_m, 1500.0 / (1500.0 / 48))  # B_i = f_0 / N = 31.25 Hz < B: 48 m
    wide = endfire_alias_of(settings().model_copy(update={"elements": 8}), Waveform("lfm", 1.0, 1500.0, 50.0))
    assert np.isclose(wide.clutter_range_m, 30.0)  # f_0 / N = 187.5 Hz > B: the pulse's own c / B


def test_a_still_points_grating_image_starts_no_track():
    assert run(None, target=False)["image"] == set()


def test_with_the_pulses_window_the_image_is_confirmed():
    assert len(run(15.0, target=False)["image"]) >= 1  # trial 18's defect: the image 19.5 m off in r_B


def test_a_target_crossing_the_point_with_its_own_image_is_held():
    # 3 m/s: its contacts and its image's recur ping to ping (the map's recurrence gate) but are never shown still,
    # so neither anchors the test: it is held on as many pings as with the test off (window 0 m), while it crosses
    # the still point and the point's image is withheld
    held = run(None, target=True)["target_pings"]
    assert held == run(0.0, target=True)["target_pings"] and held >= 15
