"""Sample inputs for the other commands, made from the passive scene (columns as arrays;
systems/simulate/files.py writes them).

* **Active bistatic contacts** (``sonartrack track --contacts``; paper P4's sonar): the ownship tows a
  transmitter ``tx_tow_length_m`` astern and the scene's array is the receiver. Every ``ping_interval_s``
  each ship echoes with probability ``pd``; false contacts are Poisson (``clutter_per_scan``) and uniform
  over the square holding every ship. Errors as P4's (models/bistatic.py ``BistaticErrors``, the
  defaults that ``track`` assumes): per ping, the transmitter and receiver positions the sonar reports
  are off by ``sigma_position_m`` per axis and the water's mean sound speed differs from the assumed c by
  ``sigma_sound_speed_mps``; per echo, travel time and bearing errors. A clutter echo is reported as the
  processor would report an echo from that point. Three tables: raw (time_s, travel_time_s,
  bearing_deg relative to the array axis, clockwise), Tx/Rx navigation, and the same contacts as
  Cartesian points with covariances J Sigma J^T (eq. 2-6).
* **Range-Doppler frames** (``sonartrack detect``; paper P1): K frames of square-law cells with one
  Swerling-1 target moving by the AR model the detector's defaults assume (sim/range_doppler.py).
* **Bearings + ownship** (``sonartrack tma``): one ship's true bearing from the array centre every
  ``tma_interval_s`` plus N(0, sigma_bearing^2), its received tonal frequency (Doppler, sim/passive_scene.py)
  plus N(0, sigma_freq^2), and the SNR that em-map models, SL - TL + DI - NL with DI = 10 log10 N (the
  tonal's, or the broadband's for a ship without one) plus N(0, sigma_snr^2); the ownship file is the
  array centre's track (the receiver).
* **Sound-speed profile** (``sonartrack tl --profile``): the scene environment's profile as a CTD cast.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.models.bistatic import BistaticErrors, bistatic_covariance, bistatic_inputs, bistatic_position
from sonartrack.models.clutter import Region, poisson_clutter
from sonartrack.models.range_doppler import CwPlaneSettings
from sonartrack.sim.passive_scene import ownship_track, place_ship, received_levels, scene_geometry, ship_motion
from sonartrack.sim.range_doppler import simulate_frames, simulate_target
from sonartrack.sim.scene import PassiveSceneSettings

#: the frames' target follows the motion model of `sonartrack detect`'s defaults (detection/mftd.py
#: MftdSettings: frame period T = 2 s, range acceleration sigma_a = 1 m/s^2)
FRAME_PERIOD_S = 2.0
FRAME_SIGMA_A_MPS2 = 1.0
#: margin of the clutter square around the ships and the ownship (m)
CLUTTER_MARGIN_M = 2_000.0


def sample_times(duration_s: float, interval_s: float) -> np.ndarray:
    """Regular sample times ``0, interval, 2 interval, ...`` up to the duration (inclusive).

    Parameters
    ----------
    duration_s : float
        Last time (s).
    interval_s : float
        Step (s).

    Returns
    -------
    ndarray
        Times (s).
    """
    return np.arange(0.0, duration_s + 1e-9, interval_s)


def _clutter_region(scene: PassiveSceneSettings, t: np.ndarray) -> Region:
    g = scene_geometry(scene, t)
    pts = np.concatenate([g.own_xy, g.ship_xy.reshape(-1, 2)])
    lo, hi = pts.min(axis=0) - CLUTTER_MARGIN_M, pts.max(axis=0) + CLUTTER_MARGIN_M
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo))
    return Region(centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half)


def _ping(rng, scene: PassiveSceneSettings, t: float, errors: BistaticErrors, region: Region) -> dict:
    """One ping's echoes (raw inputs as the sonar measured them) and the Tx/Rx navigation it reports."""
    track, s, c = ownship_track(scene), scene.samples, scene.sound_speed_mps
    tx, _ = track.towed(t, s.tx_tow_length_m)
    rx, phi = track.towed(t, scene.array.tow_length_m)
    tx_m = tx + rng.normal(0.0, errors.sigma_position_m, 2)
    rx_m = rx + rng.normal(0.0, errors.sigma_position_m, 2)
    c_water = c + rng.normal(0.0, errors.sigma_sound_speed_mps)
    ships = np.array([ship_motion(place_ship(scene, sh), np.array([t]))[0][0] for sh in scene.ships]).reshape(-1, 2)
    seen = ships[rng.random(len(ships)) < s.pd]
    tt, th = bistatic_inputs(seen, tx, rx, phi, c_water)
    tt = tt + rng.normal(0.0, errors.sigma_time_s, tt.shape)
    th = th + rng.normal(0.0, errors.sigma_bearing_rad, th.shape)
    clutter = poisson_clutter(rng, s.clutter_per_scan / region.area_m2, region)
    tc, thc = bistatic_inputs(clutter, tx_m, rx_m, phi, c)
    order = rng.permutation(len(tt) + len(tc))
    return {"travel_time_s": np.concatenate([tt, tc])[order], "theta_rad": np.concatenate([th, thc])[order],
            "tx": tx_m, "rx": rx_m, "phi": float(phi)}


