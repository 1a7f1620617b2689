"""The one-way transmission loss of an active scene's two legs, source -> target and target -> array (dB).

Used in the active sonar equation of sim/active_scene.py (RL = SL - TL(r_T) - TL(r_R) + TS; Urick, Principles of
Underwater Sound, ch. 2). ``spherical``: TL = 20 log10 r + alpha r, alpha Thorp's absorption at the carrier.
``ram``: RAM in the shipped environment (acoustics/transmission_loss.py), the Tx leg from the source depth and the
Rx leg from the array depth by reciprocity, both read at each depth the scene needs (its targets' and scatterers'),
averaged over ``tl_average_m`` and tabulated on a range grid out to the longest path a ping can hear
(:func:`max_path_range_m`). The scene is any :class:`~sonartrack.sim.active_scene.ActiveSceneSettings` (read by
attribute: this module does not import it, so that sim/active_scene.py can re-export these names).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sonartrack.sim.active_scene import ActiveSceneSettings

#: RAM transmission loss is tabulated on this range step (m) and out to a whole number of RAM_RANGE_STEP_M
TL_GRID_STEP_M = 10.0
RAM_RANGE_STEP_M = 5_000.0


@dataclass(frozen=True, slots=True)
class TransmissionLoss:
    """One-way TL (dB) of the Tx leg and the Rx leg to each depth used by the scene (module doc)."""

    kind: str
    absorption_db_per_m: float
    ranges_m: np.ndarray
    tx_db: dict
    rx_db: dict

    def tx(self, range_m, depth_m: float) -> np.ndarray:
        """TL from the source to points at ``depth_m`` and ranges (m).

        Parameters
        ----------
        range_m : float or array
            Horizontal ranges from the source (m).
        depth_m : float
            Depth of the points (m); with RAM, one of the depths tabulated for the scene.

        Returns
        -------
        numpy.ndarray
            One-way transmission loss (dB), shaped as ``range_m``.
        """
        return self._leg(self.tx_db, range_m, depth_m)

    def rx(self, range_m, depth_m: float) -> np.ndarray:
        """TL from points at ``depth_m`` to the array (reciprocity: the array as the source), as :meth:`tx` with
        ``range_m`` the horizontal ranges from the array centre (m)."""
        return self._leg(self.rx_db, range_m, depth_m)

    def _leg(self, table: dict, range_m, depth_m: float) -> np.ndarray:
        r = np.asarray(range_m, dtype=float)
        if self.kind == "spherical":
            return 20.0 * np.log10(np.maximum(r, 1.0)) + self.absorption_db_per_m * r
        return np.interp(r, self.ranges_m, table[float(depth_m)])


def max_path_range_m(scene: ActiveSceneSettings) -> float:
    """Longest one-way range that can echo within a ping's window (m): c T / 2 plus the baseline.

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (sound speed c in m/s, ping interval T in s, tow lengths in m).

    Returns
    -------
    float
        The range (m).
    """
    baseline = abs(scene.sonar.array_tow_m - scene.sonar.source_tow_m)
    return scene.sound_speed_mps * scene.ping_interval_s / 2.0 + baseline


def transmission_loss_model(scene: ActiveSceneSettings, store=None) -> TransmissionLoss:
    """The scene's one-way transmission loss (module doc).

    Parameters
    ----------
    scene : ActiveSceneSettings
        Propagation model, environment, depths, carrier.
    store : optional
        RAM field store (acoustics/transmission_loss.py ``FieldStore``), used with ``propagation = "ram"``.

    Returns
    -------
    TransmissionLoss
        TL (dB) of the Tx and Rx legs against range (m), per depth.
    """
    from sonartrack.acoustics.transmission_loss import thorp_absorption_db_per_km

    fc = scene.waveform.carrier_hz
    alpha = float(thorp_absorption_db_per_km(fc)) / 1e3
    if scene.propagation == "spherical":
        return TransmissionLoss("spherical", alpha, np.zeros(0), {}, {})
    from sonartrack.acoustics.environment import load_environment
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field

    env = load_environment(scene.environment)
    rv = scene.reverberation
    depths = sorted({float(t.depth_m) for t in scene.targets} | {rv.boundary.depth_m, rv.volume.depth_m})
    rmax = RAM_RANGE_STEP_M * np.ceil(max_path_range_m(scene) * 1.05 / RAM_RANGE_STEP_M)
    grid = np.arange(0.0, rmax, TL_GRID_STEP_M)
    s = scene.sonar
    fields = {z: tl_field(env, fc, z, rmax_m=rmax, store=store) for z in {s.source_depth_m, s.array_depth_m}}

    def line(source_depth, depth):  # as transmission_loss(): one field per source depth, read at each depth
        f = fields[source_depth]
        tl = f.at_depth(min(depth, float(f.depths_m[-1])))
        if scene.tl_average_m > 0:
            tl = smooth_tl(f.ranges_m, tl, scene.tl_average_m)
        out = np.interp(grid, f.ranges_m, tl)
        near = grid < f.ranges_m[0]
        out[near] = 20.0 * np.log10(np.maximum(grid[near], 1.0))
        return out

    return TransmissionLoss("ram", alpha, grid, {d: line(s.source_depth_m, d) for d in depths},
                            {d: line(s.array_depth_m, d) for d in depths})
