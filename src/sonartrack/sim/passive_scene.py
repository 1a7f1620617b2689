"""Geometry and received levels of a passive towed-array scene (settings: sim/scene.py).

Platforms (x east, y north; bearings clockwise from north):

* the ownship is a :class:`~sonartrack.sim.platforms.ManeuveringTrack` (a straight leg, one turn, a
  straight leg; or a zig-zag of turns alternating in direction), or with ``ownship.legs`` a
  :class:`~sonartrack.sim.platforms.LegTrack` (legs of their own course and speed, turns at the ownship's rate);
  the array centre is towed ``tow_length_m`` behind it along its own track, so it sits where the ship was
  ``tow_length_m`` of path earlier (L / v seconds at a constant speed) and its axis heading is the ship's heading
  then (the array heading lags the ship's through the turn);
* each ship moves at constant velocity, or on ``legs`` of constant velocity joined by instantaneous changes, from
  its position at t = 0 (given, or from its place relative to the array at a time: :func:`place_ship`).

Seen from the array centre (what the array measures; the ship itself is ``tow_length_m`` ahead):

    range r = |p_ship - p_array|,  true bearing b = atan2(dx, dy),
    cone angle theta = arccos(u_axis . (p_ship - p_array) / r)   (0 = ahead along the array axis,
                                                                  180 = astern; b = heading +- theta)
    range rate rdot = (p_ship - p_array) . (v_ship - v_array) / r

Received levels (passive sonar equation, per element; Urick, Principles of Underwater Sound, ch. 2):

    broadband spectral level  RL_bb = SL_bb - TL(r, f_bb)       (dB re 1 uPa^2/Hz; f_bb = the band's
                                                                 geometric centre)
    tonal power               RL_t  = SL_t - TL(r, f_t)          (dB re 1 uPa^2)
    received tonal frequency  f_r   = f_t (1 - rdot / c)         (models/passive.py, paper P2 eq. 3)
    per-element SNRs          snr_db = RL_bb - NL (in the band), tonal_snr_db = RL_t - NL (in 1 Hz);
                              a beam of N elements adds 10 log10 N to both.

TL is ``spherical`` (20 log10 r + Thorp absorption, acoustics/transmission_loss.py) or ``ram`` (RAM in
the scene's environment, source at the ship's depth, receiver at the array's depth, incoherently
averaged over ``tl_average_m``; fields come from ``store``, e.g. io/environment.py's disk cache).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.platforms import LegTrack, ManeuveringTrack
from sonartrack.sim.scene import PassiveSceneSettings, ShipSettings, course_change_deg, leg_starts_s

#: RAM fields are computed out to a whole number of these (m), so that scenes of different lengths
#: share cached fields
RAM_RANGE_STEP_M = 10_000.0


@dataclass(frozen=True, slots=True)
class SceneGeometry:
    """Platforms at times ``time_s`` (T,); ship quantities are (S, T) (S ships), seen from the array centre."""

    time_s: np.ndarray
    own_xy: np.ndarray  # (T, 2)
    own_heading_rad: np.ndarray  # (T,)
    array_xy: np.ndarray  # (T, 2)
    array_heading_rad: np.ndarray  # (T,)
    ship_xy: np.ndarray  # (S, T, 2)
    ship_velocity: np.ndarray  # (S, T, 2)
    range_m: np.ndarray
    bearing_rad: np.ndarray  # (-pi, pi]
    cone_rad: np.ndarray  # 0..pi from the array axis (ahead)
    range_rate_mps: np.ndarray


@dataclass(frozen=True, slots=True)
class ReceivedLevels:
    """Per ship and time (S, T): broadband spectral level and tonal power at an element, received tonal frequency
    (NaN for a ship without a tonal)."""

    broadband_db: np.ndarray
    tonal_db: np.ndarray
    tonal_hz: np.ndarray


def ownship_track(scene: PassiveSceneSettings) -> ManeuveringTrack | LegTrack:
    """The ownship's track: a straight leg, its turn (if any) starting at ``scene.turn_start_s``, a straight leg;
    or its legs (:func:`own_leg_track`).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (ownship start in m, speed in kn, course and turn in deg, clockwise from north).

    Returns
    -------
    ManeuveringTrack or LegTrack
        The track in SI units (m, m/s, rad).
    """
    o = scene.ownship
    if o.legs is not None:
        return own_leg_track(o)
    turns = ()
    if o.turn_deg != 0:
        t0 = scene.turn_start_s
        rate = np.sign(o.turn_deg) * np.deg2rad(o.turn_rate_deg_s)
        turn_s = abs(o.turn_deg) / o.turn_rate_deg_s
        # a zig-zag: the turns alternate in direction, so the legs alternate between two courses
        turns = tuple((t0 + k * o.leg_s, t0 + k * o.leg_s + turn_s, float(rate) * (-1.0) ** k)
                      for k in range(o.zigzag_turns))
    return ManeuveringTrack(o.x_m, o.y_m, o.speed_kn * KNOT_MPS, float(np.deg2rad(o.course_deg)), turns)


def own_leg_track(own) -> LegTrack:
    """The ownship on its legs: each leg from its start, the course change into it a turn the shorter way at
    ``turn_rate_deg_s`` from the leg's start, the speed change at once.

    Parameters
    ----------
    own : OwnshipSettings
        The ownship (start position in m, legs in s, deg, kn; turn rate in deg/s).

    Returns
    -------
    LegTrack
        Its segments in SI units (s, m/s, rad, rad/s), from t = 0.
    """
    rate = np.deg2rad(own.turn_rate_deg_s)
    segments = []
    for k, (start, leg) in enumerate(zip(leg_starts_s(own.legs), own.legs, strict=True)):
        v, course = leg.speed_kn * KNOT_MPS, float(np.deg2rad(leg.course_deg))
        turn = course_change_deg(own.legs[k - 1].course_deg, leg.course_deg) if k else 0.0
        if turn != 0.0:
            previous = float(np.deg2rad(own.legs[k - 1].course_deg))
            segments.append((start, v, previous, float(np.sign(turn) * rate)))
            start += abs(turn) / own.turn_rate_deg_s
        segments.append((start, v, course, 0.0))
    return LegTrack(own.x_m, own.y_m, tuple(segments))


def ship_leg_track(ship: ShipSettings, x0_m: float, y0_m: float) -> LegTrack:
    """A ship on its legs from (``x0_m``, ``y0_m``) at t = 0: constant velocity on each, changed at once between.

    Parameters
    ----------
    ship : ShipSettings
        The ship (legs in s, deg, kn).
    x0_m, y0_m : float
        Its position at t = 0 (m).

    Returns
    -------
    LegTrack
        Its segments in SI units (s, m/s, rad; no turn segments).
    """
    return LegTrack(x0_m, y0_m, tuple((start, leg.speed_kn * KNOT_MPS, float(np.deg2rad(leg.course_deg)), 0.0)
                                      for start, leg in zip(leg_starts_s(ship.legs), ship.legs, strict=True)))


def array_state(track: ManeuveringTrack | LegTrack, t_s, tow_length_m: float):
    """Position (T, 2), velocity (T, 2) and axis heading (T,) of the array centre towed ``tow_length_m`` behind.

    Parameters
    ----------
    track : ManeuveringTrack or LegTrack
        The ownship's track.
    t_s : ndarray, shape (T,)
        Times (s).
    tow_length_m : float
        Tow length (m).

    Returns
    -------
    tuple of ndarray
        Position (m), velocity (m/s), heading (rad, not wrapped).
    """
    if isinstance(track, LegTrack):
        return track.towed_state(t_s, tow_length_m)
    return track.state(t_s - tow_length_m / track.speed_mps)


def place_ship(scene: PassiveSceneSettings, ship: ShipSettings) -> ShipSettings:
    """A ship placed relative to the array as the same ship with its position at t = 0 (x_m, y_m).

    At ``at_time_s`` = t_c the ship is at range r = ``at_range_m`` and relative bearing beta =
    ``at_relative_bearing_deg`` (clockwise from the array's axis heading h) from the array centre::

        p(t_c) = p_array(t_c) + r [sin(h + beta), cos(h + beta)],   p(0) = p(t_c) - v t_c

    with v the ship's constant velocity (course, speed); a ship on legs goes back from p(t_c) along its legs.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (ownship, array's tow length).
    ship : ShipSettings
        The ship; returned unchanged when given by x_m, y_m.

    Returns
    -------
    ShipSettings
        The ship with ``x_m``, ``y_m`` (m) set and the placement fields cleared.
    """
    if not ship.placed:
        return ship
    xy, _, h = array_state(ownship_track(scene), np.array([ship.at_time_s]), scene.array.tow_length_m)
    a = float(h[0]) + np.deg2rad(ship.at_relative_bearing_deg)
    if ship.legs is not None:
        p0 = xy[0] + ship.at_range_m * np.array([np.sin(a), np.cos(a)])
        p0 = p0 - ship_leg_track(ship, 0.0, 0.0).state(np.array([ship.at_time_s]))[0][0]
        return ship.model_copy(update={"x_m": float(p0[0]), "y_m": float(p0[1]), "at_time_s": None,
                                       "at_range_m": None, "at_relative_bearing_deg": None})
    course = np.deg2rad(ship.course_deg)
    v = ship.speed_kn * KNOT_MPS * np.array([np.sin(course), np.cos(course)])
    p0 = xy[0] + ship.at_range_m * np.array([np.sin(a), np.cos(a)]) - v * ship.at_time_s
    return ship.model_copy(update={"x_m": float(p0[0]), "y_m": float(p0[1]), "at_time_s": None, "at_range_m": None,
                                   "at_relative_bearing_deg": None})


def ship_motion(ship: ShipSettings, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities of a ship at times ``t_s`` (at constant velocity, or on its legs).

    Parameters
    ----------
    ship : ShipSettings
        The ship (position at t = 0 in m, course in deg clockwise from north, speed in kn); a ship placed
        relative to the array goes through :func:`place_ship` first.
    t_s : array_like, shape (T,)
        Times (s).

    Returns
    -------
    position : ndarray, shape (T, 2)
        [x east, y north] (m).
    velocity : ndarray, shape (T, 2)
        [vx, vy] (m/s).
    """
    if ship.legs is not None:
        xy, v, _ = ship_leg_track(ship, ship.x_m, ship.y_m).state(np.asarray(t_s, dtype=float))
        return xy, v
    course = np.deg2rad(ship.course_deg)
    v = ship.speed_kn * KNOT_MPS * np.array([np.sin(course), np.cos(course)])
    t = np.asarray(t_s, dtype=float)
    return np.array([ship.x_m, ship.y_m]) + t[:, None] * v, np.broadcast_to(v, (t.size, 2)).copy()


