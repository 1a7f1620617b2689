"""``sonartrack simulate``'s files: the scene's recording, navigation and truth, and a sample input for every
other command (the data: run.py; the scene: sim/scene.py).

Written into the output folder, each atomically (io/atomic.py):

==================== =====================================================================================
recording.wav        N channels (element 1 = front), 32-bit float samples = pressure in pascals, written
                     block by block (memory does not grow with the duration; io/recording_writer.py: RF64
                     past 4 GiB); ``--format``, ``--split-s``, ``--gap-s``, ``--nmea``: recording_layout.py
                     (24-bit WAV or FLAC with calibration.toml, a folder of consecutive files, nav.nmea)
pair.wav             elements ``samples.pair_elements`` (default 1 and 9: 8 spacings = 20 m apart) of the
                     same recording, for ``sonartrack bearings --spacing 20``
nav.csv              time_s, x_m, y_m, heading_deg (ownship), array_x_m, array_y_m, array_heading_deg
                     (array centre and axis), every second
truth.csv            per second and ship: time_s, ship, x_m, y_m, vx_mps, vy_mps, bearing_deg (true, from
                     the array centre), cone_deg (from the array axis, 0 = ahead), side, range_m,
                     range_rate_mps, snr_db (broadband, per element, in the band), tonal_hz (received),
                     tonal_snr_db (per element, in 1 Hz)
scene.toml           the resolved scene (``--scene`` reads it back)
contacts.csv         active bistatic contacts as points with covariances (``track --contacts``)
raw.csv, raw_nav.csv the same contacts raw (travel time, bearing) and the Tx/Rx navigation (``--nav``)
frames.npy           K x Nr x Nd range-Doppler frames with one target (``detect --frames``)
brg.csv, own.csv     one ship's bearings, frequency and SNR, and the array's track (``tma``)
ctd.csv              the environment's sound-speed profile (``tl --profile``)
==================== =====================================================================================

All or nothing: the recording's size is checked against the 4 GiB of a WAV file and the free disk before anything
is written (:func:`check_recording_fits`), and a run that fails or is interrupted removes every file it wrote
(io/run_outputs.py); scene.toml, written last, marks a complete scene.
"""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import to_commented_toml
from sonartrack.io.atomic import write_csv, write_text
from sonartrack.io.run_outputs import check_out_path, discard_on_failure
from sonartrack.io.wav_writer import WAV_FORMATS
from sonartrack.sim.scene import PassiveSceneSettings, scenes_dir

#: what ``--only`` may ask for
ONLY = ("all", "passive", "samples")
CSV_FLOAT = "%.7g"
#: sample format of recording.wav and pair.wav (pressure in Pa as 32-bit floats)
SAMPLE_FORMAT = "float32"


def check_only(only: str) -> None:
    """Refuse an ``--only`` that is not all, passive or samples.

    Parameters
    ----------
    only : str
        What to write.
    """
    require(only in ONLY, f"unknown --only '{only}': choose {', '.join(ONLY)}")


def shipped_scene_path(name_or_path) -> Path:
    """A scene file: the path as given if it exists, else a shipped scene by name (``passive``).

    Parameters
    ----------
    name_or_path : str or path-like
        A TOML file, or the name of a shipped scene.

    Returns
    -------
    Path
        The scene file to read.
    """
    p = Path(name_or_path)
    if p.is_file() or p.suffix.lower() == ".toml":
        return p
    shipped = scenes_dir() / f"{p.name}.toml"
    names = sorted(q.stem for q in scenes_dir().glob("*.toml"))
    require(shipped.is_file(), f"no scene file {p}: give a TOML file, or one of the shipped scenes {names}")
    return shipped


@dataclass
class SceneFiles:
    """What :func:`write_scene` wrote: the paths, and a one-line summary of the scene."""

    folder: Path
    paths: list[Path] = field(default_factory=list)
    summary: str = ""


def write_scene(scene: PassiveSceneSettings, out, *, only: str = "all", progress=None, cache=None,
                layout=None) -> SceneFiles:
    """Simulate the scene and write its files into ``out`` (module doc).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    out : path-like
        Output folder (made if missing).
    only : str
        all | passive (recording, nav, truth) | samples (the other commands' inputs).
    progress : object, optional
        Gets ``start(label, total, done)`` and ``advance(n)`` per recording block.
    cache : path-like, optional
        The RAM field cache folder (io/environment.py ``cache_dir``).
    layout : RecordingLayout, optional
        The recording's format and files (recording_layout.py); default: one float32 recording.wav.

    Returns
    -------
    SceneFiles
        The files written and the scene's one-line summary.
    """
    from sonartrack.io.environment import TLDiskCache
    from sonartrack.systems.simulate.run import scene_summary

    check_only(only)
    folder = check_out_path(out)
    check_recording_fits(scene, only, folder, layout)
    files = SceneFiles(folder)
    store = TLDiskCache(cache) if scene.propagation == "ram" else None
    with discard_on_failure(folder):  # all the files or none: a failed run leaves no scene.toml beside nothing
        if only in ("all", "passive"):
            files.paths += write_passive_files(scene, folder, progress=progress, store=store, layout=layout)
        if only in ("all", "samples"):
            files.paths += write_sample_files(scene, folder, store=store)
        files.summary = scene_summary(scene, store)
        files.paths.insert(0, write_text(folder / "scene.toml", to_commented_toml(scene)))
    return files