def bistatic_contacts(scene: PassiveSceneSettings, rng: np.random.Generator) -> dict[str, dict[str, np.ndarray]]:
    """Column tables of the active bistatic sonar's contacts over the scene (module docstring; paper P4's sonar).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (ships, ownship, array tow, ``samples`` settings).
    rng : numpy.random.Generator
        Random stream.

    Returns
    -------
    dict
        ``"raw"``: time_s, travel_time_s (s), bearing_deg (relative to the array axis, clockwise);
        ``"nav"``: per ping time_s, tx_x_m, tx_y_m, rx_x_m, rx_y_m, array_heading_deg (0..360 clockwise
        from north); ``"cartesian"``: time_s, x_m, y_m, var_x_m2, var_y_m2, cov_xy_m2 (contacts whose
        receiver range is positive).
    """
    errors = BistaticErrors()
    t_ping = sample_times(scene.duration_s, scene.samples.ping_interval_s)
    region = _clutter_region(scene, t_ping)
    pings = [_ping(rng, scene, float(t), errors, region) for t in t_ping]
    n = np.array([p["travel_time_s"].size for p in pings])
    t = np.repeat(t_ping, n)
    tt = np.concatenate([p["travel_time_s"] for p in pings])
    th = wrap_angle(np.concatenate([p["theta_rad"] for p in pings]))
    tx, rx = (np.repeat(np.array([p[k] for p in pings]).reshape(-1, 2), n, axis=0) for k in ("tx", "rx"))
    phi = np.repeat([p["phi"] for p in pings], n)
    c = np.full(t.size, scene.sound_speed_mps)
    z, rr = bistatic_position(tt, th, phi, c, tx, rx)
    R = bistatic_covariance(tt, th, phi, c, tx, rx, errors.variances())
    keep = rr > 0
    nav = {"time_s": t_ping, "tx_x_m": np.array([p["tx"][0] for p in pings]),
           "tx_y_m": np.array([p["tx"][1] for p in pings]), "rx_x_m": np.array([p["rx"][0] for p in pings]),
           "rx_y_m": np.array([p["rx"][1] for p in pings]),
           "array_heading_deg": np.rad2deg([p["phi"] for p in pings]) % 360.0}
    raw = {"time_s": t, "travel_time_s": tt, "bearing_deg": np.rad2deg(th)}
    cartesian = {"time_s": t[keep], "x_m": z[keep, 0], "y_m": z[keep, 1], "var_x_m2": R[keep, 0, 0],
                 "var_y_m2": R[keep, 1, 1], "cov_xy_m2": R[keep, 0, 1]}
    return {"raw": raw, "nav": nav, "cartesian": cartesian}


