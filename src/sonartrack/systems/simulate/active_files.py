"""``sonartrack simulate --kind active``: an active towed-array scene's pings, navigation and truth on files.

The simulator is sim/active_scene.py (settings, geometry, truth) and sim/active_signals.py (the samples); the
file layout, writers and readers are systems/active/scene_files.py (the active system reads them; it may not
import the simulator, so the writing that drives it lives here). Ping k (0-based) draws from the seed's child
stream k (core/random.py ``trial_rng``): any ping can be re-simulated alone, bit for bit.
"""

from __future__ import annotations

import os
import re
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from sonartrack.core.settings import to_commented_toml
from sonartrack.io.atomic import atomic_path
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
    """Simulate the scene and write its files into ``out_dir``, all or none (systems/active/scene_files.py lists
    them).

    Each file is written to its hidden temporary beside it (io/atomic.py ``atomic_path``), and all are renamed over
    their names only when the last is complete, the ping table (the scene's index) last of all: a failed or
    interrupted run leaves ``out_dir`` as it was, and a scene written over an earlier one replaces it whole (the
    earlier run's ping files, listed in its ping table and named as this module names them, are removed; nothing
    else is touched). The temporaries of a killed run (SIGKILL: nothing could clean up) are removed by the next run
    into the folder (:func:`_remove_stale_temporaries`).

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
        The files written: the ping table, the ping files, nav.csv, truth.csv, scene.toml.
    """
    from sonartrack.systems.active import scene_files as sf

    folder = Path(out_dir)
    pings = folder / sf.PING_DIR
    made = not pings.exists()
    pings.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(folder)
    previous = _previous_pings(folder)
    try:
        with ExitStack() as stack:  # every file's temporary, renamed in reverse order when the block completes
            paths = _write_temporaries(settings, folder, _Temporaries(stack), progress, store)
    except BaseException:
        if made and pings.is_dir() and not any(pings.iterdir()):
            pings.rmdir()
        raise
    for p in set(previous) - set(paths):
        p.unlink(missing_ok=True)
    return paths


class _Temporaries:
    """``(path, content)``: write ``content`` (str or bytes) to the temporary of ``path`` (io/atomic.py
    ``atomic_path``), renamed over ``path`` when ``stack`` closes without an error; a failed write in one line
    naming ``path``."""

    def __init__(self, stack: ExitStack):
        self.stack = stack

    def __call__(self, path: Path, content) -> None:
        from sonartrack.systems.active.scene_files import write_error

        tmp = self.stack.enter_context(atomic_path(path))
        try:
            tmp.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
        except OSError as exc:
            raise write_error(exc, path) from None


def _write_temporaries(settings: ActiveSceneSettings, folder: Path, temporary: _Temporaries, progress,
                       store) -> list[Path]:
    """Simulate and write each file of the scene with ``temporary`` (the ping table first: it is renamed last);
    returns the final paths."""
    from sonartrack.core.random import trial_rng
    from sonartrack.sim.active_scene import nav_columns, ping_geometry, platforms, target_truth, transmission_loss_model
    from sonartrack.sim.active_signals import ping_samples
    from sonartrack.systems.active import scene_files as sf

    table = ping_table_columns(settings)
    temporary(folder / sf.PING_TABLE, sf.table_text(table))
    tl = transmission_loss_model(settings, store)
    plat = ping_geometry(settings)
    if progress is not None:
        progress.start("simulate pings", plat.time_s.size, 0)
    for k in range(plat.time_s.size):
        samples = ping_samples(settings, plat, k, tl, trial_rng(settings.seed, k))
        temporary(folder / sf.ping_file(k + 1), sf.ping_bytes(samples))
        if progress is not None:
            progress.advance(1)
    t_nav = np.arange(0.0, np.floor(settings.duration_s) + 1.0)
    files = {sf.NAV_FILE: sf.table_text(nav_columns(platforms(settings, t_nav))),
             sf.TRUTH_FILE: sf.table_text(target_truth(settings, tl, plat)), sf.SCENE_FILE: to_commented_toml(settings)}
    for name, text in files.items():
        temporary(folder / name, text)
    return [folder / sf.PING_TABLE, *(folder / f for f in table["file"]), *(folder / name for name in files)]


#: the temporaries io/atomic.py's atomic_path makes of this module's files: .NAME.PID.tmp.SUFFIX
_TEMPORARY = re.compile(r"\.(ping_\d{4,}|ping_table|nav|truth|scene)\.(\d+)\.tmp\.(npy|csv|toml)")


def _remove_stale_temporaries(folder: Path) -> None:
    """Remove the temporaries (:data:`_TEMPORARY`) of this module's files in ``folder`` and its pings/ that a run
    whose process is gone left (killed with SIGKILL)."""
    from sonartrack.systems.active import scene_files as sf

    for d in (folder, folder / sf.PING_DIR):
        for p in d.iterdir() if d.is_dir() else ():
            m = _TEMPORARY.fullmatch(p.name)
            if m and p.is_file() and not _alive(int(m.group(2))):
                p.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (one we may not signal runs too)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _previous_pings(folder: Path) -> list[Path]:
    """The ping files an earlier scene in ``folder`` listed in its ping table, only names of the form this module
    writes (pings/ping_NNNN.npy: a file named otherwise is not ours to remove); none without a readable table."""
    from sonartrack.systems.active import scene_files as sf

    table = folder / sf.PING_TABLE
    if not table.is_file():
        return []
    try:
        import pandas as pd

        names = pd.read_csv(table, usecols=["file"])["file"].astype(str)
    except Exception:  # an unreadable table names no file of ours
        return []
    return [folder / n for n in names if re.fullmatch(rf"{sf.PING_DIR}/ping_\d{{4,}}\.npy", n)]


def write_active(settings: ActiveSceneSettings, out, *, progress=None, cache=None) -> tuple[list[Path], str]:
    """``sonartrack simulate --kind active``: the scene's files in ``out``, all or none (:func:`write_active_scene`),
    and its one-line summary.

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
    from sonartrack.io.run_outputs import check_out_path

    folder = check_out_path(out)
    store = TLDiskCache(cache) if settings.propagation == "ram" else None
    paths = write_active_scene(settings, folder, progress=progress, store=store)
    return paths, active_scene_summary(settings)


def active_scene_summary(settings: ActiveSceneSettings) -> str:
    """One line on the scene ``settings``: pings, waveform, array, and each target's echo SNR (dB) range over the
    scene (only with spherical propagation)."""
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
