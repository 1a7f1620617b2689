"""``sonartrack simulate``'s files: the scene's recording, navigation and truth, and a sample input for every
other command (the scene: sim/scene.py; the signals: sim/array_signals.py; the samples: sim/sample_inputs.py).

Written into the output folder, each atomically (io/atomic.py):

===================  ======================================================================================
recording.wav        N channels (element 1 = front), 32-bit float samples = pressure in pascals, written
                     block by block (memory does not grow with the duration)
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
===================  ======================================================================================

WAV format: RIFF/WAVE, format tag 3 (IEEE float) with 32-bit samples, or tag 1 with 16-bit PCM at a stated
full scale (``WavBlockWriter``); the sizes in the header are written when the file is closed. A RIFF file
holds at most 4 GiB: a longer recording is refused with the fix (int16 or a shorter duration).
"""

from __future__ import annotations

import struct
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.core.settings import to_commented_toml
from sonartrack.io.atomic import atomic_path, write_csv, write_text
from sonartrack.sim.scene import PassiveSceneSettings, scenes_dir

#: largest data chunk of a RIFF file (bytes)
RIFF_MAX_BYTES = 2**32 - 1 - 36
#: sample formats: numpy dtype, WAVE format tag, bits per sample
WAV_FORMATS = {"float32": ("<f4", 3, 32), "int16": ("<i2", 1, 16)}
#: the seed's child streams of each output (so `--only samples` gives the same samples as a full run)
STREAMS = {"recording": 0, "contacts": 1, "frames": 2, "tma": 3}
#: what ``--only`` may ask for
ONLY = ("all", "passive", "samples")
CSV_FLOAT = "%.7g"


class WavBlockWriter:
    """Append (channels, m) blocks to an open binary file as WAV; :meth:`close` writes the header's sizes.

    ``float32`` stores the values as given; ``int16`` stores round(32767 x / full_scale), clipped (the
    scale is stated by the caller: a value of ``full_scale`` is the largest sample)."""

    def __init__(self, fh, n_channels: int, sample_rate_hz: float, sample_format: str = "float32",
                 full_scale: float = 1.0):
        require(sample_format in WAV_FORMATS, f"unknown WAV sample format '{sample_format}': float32 or int16")
        self._fh, self.n_channels, self.full_scale = fh, int(n_channels), float(full_scale)
        self._dtype, tag, bits = WAV_FORMATS[sample_format]
        self.frames_written, self.blocks_written = 0, 0
        block_align = self.n_channels * bits // 8
        fmt = struct.pack("<HHIIHH", tag, self.n_channels, int(round(sample_rate_hz)),
                          int(round(sample_rate_hz)) * block_align, block_align, bits)
        fh.write(b"RIFF" + struct.pack("<I", 0) + b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt
                 + b"data" + struct.pack("<I", 0))
        self._bytes_per_frame = block_align

    def write(self, block) -> None:
        """Append a block of shape (channels, m)."""
        x = np.asarray(block)
        require(x.ndim == 2 and x.shape[0] == self.n_channels,
                f"a WAV block must be ({self.n_channels}, m) samples, got {x.shape}")
        if self._dtype == "<i2":
            x = np.clip(np.round(x * (32767.0 / self.full_scale)), -32768, 32767)
        data = np.ascontiguousarray(x.T, dtype=self._dtype).tobytes()
        if (self.frames_written + x.shape[1]) * self._bytes_per_frame > RIFF_MAX_BYTES:
            raise InputError("the recording would exceed the 4 GiB limit of a WAV file: shorten --duration-s or "
                             "use fewer elements")
        self._fh.write(data)
        self.frames_written += x.shape[1]
        self.blocks_written += 1

    def close(self) -> None:
        """Write the RIFF and data chunk sizes."""
        n_data = self.frames_written * self._bytes_per_frame
        self._fh.seek(4)
        self._fh.write(struct.pack("<I", 36 + n_data))
        self._fh.seek(40)
        self._fh.write(struct.pack("<I", n_data))
        self._fh.seek(0, 2)


@contextmanager
def wav_block_writer(path, n_channels: int, sample_rate_hz: float, sample_format: str = "float32",
                     full_scale: float = 1.0):
    """A :class:`WavBlockWriter` on ``path``, written atomically: the file appears, complete, when the block ends."""
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        writer = WavBlockWriter(fh, n_channels, sample_rate_hz, sample_format, full_scale)
        yield writer
        writer.close()


def check_only(only: str) -> None:
    """``--only`` must be all, passive or samples."""
    require(only in ONLY, f"unknown --only '{only}': choose {', '.join(ONLY)}")


def shipped_scene_path(name_or_path) -> Path:
    """A scene file: the path as given if it exists, else a shipped scene by name (``passive``)."""
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