def range_doppler_frames(scene: PassiveSceneSettings, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Square-law frames with one Swerling-1 target on the default CW plane of ``sonartrack detect`` (paper P1).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (``samples``: frames, plane size, target SNR in dB).
    rng : numpy.random.Generator
        Random stream.

    Returns
    -------
    frames : ndarray, shape (K, Nr, Nd)
        Cell values (noise mean 2).
    cells : ndarray of int, shape (K, 2)
        The target's [range index, Doppler index] per frame.
    """
    s = scene.samples
    grid = CwPlaneSettings().grid(s.frame_range_cells, s.frame_doppler_cells)
    target = simulate_target(rng, grid, FRAME_PERIOD_S, FRAME_SIGMA_A_MPS2, s.frames)
    return simulate_frames(rng, grid, s.frames, 10.0 ** (s.frame_snr_db / 10.0), target.cells), target.cells


def tma_record(scene: PassiveSceneSettings, rng: np.random.Generator, store=None) -> tuple[dict, dict]:
    """Bearings (+ frequency, SNR) of the TMA ship and the receiver's track (module docstring).

    Parameters
    ----------
    scene, rng : PassiveSceneSettings, numpy.random.Generator
        The scene and the random stream of the record's noise.
    store : optional
        Cache of RAM fields (sim/passive_scene.py).

    Returns
    -------
    bearings : dict of str to ndarray
        time_s, bearing_deg (0..360, clockwise from north, from the array centre), frequency_hz (if the ship
        has a tonal) and snr_db; empty columns for a scene without ships.
    ownship : dict of str to ndarray
        time_s, x_m, y_m of the array centre.
    """
    name = scene.tma_ship_name()
    t = sample_times(scene.duration_s, scene.samples.tma_interval_s)
    if name is None:
        return {"time_s": np.zeros(0), "bearing_deg": np.zeros(0)}, {"time_s": np.zeros(0), "x_m": np.zeros(0),
                                                                      "y_m": np.zeros(0)}
    i = [sh.name for sh in scene.ships].index(name)
    g = scene_geometry(scene, t)
    lv = received_levels(scene, g, store)
    s = scene.samples
    di = 10.0 * np.log10(scene.array.elements)
    has_tonal = scene.ships[i].tonal_hz is not None
    level = lv.tonal_db[i] if has_tonal else lv.broadband_db[i]
    bearing = np.rad2deg(g.bearing_rad[i]) + rng.normal(0.0, s.sigma_bearing_deg, t.size)
    bearings = {"time_s": t, "bearing_deg": bearing % 360.0}
    if has_tonal:
        bearings["frequency_hz"] = lv.tonal_hz[i] + rng.normal(0.0, s.sigma_freq_hz, t.size)
    bearings["snr_db"] = level - scene.noise_level_db + di + rng.normal(0.0, s.sigma_snr_db, t.size)
    return bearings, {"time_s": t, "x_m": g.array_xy[:, 0], "y_m": g.array_xy[:, 1]}


def ctd_profile(scene: PassiveSceneSettings) -> dict[str, np.ndarray]:
    """The sound-speed profile of the ``scene``'s ``environment`` as a CTD cast, down to the water depth.

    Returns
    -------
    dict of str to ndarray
        ``depth_m`` (m) and ``sound_speed_mps`` (m/s).
    """
    from sonartrack.acoustics.environment import load_environment

    env = load_environment(scene.environment)
    z, c = np.asarray(env.depth_m, float), np.asarray(env.sound_speed_mps, float)
    if z[-1] < env.water_depth_m:  # the cast reaches the bottom: the last speed holds below the last sample
        z, c = np.append(z, env.water_depth_m), np.append(c, c[-1])
    return {"depth_m": z, "sound_speed_mps": c}
