"""The simulate system's run functions: a scene's settings in, its data as typed records of arrays out.

* :func:`simulate_passive` -- the recording (pressure in Pa on every element, drawn block by block when
  :meth:`PassiveSimulation.recording_blocks` is iterated: memory does not grow with the duration), the
  navigation and the truth tables (sim/array_signals.py, sim/passive_scene.py);
* :func:`simulate_samples` -- a sample input for every other command (sim/sample_inputs.py);
* :func:`scene_summary` -- the scene in one line, with each ship's SNR per element.

Each output draws from its own child stream of the scene's seed (:data:`STREAMS`), so ``--only samples``
gives the same samples as a full run.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sonartrack.sim.array_signals import BlockPlan
from sonartrack.sim.scene import PassiveSceneSettings

if TYPE_CHECKING:
    from sonartrack.acoustics.transmission_loss import FieldStore

#: the seed's child streams of each output (so `--only samples` gives the same samples as a full run)
STREAMS = {"recording": 0, "contacts": 1, "frames": 2, "tma": 3}


@dataclass(frozen=True, slots=True)
class PassiveSimulation:
    """The passive scene's data: the recording's block plan, and the navigation and truth as columns.

    ``nav``: time_s, x_m, y_m, heading_deg (ownship), array_x_m, array_y_m, array_heading_deg, every second;
    ``truth``: per second and ship, position (m), velocity (m/s), bearing and cone angle (deg), range (m),
    range rate (m/s), SNR (dB), received tonal (Hz). The recording itself comes from :meth:`recording_blocks`.
    """

    scene: PassiveSceneSettings
    plan: BlockPlan
    nav: dict[str, np.ndarray]
    truth: dict[str, np.ndarray]
    store: FieldStore | None = None

    def recording_blocks(self) -> Iterator[np.ndarray]:
        """The recording, block by block.

        Returns
        -------
        iterator of numpy.ndarray, shape (elements, m)
            Pressure (Pa) on every element (element 1 = front), ``plan.n_blocks`` blocks.
        """
        from sonartrack.core.random import trial_rng
        from sonartrack.sim.array_signals import array_blocks

        rng = trial_rng(self.scene.seed, STREAMS["recording"])
        return array_blocks(self.scene, rng, self.store, plan=self.plan)


@dataclass(frozen=True, slots=True)
class SampleInputs:
    """A sample input for every other command, as columns (units in the names).

    ``contacts``: the active bistatic contacts, tables ``cartesian`` (points with covariances), ``raw``
    (travel times and bearings) and ``nav`` (Tx/Rx navigation); ``frames`` (K, Nr, Nd) square-law range-Doppler
    cells; ``bearings`` and ``ownship`` one ship's bearings (+ frequency, SNR) and the array's track (empty
    without ships); ``ctd`` the environment's sound-speed profile.
    """

    contacts: dict[str, dict[str, np.ndarray]]
    frames: np.ndarray
    bearings: dict[str, np.ndarray]
    ownship: dict[str, np.ndarray]
    ctd: dict[str, np.ndarray]


def table_times(duration_s: float) -> np.ndarray:
    """The times of the navigation and truth tables: every second, and the recording's end.

    Parameters
    ----------
    duration_s : float
        Length of the recording (s).

    Returns
    -------
    numpy.ndarray
        Times (s) from 0, a second apart, ending at ``duration_s``.
    """
    t = np.arange(0.0, np.floor(duration_s) + 1.0)
    if t[-1] < duration_s:  # the tables cover the whole recording
        t = np.append(t, duration_s)
    return t


def simulate_passive(scene: PassiveSceneSettings, store=None) -> PassiveSimulation:
    """The passive scene: the recording's plan, the navigation and the truth.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    store : FieldStore, optional
        Cache of RAM transmission-loss fields (``propagation = "ram"``).

    Returns
    -------
    PassiveSimulation
        The plan and tables; the recording is drawn when its blocks are iterated.
    """
    from sonartrack.sim.array_signals import plan_blocks
    from sonartrack.sim.passive_scene import nav_columns, received_levels, scene_geometry, truth_columns

    plan = plan_blocks(scene, store)
    g = scene_geometry(scene, table_times(scene.duration_s))
    truth = truth_columns(scene, g, received_levels(scene, g, store))
    return PassiveSimulation(scene, plan, nav_columns(g), truth, store)


def simulate_samples(scene: PassiveSceneSettings, store=None) -> SampleInputs:
    """The sample inputs of the other commands, made from the scene.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (``scene.samples`` holds the samples' own settings).
    store : FieldStore, optional
        Cache of RAM transmission-loss fields (``propagation = "ram"``).

    Returns
    -------
    SampleInputs
        Contacts, frames, bearings + ownship and the sound-speed profile.
    """
    from sonartrack.core.random import trial_rng
    from sonartrack.sim import sample_inputs as si

    contacts = si.bistatic_contacts(scene, trial_rng(scene.seed, STREAMS["contacts"]))
    frames, _ = si.range_doppler_frames(scene, trial_rng(scene.seed, STREAMS["frames"]))
    bearings, own = si.tma_record(scene, trial_rng(scene.seed, STREAMS["tma"]), store)
    return SampleInputs(contacts, frames, bearings, own, si.ctd_profile(scene))


def scene_summary(scene: PassiveSceneSettings, store=None) -> str:
    """One line: duration, array, and each ship's per-element broadband SNR range over the recording.

    Parameters
    ----------
    scene, store
        The scene and the cache of RAM transmission-loss fields (optional), as :func:`simulate_passive`.

    Returns
    -------
    str
        The line (SNR in dB per element, in the band).
    """
    from sonartrack.sim.passive_scene import received_levels, scene_geometry

    t = np.linspace(0.0, scene.duration_s, 61)
    lv = received_levels(scene, scene_geometry(scene, t), store)
    snr = lv.broadband_db - scene.noise_level_db
    ships = ", ".join(f"{s.name} {snr[i].min():+.0f}..{snr[i].max():+.0f}" for i, s in enumerate(scene.ships))
    return (f"{scene.duration_s:g} s at {scene.sample_rate_hz:g} Hz, {scene.array.elements} elements "
            f"{scene.spacing_m:g} m apart, {scene.propagation} TL, {len(scene.ships)} ship(s)"
            + (f" (SNR per element, dB: {ships})" if ships else " (noise only)"))
