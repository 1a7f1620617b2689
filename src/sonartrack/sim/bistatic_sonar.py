"""A bistatic towed-array active sonar that detects one target in Poisson clutter.

Per ping at time t (Park, Song, Lee 2017, sec. IV; DIGEST P4):

* Tx and Rx are towed ``tx_cable_m`` and ``rx_cable_m`` behind the ship along its own track; the
  receiving array's axis heading phi is the ship's heading when it was where Rx is now.
* Errors common to the ping: Tx and Rx positions (``sigma_position_m`` per axis) and the assumed
  mean sound speed (``sigma_sound_speed_mps``) — the sonar does not know the true ones.
* Errors per echo: travel time (``sigma_time_s``) and bearing: ``sigma_bearing_rad`` while the ship
  runs straight, ``sigma_bearing_turn_rad`` while it turns (the towed array shakes).
* The target echo is present with probability ``pd``; clutter is Poisson over ``region``.

Every echo is converted to a Cartesian point with the noisy inputs (models/bistatic.py, eq. 2) and
reported with the covariance J Sigma J^T at the measured inputs. The Sigma the *reported*
covariance uses is ``reported_errors`` (default: the straight-running errors), which is how the
sonar's processor would describe its own accuracy if it is not told that the array shakes in a
turn — the mismatch the paper's IMM absorbs with a larger process noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.models.bistatic import BistaticErrors, bistatic_covariance, bistatic_inputs, bistatic_position
from sonartrack.models.clutter import Region, poisson_clutter
from sonartrack.sim.platforms import ManeuveringTrack


@dataclass(frozen=True, slots=True)
class BistaticSonar:
    """A bistatic towed-array active sonar (Park, Song, Lee 2017, sec. IV; module docstring).

    ``region`` is the clutter's surveillance region; ``tx_cable_m`` / ``rx_cable_m`` the tow lengths of the
    transmitter and the receiving array behind the ship (m); ``pd`` the probability that the target echo
    is present; ``clutter_density_per_m2`` the Poisson clutter density (1/m^2 per ping); ``sound_speed_mps``
    the true mean sound speed (m/s); ``errors`` the input errors while the ship runs straight;
    ``sigma_bearing_turn_rad`` the bearing error while it turns (rad); ``reported_errors`` the errors the
    reported covariances assume (None: ``errors``).
    """
    region: Region
    tx_cable_m: float = 300.0
    rx_cable_m: float = 450.0
    pd: float = 0.8
    clutter_density_per_m2: float = 1e-6
    sound_speed_mps: float = 1500.0
    errors: BistaticErrors = BistaticErrors()
    sigma_bearing_turn_rad: float = float(np.deg2rad(1.5))
    reported_errors: BistaticErrors | None = None


@dataclass(frozen=True, slots=True)
class Scan:
    """One scan of measurements: points (m, 2), covariances (m, 2, 2), target flag (m,)."""

    time_s: float
    z: np.ndarray
    R: np.ndarray
    is_target: np.ndarray
    tx_xy: np.ndarray
    rx_xy: np.ndarray


def is_turning(ship: ManeuveringTrack, t_s: float) -> bool:
    """Whether the ship is in one of its turns at ``t_s``.

    Parameters
    ----------
    ship : ManeuveringTrack
        The ship.
    t_s : float
        Time (s).

    Returns
    -------
    bool
        True if some turn has start <= t_s < end.
    """
    return any(a <= t_s < b for a, b, _ in ship.turns)


def simulate_scan(rng: np.random.Generator, sonar: BistaticSonar, ship: ManeuveringTrack, t_s: float,
                  target_xy) -> Scan:
    """Simulate one ping: the target echo (with probability pd) and clutter, as points and covariances.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    sonar, ship : BistaticSonar, ManeuveringTrack
        The sonar and the ship towing it.
    t_s : float
        Ping time (s).
    target_xy : array_like, shape (2,)
        True target position [x east, y north] (m).

    Returns
    -------
    Scan
        Points z (m, 2) in m, covariances R (m, 2, 2) in m^2 (J Sigma J^T at the measured inputs), target
        flags, and the measured Tx and Rx positions (m).
    """
    e = sonar.errors
    tx_true, _ = ship.towed(t_s, sonar.tx_cable_m)
    rx_true, phi = ship.towed(t_s, sonar.rx_cable_m)
    # per-ping errors, common to every echo of the ping
    tx_m = tx_true + rng.normal(0.0, e.sigma_position_m, 2)
    rx_m = rx_true + rng.normal(0.0, e.sigma_position_m, 2)
    c_m = sonar.sound_speed_mps + rng.normal(0.0, e.sigma_sound_speed_mps)
    phi_m = phi + rng.normal(0.0, e.sigma_heading_rad) if e.sigma_heading_rad > 0 else phi
    sigma_b = sonar.sigma_bearing_turn_rad if is_turning(ship, t_s) else e.sigma_bearing_rad

    points, times, thetas, flags = [], [], [], []
    if rng.random() < sonar.pd:
        t_true, th_true = bistatic_inputs(np.asarray(target_xy, float), tx_true, rx_true, phi, sonar.sound_speed_mps)
        t_meas = t_true + rng.normal(0.0, e.sigma_time_s)
        th_meas = th_true + rng.normal(0.0, sigma_b)
        p, rr = bistatic_position(t_meas, th_meas, phi_m, c_m, tx_m, rx_m)
        if rr > 0:  # a negative Rx range means the noisy ellipse did not reach the baseline: no point
            points.append(p[None])
            times.append(np.atleast_1d(t_meas))
            thetas.append(np.atleast_1d(th_meas))
            flags.append(np.ones(1, bool))
    clutter = poisson_clutter(rng, sonar.clutter_density_per_m2, sonar.region)
    if len(clutter):
        # a clutter echo is reported as the processor would report an echo from that point
        t_c, th_c = bistatic_inputs(clutter, tx_m, rx_m, phi_m, c_m)
        points.append(clutter)
        times.append(t_c)
        thetas.append(th_c)
        flags.append(np.zeros(len(clutter), bool))
    if not points:
        return Scan(t_s, np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0, bool), tx_m, rx_m)
    z = np.concatenate(points)
    tt = np.concatenate(times)
    th = np.concatenate(thetas)
    rep = sonar.reported_errors or e
    R = bistatic_covariance(tt, th, phi_m, c_m, tx_m, rx_m, rep.variances())
    return Scan(t_s, z, R, np.concatenate(flags), tx_m, rx_m)