def scene_geometry(scene: PassiveSceneSettings, t_s) -> SceneGeometry:
    """Every platform at times ``t_s`` and each ship's range, bearing, cone angle and range rate from the array centre.

    Equations in the module docstring.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    t_s : float or array_like, shape (T,)
        Times (s).

    Returns
    -------
    SceneGeometry
        Ownship and array-centre positions (m) and headings (rad, clockwise from north); per ship (S, T):
        positions, velocities, range (m), true bearing (rad, clockwise from north, in (-pi, pi]), cone angle
        (rad, 0..pi from the array axis, 0 ahead) and range rate (m/s).
    """
    t = np.atleast_1d(np.asarray(t_s, dtype=float))
    track = ownship_track(scene)
    own_xy, _, own_h = track.state(t)
    array_xy, array_v, array_h = array_state(track, t, scene.array.tow_length_m)
    motion = [ship_motion(place_ship(scene, s), t) for s in scene.ships]
    ship_xy = np.stack([m[0] for m in motion]) if motion else np.zeros((0, t.size, 2))
    ship_v = np.stack([m[1] for m in motion]) if motion else np.zeros((0, t.size, 2))
    d = ship_xy - array_xy[None]
    r = np.hypot(d[..., 0], d[..., 1])
    axis = np.stack([np.sin(array_h), np.cos(array_h)], axis=-1)
    cos_cone = np.einsum("stk,tk->st", d, axis) / np.maximum(r, 1e-9)
    rdot = np.einsum("stk,stk->st", d, ship_v - array_v[None]) / np.maximum(r, 1e-9)
    return SceneGeometry(t, own_xy, wrap_angle(own_h), array_xy, wrap_angle(array_h), ship_xy, ship_v, r,
                         np.arctan2(d[..., 0], d[..., 1]), np.arccos(np.clip(cos_cone, -1.0, 1.0)), rdot)


