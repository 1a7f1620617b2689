"""Scenes of a target that zigs: piecewise-constant-velocity target legs seen from an ownship on a manoeuvre pattern.

The target (the truth of study ``manoeuvring-target``): legs of ``leg_min_s``..``leg_max_s`` at constant velocity,
joined by instantaneous velocity changes (a zig): a course change of ``turn_deg`` (either side), and with
probability ``speed_change_share`` a speed change of ``speed_change_kn`` too (up or down, within ``speed_kn``). The
position is continuous, p(t) = p0 + sum_k a_k(t) v_k with a_k the time spent on leg k up to t (the model of
tma/legs.py, so that its Cramer-Rao bound is the bound of the truth). A share ``cv_share`` of the scenes hold
one leg (constant velocity). The last leg goes on after the record (the ownship's advice is judged there).

A real turn takes time (120 deg at 3 deg/s: 40 s, one or two bearing intervals); taking it as instantaneous makes
the leg model exact, so that every error measured is the estimator's, not the model's.

Placement: the target's range at the middle of the record is drawn in ``range_m`` at a uniform bearing; a scene
whose range leaves ``min_range_m``..``max_range_m`` during the record is drawn again (a target that passes within a
few km or runs out to 40 km is another study).

The ownship (sim/platforms.py :class:`~sonartrack.sim.platforms.ManeuveringTrack`, constant speed ``own_speed_kn``)
follows one of three patterns, drawn with equal odds:

* ``leg-turn-leg``: legs of 15-30 min joined by turns of 60-120 deg to either side at 1 deg/s;
* ``zig-zag``: legs of 5-10 min alternating 20-45 deg either side of a base course (turns of 40-90 deg) at 1 deg/s;
* ``constant-turn``: a steady turn at 0.05-0.15 deg/s (a circle of 1-3 km radius at 4-8 kn) the whole record.

Bearings every ``bearing_interval_s`` (drawn per scene), from a random phase. The scene gives the true bearings and
the cone angle of each (the angle between the ownship's heading, taken as the axis of its towed line array, and
the line of sight: a towed array's lag behind the ship is neglected); the measurement noise, whose sd follows the
array's law in cone angle, is drawn by the study that uses the scene (systems/passive/targets.py
:func:`~sonartrack.systems.passive.targets.line_array_relative_sigma`): sim/ only makes the truth here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.settings import Settings, setting
from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.platforms import ManeuveringTrack

#: the ownship's manoeuvre patterns (module doc)
OWN_PATTERNS = ("leg-turn-leg", "zig-zag", "constant-turn")
#: scenes drawn again at most this many times to meet the range bounds before the bounds are widened
MAX_DRAWS = 200


class ManoeuvreSceneSettings(Settings):
    """The family of scenes :func:`draw_manoeuvre_scene` draws from (each pair a [low, high] range)."""

    duration_s: list[float] = setting(default_factory=lambda: [3600.0, 5400.0], doc="length of the record",
                                      unit="s", min_length=2, max_length=2)
    bearing_interval_s: list[float] = setting(default_factory=lambda: [2.0, 10.0], doc="time between bearings",
                                              unit="s", min_length=2, max_length=2)
    leg_s: list[float] = setting(default_factory=lambda: [300.0, 1800.0], doc="length of each target leg",
                                 unit="s", min_length=2, max_length=2)
    turn_deg: list[float] = setting(default_factory=lambda: [20.0, 120.0], doc="course change at a zig (either "
                                    "side)", unit="deg", min_length=2, max_length=2)
    speed_change_kn: list[float] = setting(default_factory=lambda: [2.0, 10.0], doc="speed change at a zig that "
                                           "changes speed (up or down)", unit="kn", min_length=2, max_length=2)
    speed_change_share: float = setting(0.5, "share of the zigs that change speed as well as course", unit="1",
                                        ge=0, le=1)
    speed_kn: list[float] = setting(default_factory=lambda: [4.0, 15.0], doc="target speeds", unit="kn",
                                    min_length=2, max_length=2)
    range_m: list[float] = setting(default_factory=lambda: [5000.0, 20000.0], doc="target range at the middle of "
                                   "the record", unit="m", min_length=2, max_length=2)
    min_range_m: float = setting(2000.0, "a scene whose range falls below this during the record is drawn again",
                                 unit="m", gt=0)
    max_range_m: float = setting(30000.0, "a scene whose range exceeds this during the record is drawn again",
                                 unit="m", gt=0)
    cv_share: float = setting(0.3, "share of the scenes whose target keeps one leg (constant velocity)", unit="1",
                              ge=0, le=1)
    own_speed_kn: list[float] = setting(default_factory=lambda: [4.0, 8.0], doc="ownship speed", unit="kn",
                                        min_length=2, max_length=2)


@dataclass(frozen=True, slots=True)
class ManoeuvreScene:
    """One drawn scene: the bearing times, the ownship and its heading there, the target's legs and the true
    bearings and cone angles.

    ``params`` is the target's leg parameters [x0, y0, vx_1, vy_1, ..., vx_K+1, vy_K+1] (m, m/s) at ``time_s[0]``
    and ``change_times_s`` its K zig times (tma/legs.py's theta and c); ``turn_deg`` and ``speed_change_kn`` each
    zig's course change (signed, positive to starboard) and speed change."""

    time_s: np.ndarray
    own_xy_m: np.ndarray
    own_heading_rad: np.ndarray
    ownship: ManeuveringTrack
    own_pattern: str
    params: np.ndarray
    change_times_s: np.ndarray
    turn_deg: np.ndarray
    speed_change_kn: np.ndarray
    bearing_rad: np.ndarray
    cone_rad: np.ndarray

    def target_xy_m(self, t_s) -> np.ndarray:
        """The target's positions (n, 2) (m) at times ``t_s`` (s; the last leg goes on after the record)."""
        t = np.atleast_1d(np.asarray(t_s, float))
        edges = np.r_[self.time_s[0], self.change_times_s, np.inf]
        a = np.clip(t[:, None] - edges[:-1], 0.0, edges[1:] - edges[:-1])
        return self.params[:2] + a @ self.params[2:].reshape(-1, 2)

    @property
    def velocities_mps(self) -> np.ndarray:
        """Each leg's velocity (K + 1, 2) (m/s)."""
        return self.params[2:].reshape(-1, 2)


def _uniform(rng: np.random.Generator, bounds) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def _ownship_turns(rng: np.random.Generator, pattern: str, duration_s: float) -> tuple[float, tuple]:
    """Initial heading (rad) and turns (start s, end s, rate rad/s) of an ownship pattern (module doc)."""
    heading0 = rng.uniform(0.0, 2.0 * np.pi)
    rate = np.radians(1.0)
    if pattern == "constant-turn":
        w = rng.choice([-1.0, 1.0]) * np.radians(rng.uniform(0.05, 0.15))
        return heading0, ((0.0, duration_s + 1.0, float(w)),)
    turns, t, side = [], 0.0, rng.choice([-1.0, 1.0])
    while True:
        if pattern == "leg-turn-leg":
            t += rng.uniform(900.0, 1800.0)
            size = np.radians(rng.uniform(60.0, 120.0)) * rng.choice([-1.0, 1.0])
        else:  # zig-zag about the base course: from +a to -b is a turn of a + b
            t += rng.uniform(300.0, 600.0)
            size = side * np.radians(rng.uniform(40.0, 90.0))
            side = -side
        if t >= duration_s:
            return heading0, tuple(turns)
        end = t + abs(size) / rate
        turns.append((t, end, float(np.sign(size) * rate)))
        t = end


def _target_legs(rng: np.random.Generator, s: ManoeuvreSceneSettings, t0: float, t_end: float):
    """Change times, course changes (deg), speed changes (kn) and leg velocities (m/s) of one target."""
    course = rng.uniform(0.0, 360.0)
    speed = _uniform(rng, s.speed_kn)
    changes, turns, dspeeds, vels = [], [], [], []
    t = t0
    while True:
        vels.append(speed * KNOT_MPS * np.array([np.sin(np.radians(course)), np.cos(np.radians(course))]))
        if rng.uniform() < s.cv_share and not changes:  # a constant-velocity scene: one leg
            break
        t += _uniform(rng, s.leg_s)
        if t > t_end - s.leg_s[0]:  # the last leg lasts at least the shortest leg
            break
        turn = rng.choice([-1.0, 1.0]) * _uniform(rng, s.turn_deg)
        dv = 0.0
        if rng.uniform() < s.speed_change_share:
            dv = _uniform(rng, s.speed_change_kn)
            room = [d for d in (dv, -dv) if s.speed_kn[0] <= speed + d <= s.speed_kn[1]]
            # no room either way (a 9 kn change at 8 kn): the largest change the speed bounds allow
            dv = float(rng.choice(room)) if room else max(s.speed_kn[1] - speed, s.speed_kn[0] - speed, key=abs)
        changes.append(t)
        turns.append(turn)
        dspeeds.append(dv)
        course, speed = course + turn, speed + dv
    return np.array(changes), np.array(turns), np.array(dspeeds), np.array(vels)


def draw_manoeuvre_scene(settings: ManoeuvreSceneSettings, rng: np.random.Generator) -> ManoeuvreScene:
    """One scene of the family (module doc), a pure function of ``rng``'s state.

    Parameters
    ----------
    settings : ManoeuvreSceneSettings
        The family.
    rng : numpy.random.Generator
        The trial's random stream.

    Returns
    -------
    ManoeuvreScene
        The bearing times, ownship, target legs, true bearings and cone angles.
    """
    s = settings
    duration, dt = _uniform(rng, s.duration_s), _uniform(rng, s.bearing_interval_s)
    t = rng.uniform(0.0, dt) + np.arange(0.0, duration, dt)
    pattern = str(rng.choice(OWN_PATTERNS))
    heading0, turns = _ownship_turns(rng, pattern, duration + dt)
    ownship = ManeuveringTrack(0.0, 0.0, _uniform(rng, s.own_speed_kn) * KNOT_MPS, float(heading0), turns)
    own, _, heading = ownship.state(t)
    mid = len(t) // 2
    for draw in range(MAX_DRAWS):
        changes, turn_deg, dspeed, vels = _target_legs(rng, s, t[0], t[-1])
        edges = np.r_[t[0], changes, np.inf]
        a = np.clip(t[:, None] - edges[:-1], 0.0, edges[1:] - edges[:-1])
        rel = a @ vels  # the track from p0 = 0
        b, r = rng.uniform(0.0, 2.0 * np.pi), _uniform(rng, s.range_m)
        p0 = own[mid] + r * np.array([np.sin(b), np.cos(b)]) - rel[mid]
        rng_m = np.hypot(*(p0 + rel - own).T)
        if (rng_m.min() >= s.min_range_m and rng_m.max() <= s.max_range_m) or draw == MAX_DRAWS - 1:
            break
    d = p0 + rel - own
    bearing = np.arctan2(d[:, 0], d[:, 1])
    return ManoeuvreScene(time_s=t, own_xy_m=own, own_heading_rad=heading, ownship=ownship, own_pattern=pattern,
                          params=np.r_[p0, vels.ravel()], change_times_s=changes, turn_deg=turn_deg,
                          speed_change_kn=dspeed, bearing_rad=bearing, cone_rad=wrap_angle(bearing - heading))
