"""A line array's grating-lobe alias of a held echo (contact_tracker.py ``EndfireAlias``): at half-wavelength spacing
the array factor repeats in u = cos(cone) with period lambda / d = 2, so an echo near the aft endfire (u ~ -1) is heard
by the fore endfire beam (u ~ +1) at the same travel time and, in its widest beam, can come out stronger than in its
own: the clutter map's image test (weaker only) let such aliases of a tracked target start a false track (default
scene as CW, seed 1). The cases here are worked by hand from the definition (array heading north, receiver at the
origin, source 150 m ahead), and the tracker check uses detections written from the geometry, not by our simulator."""

import numpy as np

from sonartrack.detection.cells import Detections
from sonartrack.systems.active.contact_tracker import EndfireAlias, endfire_alias_of
from sonartrack.systems.active.contacts import ActiveGeometry, form_contacts

TX, RX = np.array([0.0, 150.0]), np.array([0.0, 0.0])


def at_cone(cone_deg: float, r_m: float) -> np.ndarray:
    """A point at ``r_m`` from the receiver at cone ``cone_deg`` from the array's axis (north), starboard."""
    a = np.deg2rad(cone_deg)
    return RX + r_m * np.array([np.sin(a), np.cos(a)])


def r_b(xy) -> float:
    return float(np.linalg.norm(xy - TX) + np.linalg.norm(xy - RX))


def test_the_aft_endfire_echo_aliases_to_the_fore_endfire_at_half_wavelength():
    al = EndfireAlias.of(1.0, 0.5, 16, 100.0)  # period 2, lobe 2 / 16 = 0.125 in u
    anchor = at_cone(170.0, 4000.0)  # u = cos 170 deg = -0.985: alias at u = 1.015, 0.015 from the fore endfire
    fore = at_cone(0.0, 4000.0)
    fore = RX + (fore - RX) * (r_b(anchor) - 150.0) / (r_b(fore) - 150.0)  # scaled to within ~1 m of its r_B
    side = at_cone(60.0, 4000.0)  # u = 0.5: 1.485 from the anchor, far from the period
    far = at_cone(0.0, 4400.0)  # the alias cone, but 800 m further in r_B
    xy = np.stack([anchor, fore, side, far])
    got = al.of_contacts(xy, TX, RX, 0.0, np.array([True, False, False, False]))
    assert got.tolist() == [False, True, False, False]


def test_no_alias_when_the_spacing_is_below_half_a_wavelength():
    # 32 elements 0.3 m apart at 0.625 m: period 2.083, lobe 0.065; an endfire pair differs by at most 2 in u, so
    # |2 - 2.083| = 0.083 > 0.065: the aft endfire is not heard ahead (the alias of u = -1 lies at u = 1.083)
    al = EndfireAlias.of(0.625, 0.3, 32, 100.0)
    xy = np.stack([at_cone(180.0, 4000.0), at_cone(0.0, 3700.0)])
    assert not al.of_contacts(xy, TX, RX, 0.0, np.array([True, False]))[1]


def test_the_window_is_the_pulses_delay_resolution():
    from sonartrack.acoustics.matched_filter import Waveform
    from sonartrack.systems.active.settings import ActiveSettings

    s = ActiveSettings(spacing_m=0.5, elements=16)
    cw = endfire_alias_of(s, Waveform("cw", 1.0, 1500.0))
    assert np.isclose(cw.range_m, 1500.0 / np.sqrt(12.0))  # c tau / sqrt(12)
    assert np.isclose(cw.period_u, 2.0) and np.isclose(cw.lobe_u, 2.0 / 16)
    lfm = endfire_alias_of(s, Waveform("lfm", 1.0, 1500.0, 100.0))
    assert np.isclose(lfm.range_m, max(15.0, 15.0 / np.sqrt(12.0)))  # c / (B sqrt 12) = 4.3 m: the map's 15 m
    assert endfire_alias_of(s.model_copy(update={"endfire_alias": False}), Waveform("cw", 1.0, 1500.0)) is None


