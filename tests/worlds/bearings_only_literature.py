"""Bearings-only scenarios published in the literature, posed from their papers' numbers with numpy alone.

Nothing here imports sonartrack: the geometry, the target's wandering and the bearings are written from the papers'
descriptions, so that a test holds our TMA and its bounds to worlds we did not build with our own simulator.

The two scenarios of Leong, Arulampalam, Lamahewa & Abhayapala, "Gaussian-sum cubature Kalman filter with improved
robustness for bearings-only tracking", IEEE Signal Processing Letters 21(5), 513-517, 2014 (their MATLAB scenario
definitions, read at github: the file opening "% Bearings-only tracking using the Gaussian-sum cubature Kalman filter
with improved robustness", scenarios 'm' and 'h'); 'm' is the scenario of Ristic, Arulampalam & Gordon, Beyond the
Kalman Filter, Artech House 2004, ch. 6 (sec. 6.4: observer at 5 kn on 140 deg turning to 20 deg, target ~5 km away
at 4 kn on -140 deg, bearing sd 1.5 deg, one bearing a minute for 32 minutes):

* ``MODERATE`` ('m', "moderately nonlinear"): 33 bearings T = 60 s apart (steps 0..32); ownship from the origin at
  5 kn on course 140 deg, turning to 20 deg in four equal course steps, the new velocities taking effect at steps
  13, 14, 15, 16 (each moves the ship from that step on); target from (4.92, 0.85) km at 4 kn on course -140 deg;
  bearing sd 1.5 deg; white-acceleration spectral density q = 9e-12 km^2/s^3 (9e-6 m^2/s^3); the filters' prior:
  range sd 2 km, speed sd 2 kn, course sd pi / sqrt(12) (uniform), from the first bearing.
* ``HIGH`` ('h', "highly nonlinear"): 31 bearings 60 s apart; ownship 5 kn on course -80 deg, one turn to 146 deg
  taking effect at step 15; target from (7.0909, 7.0526) km at 15 kn on course -135.4 deg; bearing sd 2 deg; the
  same q; prior range sd 4 km, speed sd 2 kn, course sd pi / sqrt(12).

The papers' knot is 5.14e-4 km/s; we use 1852 / 3600 m/s (0.09 % apart). Bearings are clockwise from north,
atan2(dx, dy), as in the papers. Units here: m, s, rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KNOT_MPS = 1852.0 / 3600.0


@dataclass(frozen=True)
class Scenario:
    """One published bearings-only scenario (module docstring): the numbers as the paper gives them."""

    name: str
    steps: int  # bearings at steps 0..steps
    step_s: float
    own_speed_kn: float
    own_course_deg: float
    own_final_course_deg: float
    turn_steps: tuple  # the steps at which each equal course change takes effect
    target_xy_m: tuple
    target_speed_kn: float
    target_course_deg: float
    bearing_sd_deg: float
    q_m2_s3: float
    prior_range_sd_m: float
    prior_speed_sd_kn: float = 2.0
    prior_course_sd_rad: float = np.pi / np.sqrt(12.0)

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.steps + 1) * self.step_s

    @property
    def sigma_rad(self) -> float:
        return float(np.radians(self.bearing_sd_deg))

    def ownship(self, turn: bool = True) -> np.ndarray:
        """Ownship positions (steps + 1, 2) (m): dead reckoning at each step's velocity, the course changed in equal
        parts at ``turn_steps`` (``turn`` False: the first leg's course throughout, the no-manoeuvre variant)."""
        course = np.radians(self.own_course_deg)
        step = np.radians(self.own_final_course_deg - self.own_course_deg) / len(self.turn_steps)
        pos = np.zeros((self.steps + 1, 2))
        for k in range(1, self.steps + 1):
            v = self.own_speed_kn * KNOT_MPS * np.array([np.sin(course), np.cos(course)])
            pos[k] = pos[k - 1] + self.step_s * v
            if turn and k in self.turn_steps:
                course += step
        return pos

    @property
    def target_x0(self) -> np.ndarray:
        """The target's true [x, y, vx, vy] at step 0 (m, m/s)."""
        c = np.radians(self.target_course_deg)
        v = self.target_speed_kn * KNOT_MPS
        return np.array([*self.target_xy_m, v * np.sin(c), v * np.cos(c)], float)

    def target(self, runs: int = 0, seed: int = 0) -> np.ndarray:
        """True target states: (steps + 1, 4) at constant velocity (``runs`` 0), or (runs, steps + 1, 4) driven by
        white acceleration of density q, discretised exactly: x_k = F x_k-1 + w, w ~ N(0, q [[T^3/3, T^2/2],
        [T^2/2, T]] per axis) (Bar-Shalom, Li & Kirubarajan 2001, sec. 6.2.2)."""
        T, n = self.step_s, self.steps + 1
        x0 = self.target_x0
        if runs == 0:
            return x0 + self.time_s[:, None] * np.r_[x0[2:], 0.0, 0.0]
        per_axis = self.q_m2_s3 * np.array([[T**3 / 3.0, T**2 / 2.0], [T**2 / 2.0, T]])
        L = np.linalg.cholesky(per_axis)
        rng = np.random.default_rng(seed)
        w = rng.standard_normal((runs, n - 1, 2, 2)) @ L.T  # [..., axis, (position, velocity)]
        X = np.empty((runs, n, 4))
        X[:, 0] = x0
        for k in range(1, n):
            X[:, k, :2] = X[:, k - 1, :2] + T * X[:, k - 1, 2:] + w[:, k - 1, :, 0]
            X[:, k, 2:] = X[:, k - 1, 2:] + w[:, k - 1, :, 1]
        return X

    def bearings(self, target_xy, own_xy, rng) -> np.ndarray:
        """Noisy bearings (rad, clockwise from north) of target positions (..., n, 2) from the ownship (n, 2)."""
        d = np.asarray(target_xy)[..., :2] - own_xy
        z = np.arctan2(d[..., 0], d[..., 1]) + self.sigma_rad * rng.standard_normal(d.shape[:-1])
        return (z + np.pi) % (2.0 * np.pi) - np.pi


MODERATE = Scenario(name="m", steps=32, step_s=60.0, own_speed_kn=5.0, own_course_deg=140.0,
                    own_final_course_deg=20.0, turn_steps=(13, 14, 15, 16), target_xy_m=(4920.0, 850.0),
                    target_speed_kn=4.0, target_course_deg=-140.0, bearing_sd_deg=1.5, q_m2_s3=9e-6,
                    prior_range_sd_m=2000.0)

HIGH = Scenario(name="h", steps=30, step_s=60.0, own_speed_kn=5.0, own_course_deg=-80.0, own_final_course_deg=146.0,
                turn_steps=(15,), target_xy_m=(7090.9, 7052.6), target_speed_kn=15.0, target_course_deg=-135.4,
                bearing_sd_deg=2.0, q_m2_s3=9e-6, prior_range_sd_m=4000.0)
