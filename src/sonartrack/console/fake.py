"""A stand-in for the live chain: display updates in the LIVE.md shapes, drawn from plain geometry.

For the console's tests, its benchmark and a look at the page before a stream is wired: an ownship steaming north
that turns to east at ``turn_s``, straight-running targets, a bearing-time row per window (noise plus a peak at
each target's cone angle), tracks at those cones, LOFAR rows of the selected track with its tonal, a target
table whose range is undetermined until the ownship has turned, the 95 % ellipse of a made-up range error and
the mirror across the array axis. Nothing here is an estimate: it only exercises the display.
"""

from __future__ import annotations

import math

import numpy as np

_CHI2_95_2DOF = 5.991  # 95 % point of chi-square with 2 degrees of freedom (the ellipse's scale)


class FakeLive:
    """Display updates window by window; :meth:`step` returns one window's list, :attr:`selected` picks LOFAR.

    Parameters
    ----------
    seed : int
        Seed of the noise (same seed, same updates).
    window_s : float
        Seconds per bearing-time row.
    n_bins : int
        Cone-angle bins of a row, 0..180 deg.
    """

    def __init__(self, seed: int = 0, *, window_s: float = 1.0, n_bins: int = 181, turn_s: float = 120.0):
        self.rng = np.random.default_rng(seed)
        self.window_s, self.turn_s = float(window_s), float(turn_s)
        self.cone_deg = np.linspace(0.0, 180.0, n_bins)
        self.freq_hz = np.arange(20.0, 500.0, 2.0)
        # targets: start position (m), velocity (m/s), tonal (Hz), source level above noise (dB)
        self.targets = [
            dict(id=1, xy=np.array([4000.0, 6000.0]), v=np.array([-3.0, 1.0]), tonal=120.0, snr=14.0),
            dict(id=2, xy=np.array([-5000.0, 3000.0]), v=np.array([2.0, 2.0]), tonal=250.0, snr=11.0),
            dict(id=3, xy=np.array([1500.0, -7000.0]), v=np.array([0.0, 4.0]), tonal=330.0, snr=9.0),
        ]
        self.k = 0
        self.selected: int | None = None

    def ownship(self, t_s: float) -> tuple[np.ndarray, float]:
        """Ownship position (m) and heading (deg) at ``t_s``: north at 3 m/s, then east after the turn."""
        if t_s <= self.turn_s:
            return np.array([0.0, 3.0 * t_s]), 0.0
        return np.array([3.0 * (t_s - self.turn_s), 3.0 * self.turn_s]), 90.0

    def step(self) -> list[dict]:
        """The updates of the next window."""
        t = self.k * self.window_s
        self.k += 1
        own, heading = self.ownship(t)
        a = math.radians(heading)
        axis = np.array([math.sin(a), math.cos(a)])
        seen = []
        for tg in self.targets:
            xy = tg["xy"] + tg["v"] * t
            d = xy - own
            bearing = math.degrees(math.atan2(d[0], d[1])) % 360.0
            cone = math.degrees(math.acos(float(np.clip(d @ axis / np.hypot(*d), -1, 1))))
            seen.append((tg, xy, bearing, cone, float(np.hypot(*d))))
        level = 60.0 + 2.0 * self.rng.standard_normal(self.cone_deg.size)
        for tg, _, _, cone, _ in seen:
            level += tg["snr"] * np.exp(-0.5 * ((self.cone_deg - cone) / 2.5) ** 2)
        updates = [
            {"type": "ownship", "t_s": t, "x_m": own[0], "y_m": own[1], "heading_deg": heading,
             "array": [own.tolist(), (own - 300.0 * axis).tolist()], "lat_deg": 50.0, "lon_deg": -4.0},
            {"type": "btr", "t_s": t, "cone_deg": self.cone_deg.round(2), "level_db": level.round(2)},
            {"type": "tracks", "t_s": t, "tracks": [{"id": tg["id"], "cone_deg": round(cone, 2),
                                                    "status": "confirmed" if t >= 5 * self.window_s else "tentative"}
                                                   for tg, _, _, cone, _ in seen]},
        ]
        updates += self._lofar(t, seen) + [self._targets(t, seen, own, axis), self._health(t)]
        return updates

    def _lofar(self, t: float, seen) -> list[dict]:
        for tg, *_ in seen:
            if tg["id"] == self.selected:
                level = 50.0 + 2.0 * self.rng.standard_normal(self.freq_hz.size)
                level += 12.0 * np.exp(-0.5 * ((self.freq_hz - tg["tonal"]) / 2.0) ** 2)
                return [{"type": "lofar", "track": tg["id"], "t_s": t, "freq_hz": self.freq_hz,
                         "level_db": level.round(2)}]
        return []

    def _targets(self, t: float, seen, own: np.ndarray, axis: np.ndarray) -> dict:
        rows = []
        for tg, xy, bearing, _, rng_m in seen:
            row = {"id": tg["id"], "side": "undecided", "bearing_deg": round(bearing, 2), "range_m": None,
                   "range_sd_m": None, "reason": "ownship has not turned: range not observable yet",
                   "tonal_hz": tg["tonal"], "course_deg": None, "speed_mps": None, "x_m": None, "y_m": None,
                   "ellipse": [], "mirror": None, "legs": []}
            if t > self.turn_s + 30.0:
                sd = 0.08 * rng_m
                u = (xy - own) / rng_m  # the ellipse is long along the line of sight
                phi = np.linspace(0, 2 * np.pi, 37)
                k = math.sqrt(_CHI2_95_2DOF)
                ell = xy + k * (np.outer(np.cos(phi) * sd, u) + np.outer(np.sin(phi) * 0.02 * rng_m, [-u[1], u[0]]))
                d = xy - own
                mirror = own + 2 * (d @ axis) * axis - d  # reflected across the array axis
                v = tg["v"]
                row.update(side="starboard" if (axis[0] * d[1] - axis[1] * d[0]) < 0 else "port", range_m=rng_m,
                           range_sd_m=sd, reason=None, x_m=xy[0], y_m=xy[1], ellipse=ell.round(1),
                           course_deg=math.degrees(math.atan2(v[0], v[1])) % 360.0, speed_mps=float(np.hypot(*v)),
                           mirror={"x_m": mirror[0], "y_m": mirror[1]},
                           legs=[[(tg["xy"] + v * (t - 600.0)).tolist(), xy.tolist()]])
            rows.append(row)
        return {"type": "targets", "t_s": t, "rows": rows}

    def _health(self, t: float) -> dict:
        events = ["connected to tcp://127.0.0.1:5555"] if self.k == 1 else []
        return {"type": "health", "t_s": t, "rate_hz": 4000.0, "latency_s": 0.2, "gaps": 0, "events": events,
                "nav": "ok"}