def broadband_tl_frequency_hz(scene: PassiveSceneSettings) -> float:
    """Frequency at which the broadband noise's TL is taken: the band's geometric centre ``sqrt(max(lo, 1) hi)``.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (``band_hz``).

    Returns
    -------
    float
        Frequency (Hz).
    """
    lo, hi = scene.band_hz
    return float(np.sqrt(max(lo, 1.0) * hi))


def transmission_loss_db(scene: PassiveSceneSettings, ranges_m, freq_hz: float, source_depth_m: float,
                         store=None) -> np.ndarray:
    """Transmission loss by the scene's propagation model (module docstring).

    ``spherical``: 20 log10 r + Thorp absorption; ``ram``: RAM in the scene's environment, averaged over
    ``tl_average_m``.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (propagation model, environment, array depth).
    ranges_m : array_like
        Source-receiver ranges (m).
    freq_hz : float
        Frequency (Hz).
    source_depth_m : float
        Source depth (m).
    store : optional
        Cache of RAM fields (e.g. io/environment.py's ``TLDiskCache``); None computes them.

    Returns
    -------
    ndarray
        TL (dB), shape of ``ranges_m``.
    """
    from sonartrack.acoustics.transmission_loss import thorp_absorption_db_per_km, transmission_loss

    r = np.asarray(ranges_m, dtype=float)
    if scene.propagation == "spherical":
        return 20.0 * np.log10(np.maximum(r, 1.0)) + thorp_absorption_db_per_km(freq_hz) * r / 1e3
    from sonartrack.acoustics.environment import load_environment

    rmax = RAM_RANGE_STEP_M * np.ceil(max(float(r.max(initial=0.0)) * 1.05, 1.0) / RAM_RANGE_STEP_M)
    return transmission_loss(load_environment(scene.environment), freq_hz, source_depth_m, scene.array.depth_m, r,
                             rmax_m=rmax, average_m=scene.tl_average_m, store=store)


