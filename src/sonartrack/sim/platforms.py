"""Platform trajectories: constant-speed tracks with piecewise-constant turn rates.

A track is defined by a start position, a speed, an initial heading (clockwise from north) and a
list of turns ``(t_start_s, t_end_s, rate_rad_s)``. Between turns the heading is constant; during
a turn it changes linearly. Positions are integrated in closed form (straight segments and arcs),
so they are exact at any time, not only on a simulation grid:

    straight:  p(t) = p0 + v (t - t0) [sin h0, cos h0]
    arc:       p(t) = p0 + (v / w) [cos h0 - cos h(t), sin h(t) - sin h0],  h(t) = h0 + w (t - t0)

Towed bodies (a transmitter or receiver on a cable of length L behind the ship) follow the ship's
own track: a body towed L metres behind sits where the ship was ``L / v`` seconds earlier, and its
axis heading is the ship's heading then (DIGEST P4: "both towed behind the ownship along its track").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require


@dataclass(frozen=True, slots=True)
class ManeuveringTrack:
    """A constant-speed platform track with turns ``(t_start_s, t_end_s, rate_rad_s)``."""

    x0_m: float
    y0_m: float
    speed_mps: float
    heading0_rad: float
    turns: tuple[tuple[float, float, float], ...] = ()
    t0_s: float = 0.0

    def __post_init__(self):
        require(self.speed_mps >= 0, f"speed must be non-negative (got {self.speed_mps} m/s)")
        last = -np.inf
        for a, b, _ in self.turns:
            require(b > a and a >= last, "turns must be (start, end) with start < end, sorted and not overlapping")
            last = b

    def _segments(self):
        """Breakpoints (t, heading, rate) of the piecewise-constant turn rate, from t0 onwards."""
        seg = [(self.t0_s, self.heading0_rad, 0.0)]
        h, t = self.heading0_rad, self.t0_s
        for a, b, w in self.turns:
            if b <= t:
                continue
            a = max(a, t)
            h = h + seg[-1][2] * (a - seg[-1][0])
            seg.append((a, h, w))
            h = h + w * (b - a)
            seg.append((b, h, 0.0))
            t = b
        return seg

    def state(self, t_s):
        """Position, velocity and heading at any times, in closed form (module docstring).

        Parameters
        ----------
        t_s : float or array_like, shape (...)
            Times (s); before ``t0_s`` the first segment is extrapolated backwards.

        Returns
        -------
        pos : ndarray, shape (..., 2)
            Position [x east, y north] (m).
        vel : ndarray, shape (..., 2)
            Velocity [vx, vy] (m/s).
        heading : ndarray, shape (...)
            Heading (rad, clockwise from north; not wrapped).
        """
        t = np.asarray(t_s, dtype=float)
        seg = self._segments()
        # position at each breakpoint
        p = [np.array([self.x0_m, self.y0_m])]
        for (ta, ha, wa), (tb, _, _) in zip(seg[:-1], seg[1:], strict=True):
            p.append(p[-1] + self._advance(tb - ta, ha, wa))
        starts = np.array([s[0] for s in seg])
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(seg) - 1)
        ta = starts[k]
        ha = np.array([s[1] for s in seg])[k]
        wa = np.array([s[2] for s in seg])[k]
        pk = np.stack(p)[k]
        dt = t - ta
        pos = pk + self._advance(dt, ha, wa)
        heading = ha + wa * dt
        vel = self.speed_mps * np.stack([np.sin(heading), np.cos(heading)], axis=-1)
        return pos, vel, heading

    def _advance(self, dt, h0, w):
        """Displacement after ``dt`` from heading ``h0`` at turn rate ``w`` (closed form, w -> 0 safe)."""
        return _displacement(self.speed_mps, dt, h0, w)

    def towed(self, t_s, cable_m: float):
        """Position and axis heading of a body towed ``cable_m`` behind along the ship's own track.

        The body sits where the ship was ``cable_m / speed`` seconds earlier, heading as the ship did then.

        Parameters
        ----------
        t_s : float or array_like, shape (...)
            Times (s).
        cable_m : float
            Distance behind the ship along its track (m).

        Returns
        -------
        pos : ndarray, shape (..., 2)
            Position [x east, y north] (m).
        heading : ndarray, shape (...)
            Axis heading (rad, clockwise from north).

        Raises
        ------
        InputError
            If the ship does not move (speed 0).
        """
        require(self.speed_mps > 0, "a towed body needs a moving ship (speed > 0)")
        pos, _, heading = self.state(np.asarray(t_s, float) - cable_m / self.speed_mps)
        return pos, heading


def constant_velocity_track(t_s, x0_m, y0_m, vx_mps, vy_mps, t0_s: float = 0.0):
    """States of a constant-velocity target at times ``t_s``.

    Parameters
    ----------
    t_s : float or array_like, shape (...)
        Times (s).
    x0_m, y0_m : float
        Position east and north at ``t0_s`` (m).
    vx_mps, vy_mps : float
        Velocity east and north (m/s).
    t0_s : float, default 0.0
        Reference time (s).

    Returns
    -------
    ndarray, shape (..., 4)
        [x, y, vx, vy] (m, m/s).
    """
    t = np.asarray(t_s, dtype=float) - t0_s
    return np.stack([x0_m + vx_mps * t, y0_m + vy_mps * t,
                     np.full_like(t, vx_mps), np.full_like(t, vy_mps)], axis=-1)


def _displacement(speed_mps, dt_s, h0_rad, rate_rad_s):
    """Displacement (..., 2) after ``dt_s`` at ``speed_mps`` from heading ``h0_rad`` turning at ``rate_rad_s``
    (closed form: straight or arc; w -> 0 safe)."""
    v, dt, h0, w = np.broadcast_arrays(*(np.asarray(a, float) for a in (speed_mps, dt_s, h0_rad, rate_rad_s)))
    small = np.abs(w * dt) < 1e-9
    ws = np.where(small, 1.0, w)
    h1 = h0 + w * dt
    dx = np.where(small, v * dt * np.sin(h0 + 0.5 * w * dt), v / ws * (np.cos(h0) - np.cos(h1)))
    dy = np.where(small, v * dt * np.cos(h0 + 0.5 * w * dt), v / ws * (np.sin(h1) - np.sin(h0)))
    return np.stack([dx, dy], axis=-1)


@dataclass(frozen=True, slots=True)
class LegTrack:
    """A platform on legs: segments ``(t_start_s, speed_mps, heading_rad, rate_rad_s)`` of constant speed and
    constant turn rate (0 on a leg, non-zero in a turn between legs), the position continuous.

    The first segment starts at the time of ``(x0_m, y0_m)`` and is extrapolated backwards before it; the last goes
    on for ever. A speed change is instantaneous (at a segment's start); a course change is a turn segment, or
    instantaneous when the next segment simply starts on the new heading (a velocity step, the model of tma/legs.py).
    A body towed ``cable_m`` behind sits on the ship's own track ``cable_m`` of path behind the ship (for a constant
    speed, where the ship was ``cable_m / v`` earlier, as :meth:`ManeuveringTrack.towed`)."""

    x0_m: float
    y0_m: float
    segments: tuple[tuple[float, float, float, float], ...]

    def __post_init__(self):
        require(len(self.segments) >= 1, "a leg track needs at least one segment")
        starts = [s[0] for s in self.segments]
        require(all(b > a for a, b in zip(starts[:-1], starts[1:], strict=True)), "segments must start in order")
        require(all(s[1] >= 0 for s in self.segments), "segment speeds must be non-negative")

    def _knots(self):
        """Per segment: start time, speed, heading, rate, and the position and path length at its start."""
        seg = np.array(self.segments, float)
        t, v, h, w = seg.T
        dt = np.diff(t)
        steps = _displacement(v[:-1], dt, h[:-1], w[:-1])
        pos = np.vstack([[self.x0_m, self.y0_m], np.array([self.x0_m, self.y0_m]) + np.cumsum(steps, axis=0)])
        path = np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
        return t, v, h, w, pos, path

    def state(self, t_s):
        """Position (..., 2) (m), velocity (..., 2) (m/s) and heading (...) (rad, clockwise from north, not
        wrapped) at times ``t_s`` (s), in closed form."""
        t = np.asarray(t_s, dtype=float)
        ts, v, h, w, pos, _ = self._knots()
        k = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, len(ts) - 1)
        dt = t - ts[k]
        heading = h[k] + w[k] * dt
        xy = pos[k] + _displacement(v[k], dt, h[k], w[k])
        return xy, v[k][..., None] * np.stack([np.sin(heading), np.cos(heading)], axis=-1), heading

    def towed_state(self, t_s, cable_m: float):
        """Position (..., 2), velocity (..., 2) and axis heading (...) of a body towed ``cable_m`` behind along the
        ship's own track (class doc): at path length s(t) - cable_m, moving along the track at the ship's speed.

        Raises
        ------
        InputError
            If a segment has speed 0 (a towed body needs way on).
        """
        t = np.asarray(t_s, dtype=float)
        ts, v, _, _, _, path = self._knots()
        require(bool(np.all(v > 0)), "a towed body needs a moving ship (speed > 0 on every leg)")
        k = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, len(ts) - 1)
        behind = path[k] + v[k] * (t - ts[k]) - cable_m
        j = np.clip(np.searchsorted(path, behind, side="right") - 1, 0, len(ts) - 1)
        tau = ts[j] + (behind - path[j]) / v[j]
        xy, _, heading = self.state(tau)
        return xy, v[k][..., None] * np.stack([np.sin(heading), np.cos(heading)], axis=-1), heading

    def towed(self, t_s, cable_m: float):
        """Position (..., 2) (m) and axis heading (...) (rad) of a body towed ``cable_m`` behind (``towed_state``)."""
        xy, _, heading = self.towed_state(t_s, cable_m)
        return xy, heading