def recording_bytes(scene: PassiveSceneSettings, sample_format: str = SAMPLE_FORMAT) -> int:
    """Size of recording.wav's data: samples x channels x bytes per sample.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (duration in s, sample rate in Hz, elements).
    sample_format : str
        A format of io/wav_writer.py (``float32``, ``int16``).

    Returns
    -------
    int
        Bytes of the data chunk.
    """
    bits = WAV_FORMATS[sample_format][2]
    return round(scene.duration_s * scene.sample_rate_hz) * scene.array.elements * bits // 8


def check_recording_fits(scene: PassiveSceneSettings, only: str, folder: Path, layout=None) -> None:
    """Refuse, before anything is written, a layout the scene cannot have (recording_layout.py ``check_layout``:
    FLAC of more than 8 channels, a gap without a second file) or a recording the disk under ``folder`` has no
    room for, with the longest duration that fits. A recording past the 4 GiB of a WAV file is written as RF64.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    only : str
        What is written (``samples`` writes no recording).
    folder : Path
        The output folder (it or its nearest existing parent gives the free space).
    layout : RecordingLayout, optional
        The recording's format and files (default: one float32 WAV).
    """
    import shutil

    from sonartrack.systems.simulate.recording_layout import RecordingLayout, check_layout

    if only == "samples":
        return
    check_layout(layout or RecordingLayout(), scene.array.elements, scene.duration_s)
    need = recording_bytes(scene)  # float32: at least the bytes of 24-bit or FLAC samples
    existing = next(p for p in (folder, *folder.absolute().parents) if p.exists())
    free = shutil.disk_usage(existing).free
    total = need * (1 + 2 / scene.array.elements)  # recording.wav and pair.wav
    require(total <= free, f"recording.wav and pair.wav need {total / 1e9:.2f} GB but {existing} has "
                           f"{free / 1e9:.2f} GB free: free some space, or give a shorter --duration-s "
                           f"({int(free // (total / scene.duration_s))} s would fit)")


def write_passive_files(scene: PassiveSceneSettings, folder: Path, *, progress=None, store=None,
                        layout=None) -> list[Path]:
    """Write the recording (recording.wav, or as ``layout`` says: recording_layout.py) and pair.wav block by
    block, nav.csv and truth.csv, and the layout's calibration.toml and nav.nmea.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    folder : Path
        Output folder (existing).
    progress : object, optional
        As :func:`write_scene`'s.
    store : FieldStore, optional
        Cache of RAM transmission-loss fields.
    layout : RecordingLayout, optional
        The recording's format and files.

    Returns
    -------
    list of Path
        The files written.
    """
    import pandas as pd

    from sonartrack.io.recording_writer import recording_writer
    from sonartrack.systems.simulate.recording_layout import RecordingLayout, layout_writer, write_layout_extras
    from sonartrack.systems.simulate.run import simulate_passive

    sim = simulate_passive(scene, store)
    pair = [e - 1 for e in scene.samples.pair_elements]
    fs = scene.sample_rate_hz
    layout = layout or RecordingLayout()
    frames = round(scene.duration_s * fs)
    if progress is not None:
        progress.start("simulate recording", sim.plan.n_blocks, 0)
    with ExitStack() as stack:  # each file atomic: complete when the stack closes, removed if it fails
        rec = layout_writer(stack, folder, layout, scene.array.elements, fs, frames)
        two = stack.enter_context(recording_writer(folder / "pair.wav", 2, fs, SAMPLE_FORMAT, expected_frames=frames))
        for block in sim.recording_blocks():
            rec.write(block)
            two.write(block[pair])
            if progress is not None:
                progress.advance(1)
    nav = write_csv(pd.DataFrame(sim.nav), folder / "nav.csv", float_format=CSV_FLOAT)
    truth_csv = write_csv(pd.DataFrame(sim.truth), folder / "truth.csv", float_format=CSV_FLOAT)
    return [*rec.paths, folder / "pair.wav", nav, truth_csv, *write_layout_extras(folder, layout, sim.nav, scene)]


def write_sample_files(scene: PassiveSceneSettings, folder: Path, *, store=None) -> list[Path]:
    """Write contacts.csv, raw.csv, raw_nav.csv, frames.npy, brg.csv, own.csv (with ships) and ctd.csv.

    Parameters
    ----------
    scene, folder, store
        The scene, the output folder (existing) and the cache of RAM transmission-loss fields (optional), as
        :func:`write_passive_files`.

    Returns
    -------
    list of Path
        The files written.
    """
    import pandas as pd

    from sonartrack.io.atomic import write_bytes
    from sonartrack.systems.simulate.run import simulate_samples

    s = simulate_samples(scene, store)
    paths = [write_csv(pd.DataFrame(s.contacts[key]), folder / name, float_format=CSV_FLOAT)
             for key, name in (("cartesian", "contacts.csv"), ("raw", "raw.csv"), ("nav", "raw_nav.csv"))]
    paths.append(write_bytes(folder / "frames.npy", _npy_bytes(s.frames)))
    if s.bearings["time_s"].size:
        paths.append(write_csv(pd.DataFrame(s.bearings), folder / "brg.csv", float_format=CSV_FLOAT))
        paths.append(write_csv(pd.DataFrame(s.ownship), folder / "own.csv", float_format=CSV_FLOAT))
    paths.append(write_csv(pd.DataFrame(s.ctd), folder / "ctd.csv", float_format=CSV_FLOAT))
    return paths


def _npy_bytes(array: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()