C_MPS, T_PING_S, PINGS, ALIAS_FROM = 1500.0, 30.0, 24, 8


def geometry() -> ActiveGeometry:
    t = np.arange(0.0, PINGS * T_PING_S + 60.0, 10.0)
    rx = np.stack([np.zeros_like(t), 2.5 * t], -1)
    return ActiveGeometry(t, rx + [0.0, 150.0], rx, np.zeros_like(t))


def target_xy(t: float) -> np.ndarray:
    return np.array([800.0, -3000.0]) + np.array([0.0, 4.0]) * t  # behind the array, cone ~165 deg, 4 m/s north


def ping_detections(k: int, g: ActiveGeometry, rng) -> Detections:
    """The target (statistic 100) on its beam and, from ping ``ALIAS_FROM`` (the target confirmed by then), its
    alias on the fore endfire beam (statistic 150: stronger), both at its travel time with 5 ms jitter each, and 3
    uniform false alarms (the alias's row is 1 either way: a far false alarm stands in before)."""
    t = k * T_PING_S
    xy, tx, rx = target_xy(t), g.tx_at(t), g.rx_at(t)
    tt = (np.linalg.norm(xy - tx) + np.linalg.norm(xy - rx)) / C_MPS
    d = xy - rx
    cone = np.degrees(np.arccos(d[1] / np.hypot(*d)))
    cones = np.concatenate([[cone, 0.0 if k >= ALIAS_FROM else 90.0], rng.uniform(0.0, 180.0, 3)])
    tts = np.concatenate([tt + 0.005 * rng.standard_normal(2), rng.uniform(2.0, 8.0, 3)])
    if k < ALIAS_FROM:
        tts[1] = 9.0
    stat = np.array([100.0, 150.0, 20.0, 20.0, 20.0])
    n, nan = len(cones), np.full(len(cones), np.nan)
    return Detections(np.full(n, k), np.full(n, t), cones, tts, nan, nan, stat, np.round(cones / 3.0).astype(int),
                      np.zeros(n, int), np.zeros(n, int))


def alias_tracks(alias: bool) -> tuple[int, int]:
    """(confirmed tracks ever within 1 km of the alias's positions, of the target's) over the pings."""
    from sonartrack.systems.active.run import ContactTracker, clutter_map_of
    from sonartrack.systems.active.settings import ActiveSettings
    from sonartrack.tracking.tracks import TrackSnapshot

    s, g, rng = ActiveSettings(spacing_m=0.5, elements=16), geometry(), np.random.default_rng(3)
    trk = ContactTracker(s.tracker_settings(), g, s.range_rate_gate_sigma, 1.0, s.side_turn_deg, s.merge_probability,
                         s.max_range_rate_mps, turns=s.turn_modes(), clutter_map=clutter_map_of(s),
                         scan_interval_s=T_PING_S, endfire_alias=EndfireAlias.of(1.0, 0.5, 16, 15.0) if alias else None)
    on = {0: set(), 1: set()}
    for k in range(PINGS):
        con = form_contacts(ping_detections(k, g, rng), [k * T_PING_S], g, C_MPS, s.contacts, 3.0, [k])
        trk.step(k * T_PING_S, con)
        T = trk.tracker.tracks
        if not len(T) or not T.confirmed.any():
            continue
        x = TrackSnapshot.of(k * T_PING_S, T.select(T.confirmed))
        for row in (0, 1):  # the target's and the alias's mirror pairs
            if row and k < ALIAS_FROM:
                continue
            p = con.xy[con.detection == row]
            near = (np.hypot(*(x.x[:, None, :2] - p[None]).transpose(2, 0, 1)) < 1000.0).any(axis=1)
            on[row] |= set(x.track_id[near].tolist())
    return len(on[1] - on[0]), len(on[0])


def test_a_held_targets_stronger_alias_starts_no_track():
    on_alias_only, on_target = alias_tracks(True)
    assert on_alias_only == 0 and on_target >= 1


def test_without_the_alias_test_the_alias_is_confirmed():
    assert alias_tracks(False)[0] >= 1