def write_scene(scene: PassiveSceneSettings, out, *, only: str = "all", progress=None, cache=None) -> SceneFiles:
    """Simulate the scene and write its files into ``out`` (module doc); ``only`` = all | passive | samples.

    ``progress`` (optional) gets ``start(label, total, done)`` and ``advance(n)`` per recording block;
    ``cache`` is the RAM field cache folder (io/environment.py ``cache_dir``)."""
    from sonartrack.io.environment import TLDiskCache

    check_only(only)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    files = SceneFiles(folder)
    store = TLDiskCache(cache) if scene.propagation == "ram" else None
    files.paths.append(write_text(folder / "scene.toml", to_commented_toml(scene)))
    if only in ("all", "passive"):
        files.paths += write_passive_files(scene, folder, progress=progress, store=store)
    if only in ("all", "samples"):
        files.paths += write_sample_files(scene, folder, store=store)
    files.summary = scene_summary(scene, store)
    return files


def write_passive_files(scene: PassiveSceneSettings, folder: Path, *, progress=None, store=None) -> list[Path]:
    """recording.wav, pair.wav (block by block), nav.csv and truth.csv."""
    import pandas as pd

    from sonartrack.core.random import trial_rng
    from sonartrack.sim.array_signals import array_blocks, plan_blocks
    from sonartrack.sim.passive_scene import nav_columns, received_levels, scene_geometry, truth_columns

    plan = plan_blocks(scene, store)
    pair = [e - 1 for e in scene.samples.pair_elements]
    fs = scene.sample_rate_hz
    if progress is not None:
        progress.start("simulate recording.wav", plan.n_blocks, 0)
    with ExitStack() as stack:
        rec = stack.enter_context(wav_block_writer(folder / "recording.wav", scene.array.elements, fs))
        two = stack.enter_context(wav_block_writer(folder / "pair.wav", 2, fs))
        for block in array_blocks(scene, trial_rng(scene.seed, STREAMS["recording"]), store, plan=plan):
            rec.write(block)
            two.write(block[pair])
            if progress is not None:
                progress.advance(1)
    t = np.arange(0.0, np.floor(scene.duration_s) + 1.0)
    if t[-1] < scene.duration_s:  # the tables cover the whole recording
        t = np.append(t, scene.duration_s)
    g = scene_geometry(scene, t)
    nav = write_csv(pd.DataFrame(nav_columns(g)), folder / "nav.csv", float_format=CSV_FLOAT)
    truth = truth_columns(scene, g, received_levels(scene, g, store))
    truth_csv = write_csv(pd.DataFrame(truth), folder / "truth.csv", float_format=CSV_FLOAT)
    return [folder / "recording.wav", folder / "pair.wav", nav, truth_csv]


def write_sample_files(scene: PassiveSceneSettings, folder: Path, *, store=None) -> list[Path]:
    """contacts.csv, raw.csv, raw_nav.csv, frames.npy, brg.csv, own.csv and ctd.csv (module doc)."""
    import pandas as pd

    from sonartrack.core.random import trial_rng
    from sonartrack.io.atomic import write_bytes
    from sonartrack.sim import sample_inputs as si

    tables = si.bistatic_contacts(scene, trial_rng(scene.seed, STREAMS["contacts"]))
    paths = [write_csv(pd.DataFrame(tables[key]), folder / name, float_format=CSV_FLOAT)
             for key, name in (("cartesian", "contacts.csv"), ("raw", "raw.csv"), ("nav", "raw_nav.csv"))]
    frames, _ = si.range_doppler_frames(scene, trial_rng(scene.seed, STREAMS["frames"]))
    paths.append(write_bytes(folder / "frames.npy", _npy_bytes(frames)))
    bearings, own = si.tma_record(scene, trial_rng(scene.seed, STREAMS["tma"]), store)
    if bearings["time_s"].size:
        paths.append(write_csv(pd.DataFrame(bearings), folder / "brg.csv", float_format=CSV_FLOAT))
        paths.append(write_csv(pd.DataFrame(own), folder / "own.csv", float_format=CSV_FLOAT))
    paths.append(write_csv(pd.DataFrame(si.ctd_profile(scene)), folder / "ctd.csv", float_format=CSV_FLOAT))
    return paths


def _npy_bytes(array: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()


def scene_summary(scene: PassiveSceneSettings, store=None) -> str:
    """One line: duration, array, and each ship's per-element broadband SNR range over the recording."""
    from sonartrack.sim.passive_scene import received_levels, scene_geometry

    t = np.linspace(0.0, scene.duration_s, 61)
    lv = received_levels(scene, scene_geometry(scene, t), store)
    snr = lv.broadband_db - scene.noise_level_db
    ships = ", ".join(f"{s.name} {snr[i].min():+.0f}..{snr[i].max():+.0f}" for i, s in enumerate(scene.ships))
    return (f"{scene.duration_s:g} s at {scene.sample_rate_hz:g} Hz, {scene.array.elements} elements "
            f"{scene.spacing_m:g} m apart, {scene.propagation} TL, {len(scene.ships)} ship(s)"
            + (f" (SNR per element, dB: {ships})" if ships else " (noise only)"))
