"""``sonartrack simulate --kind active``: an active towed-array scene's pings, navigation and truth on files.

The simulator is sim/active_scene.py (settings, geometry, truth) and sim/active_signals.py (the samples); the
file layout, writers and readers are systems/active/scene_files.py (the active system reads them; it may not
import the simulator, so the writing that drives it lives here). Ping k (0-based) draws from the seed's child
stream k (core/random.py ``trial_rng``): any ping can be re-simulated alone, bit for bit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.settings import to_commented_toml
from sonartrack.io.atomic import write_text
from sonartrack.sim.active_scene import ActiveSceneSettings


def ping_table_columns(scene: ActiveSceneSettings) -> dict:
    """The ping table's columns (systems/active/scene_files.py) of the scene's pings.

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (ping times, waveform, sample rate, array).

    Returns
    -------
    dict
        Column name -> one value per ping (``PING_TABLE_COLUMNS``; pings numbered from 1, times s, frequencies
        Hz, bandwidth 0 for a CW).
    """
    from sonartrack.systems.active.scene_files import ping_file

    t = scene.ping_times_s
    n = t.size
    w = scene.waveform
    ping = np.arange(1, n + 1)
    return {"ping": ping, "transmit_time_s": t, "file": [ping_file(p) for p in ping], "waveform": [w.kind] * n,
            "fc_hz": np.full(n, w.carrier_hz), "bandwidth_hz": np.full(n, w.bandwidth_hz if w.kind == "lfm" else 0.0),
            "duration_s": np.full(n, w.duration_s), "fs_hz": np.full(n, scene.sample_rate_hz),
            "channels": np.full(n, scene.sonar.elements), "samples": np.full(n, scene.samples_per_ping)}


def write_active_scene(settings: ActiveSceneSettings, out_dir, progress=None, store=None) -> list[Path]:
    """Simulate the scene and write its files into ``out_dir`` (systems/active/scene_files.py lists them).

    Parameters
    ----------
    settings : ActiveSceneSettings
        The scene (sim/active_scene.py).
    out_dir : str or path-like
        Output folder (created).
    progress : optional
        Gets ``start(label, total, done)`` once and ``advance(1)`` after each ping.
    store : optional
        RAM field store (io/environment.py ``TLDiskCache``) when ``settings.propagation`` is ram.

    Returns
    -------
    list of Path
        The files written: scene.toml, the ping files, ping_table.csv, nav.csv, truth.csv.
    """
    from sonartrack.core.random import trial_rng
    from sonartrack.sim.active_scene import nav_columns, ping_geometry, platforms, target_truth, transmission_loss_model
    from sonartrack.sim.active_signals import ping_samples
    from sonartrack.systems.active import scene_files as sf

    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [write_text(folder / sf.SCENE_FILE, to_commented_toml(settings))]
    tl = transmission_loss_model(settings, store)
    plat = ping_geometry(settings)
    if progress is not None:
        progress.start("simulate pings", plat.time_s.size, 0)
    for k in range(plat.time_s.size):
        paths.append(sf.write_ping(folder, k + 1, ping_samples(settings, plat, k, tl, trial_rng(settings.seed, k))))
        if progress is not None:
            progress.advance(1)
    paths.append(sf.write_table(ping_table_columns(settings), folder / sf.PING_TABLE))
    t_nav = np.arange(0.0, np.floor(settings.duration_s) + 1.0)
    paths.append(sf.write_table(nav_columns(platforms(settings, t_nav)), folder / sf.NAV_FILE))
    paths.append(sf.write_table(target_truth(settings, tl, plat), folder / sf.TRUTH_FILE))
    return paths


def write_active(settings: ActiveSceneSettings, out, *, progress=None, cache=None) -> tuple[list[Path], str]:
    """``sonartrack simulate --kind active``: the scene's files in ``out``, all or none, and its one-line summary.

    Parameters
    ----------
    settings : ActiveSceneSettings
        The scene.
    out : path-like
        Output folder (made if missing; a failed or interrupted run leaves none of its files).
    progress : optional
        Gets ``start(label, total, done)`` once and ``advance(1)`` after each ping.
    cache : path-like, optional
        The RAM field cache folder (io/environment.py ``cache_dir``), used when ``settings.propagation`` is ram.

    Returns
    -------
    tuple of (list of Path, str)
        The files written and the scene's summary line.
    """
    from sonartrack.io.environment import TLDiskCache
    from sonartrack.io.run_outputs import check_out_path, discard_on_failure

    folder = check_out_path(out)
    store = TLDiskCache(cache) if settings.propagation == "ram" else None
    with discard_on_failure(folder):
        paths = write_active_scene(settings, folder, progress=progress, store=store)
    return paths, active_scene_summary(settings)


def active_scene_summary(settings: ActiveSceneSettings) -> str:
    """One line: pings, waveform, array, and each target's echo SNR range over the scene.

    Parameters
    ----------
    settings : ActiveSceneSettings
        The scene.

    Returns
    -------
    str
        The summary; the echo SNR (dB) of each target only with spherical propagation.
    """
    from sonartrack.sim.active_scene import target_truth, transmission_loss_model

    w = settings.waveform
    truth = target_truth(settings, transmission_loss_model(settings)) if settings.propagation == "spherical" else None
    parts = []
    for tgt in settings.targets if truth is not None else []:
        snr = truth["snr_db"][truth["target"] == tgt.name]
        parts.append(f"{tgt.name} {snr.min():+.0f}..{snr.max():+.0f}")
    return (f"{settings.ping_times_s.size} pings every {settings.ping_interval_s:g} s, {w.kind.upper()} "
            f"{w.duration_s:g} s at {w.carrier_hz:g} Hz, {settings.sonar.elements} elements "
            f"{settings.spacing_m:g} m apart, {len(settings.targets)} target(s)"
            + (f" (echo SNR dB: {', '.join(parts)})" if parts else ""))