def received_levels(scene: PassiveSceneSettings, geometry: SceneGeometry, store=None) -> ReceivedLevels:
    """Received levels at an element and the Doppler-shifted tonal frequency of every ship (module docstring).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    geometry : SceneGeometry
        Its geometry (:func:`scene_geometry`).
    store : optional
        Cache of RAM fields (see :func:`transmission_loss_db`).

    Returns
    -------
    ReceivedLevels
        Per ship and time (S, T): broadband spectral level (dB re 1 uPa^2/Hz), tonal power (dB re 1 uPa^2)
        and received tonal frequency (Hz); NaN for a ship without a tonal.
    """
    f_bb = broadband_tl_frequency_hz(scene)
    shape = geometry.range_m.shape
    bb, tonal, f_r = np.empty(shape), np.full(shape, np.nan), np.full(shape, np.nan)
    for i, ship in enumerate(scene.ships):
        r = geometry.range_m[i]
        bb[i] = ship.source_level_db - transmission_loss_db(scene, r, f_bb, ship.depth_m, store)
        if ship.tonal_hz is not None:
            tonal[i] = ship.tonal_level_db - transmission_loss_db(scene, r, ship.tonal_hz, ship.depth_m, store)
            f_r[i] = ship.tonal_hz * (1.0 - geometry.range_rate_mps[i] / scene.sound_speed_mps)
    return ReceivedLevels(bb, tonal, f_r)


def nav_columns(geometry: SceneGeometry) -> dict[str, np.ndarray]:
    """The navigation table: ownship position and heading, array centre position and axis heading.

    Parameters
    ----------
    geometry : SceneGeometry
        Scene geometry.

    Returns
    -------
    dict of str to ndarray, each shape (T,)
        ``time_s``, ``x_m``, ``y_m``, ``heading_deg``, ``array_x_m``, ``array_y_m``, ``array_heading_deg``
        (headings in deg 0..360, clockwise from north).
    """
    g = geometry
    return {"time_s": g.time_s, "x_m": g.own_xy[:, 0], "y_m": g.own_xy[:, 1],
            "heading_deg": np.rad2deg(g.own_heading_rad) % 360.0,
            "array_x_m": g.array_xy[:, 0], "array_y_m": g.array_xy[:, 1],
            "array_heading_deg": np.rad2deg(g.array_heading_rad) % 360.0}


def truth_columns(scene: PassiveSceneSettings, geometry: SceneGeometry, levels: ReceivedLevels) -> dict:
    """The truth table, a row per time and ship (time-major): kinematics, bearing, cone angle, side, SNRs.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (ship names, noise level).
    geometry : SceneGeometry
        Scene geometry.
    levels : ReceivedLevels
        Received levels.

    Returns
    -------
    dict of str to ndarray, each shape (T S,)
        ``time_s``, ``ship``, ``x_m``, ``y_m``, ``vx_mps``, ``vy_mps``, ``bearing_deg`` (0..360, clockwise
        from north), ``cone_deg`` (0..180 from the array axis), ``side`` ("port"/"starboard"), ``range_m``,
        ``range_rate_mps``, ``snr_db`` (broadband, per element: RL_bb - NL), ``tonal_hz``, ``tonal_snr_db``
        (RL_t - NL, in 1 Hz).
    """
    g = geometry
    n_s, n_t = g.range_m.shape
    names = np.array([s.name for s in scene.ships], dtype=object)
    side = np.where(np.sin(g.bearing_rad - g.array_heading_rad[None]) >= 0.0, "starboard", "port")

    def flat(a):  # (S, T) -> time-major rows
        return np.asarray(a).T.reshape(-1)

    return {"time_s": np.repeat(g.time_s, n_s), "ship": np.tile(names, n_t),
            "x_m": flat(g.ship_xy[..., 0]), "y_m": flat(g.ship_xy[..., 1]),
            "vx_mps": flat(g.ship_velocity[..., 0]), "vy_mps": flat(g.ship_velocity[..., 1]),
            "bearing_deg": flat(np.rad2deg(g.bearing_rad) % 360.0), "cone_deg": flat(np.rad2deg(g.cone_rad)),
            "side": flat(side), "range_m": flat(g.range_m), "range_rate_mps": flat(g.range_rate_mps),
            "snr_db": flat(levels.broadband_db - scene.noise_level_db),
            "tonal_hz": flat(levels.tonal_hz), "tonal_snr_db": flat(levels.tonal_db - scene.noise_level_db)}
