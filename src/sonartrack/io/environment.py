"""Acoustic environments on disk: a user's sound-speed profile file, and the transmission-loss cache.

Profiles (:func:`read_profile`) -> :class:`~sonartrack.acoustics.environment.Environment`. Two
formats: a TOML file with the shipped environments' keys (``depth_m``, ``sound_speed_mps`` or
``temperature_c`` + ``salinity_psu``, optional ``water_depth_m`` and seabed keys), or a CSV with a
``depth_m`` column and ``sound_speed_mps`` (or ``temperature_c`` and ``salinity_psu``) columns. The
water depth is the last depth unless given; the seabed is
:data:`~sonartrack.acoustics.environment.DEFAULT_BOTTOM` unless given. This module only reads the
file; every check of the values is :func:`~sonartrack.acoustics.environment.environment_from_mapping`.

The TL cache (:class:`TLDiskCache`): one ``<key>.npz`` per RAM field in ``$SONARTRACK_CACHE_DIR/tl``
(default ``.sonartrack-cache/tl``), named by :func:`sonartrack.acoustics.transmission_loss.field_key`
(a hash of every input) and written atomically (``io/atomic.py``), so Monte Carlo workers and reruns
share fields and a worker either finds a complete field or computes it. A damaged file reads as
absent and is recomputed and replaced. :func:`cached_tl_field` is
:func:`~sonartrack.acoustics.transmission_loss.tl_field` through this cache.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from sonartrack.acoustics.environment import Environment, environment_from_mapping, load_environment
from sonartrack.acoustics.transmission_loss import DEPTH_DECIMATION, TLField, tl_field
from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import atomic_path

#: file suffixes read as a profile file (anything else is a shipped environment's name)
PROFILE_SUFFIXES = (".toml", ".csv")


def _csv_columns(p: Path) -> dict:
    """The profile columns of a CSV file as lists (one-line errors for unreadable or incomplete files)."""
    import pandas as pd

    try:
        df = pd.read_csv(p)
    except Exception as exc:  # noqa: BLE001 - pandas raises many types for bad files
        raise InputError(f"cannot read profile {p.name} as CSV: {exc}") from None
    require(len(df) > 0, f"profile {p.name} has no rows")
    cols = set(df.columns)
    require("depth_m" in cols, f"profile {p.name} needs a depth_m column (has {', '.join(map(str, df.columns))})")
    data = {"name": p.stem, "description": f"user profile {p.name}", "depth_m": df["depth_m"].to_list()}
    if "sound_speed_mps" in cols:
        data["sound_speed_mps"] = df["sound_speed_mps"].to_list()
    elif {"temperature_c", "salinity_psu"} <= cols:
        data["temperature_c"] = df["temperature_c"].to_list()
        data["salinity_psu"] = df["salinity_psu"].to_list()
    else:
        raise InputError(f"profile {p.name} needs sound_speed_mps, or temperature_c and salinity_psu, next to depth_m")
    return data


def read_profile(path: str | Path, water_depth_m: float | None = None) -> Environment:
    """A user environment from a TOML or CSV profile file (module doc); ``water_depth_m`` overrides the file's."""
    from sonartrack.io import toml as toml_io

    p = Path(path)
    require(p.is_file(), f"profile file not found: {p}")
    data = toml_io.load(p) if p.suffix.lower() == ".toml" else _csv_columns(p)
    if water_depth_m is not None:
        data["water_depth_m"] = float(water_depth_m)
    data.setdefault("water_depth_m", float(np.max(np.asarray(data["depth_m"], dtype=float))))
    return environment_from_mapping(data, source=p.name)


def environment_from_name_or_file(name_or_path: str | Path, water_depth_m: float | None = None) -> Environment:
    """A shipped environment by name (``yellow-summer``) or a profile file (a name ending .toml or .csv)."""
    if Path(name_or_path).suffix.lower() in PROFILE_SUFFIXES:
        return read_profile(name_or_path, water_depth_m)
    return load_environment(str(name_or_path))


def cache_dir(path: str | Path | None = None) -> Path:
    """Folder of cached TL fields: ``path``, else $SONARTRACK_CACHE_DIR/tl, else .sonartrack-cache/tl."""
    if path is not None:
        return Path(path)
    return Path(os.environ.get("SONARTRACK_CACHE_DIR", ".sonartrack-cache")) / "tl"


class TLDiskCache:
    """A :class:`~sonartrack.acoustics.transmission_loss.FieldStore` on disk (``folder``: see :func:`cache_dir`)."""

    def __init__(self, folder: str | Path | None = None):
        self.folder = cache_dir(folder)

    def path(self, key: str) -> Path:
        return self.folder / f"{key}.npz"

    def load(self, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            with np.load(path) as f:
                return f["ranges_m"], f["depths_m"], f["tl_db"]
        except (OSError, ValueError, KeyError):
            return None  # a damaged cache file is recomputed and replaced

    def save(self, key: str, ranges_m: np.ndarray, depths_m: np.ndarray, tl_db: np.ndarray) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(self.path(key)) as tmp:
            np.savez(tmp, ranges_m=ranges_m, depths_m=depths_m, tl_db=tl_db)


def cached_tl_field(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float = 50_000.0,
                    dr_m: float | None = None, dz_m: float | None = None, ndz: int = DEPTH_DECIMATION,
                    cache: str | Path | None = None) -> TLField:
    """:func:`~sonartrack.acoustics.transmission_loss.tl_field` through the disk cache in :func:`cache_dir`
    (``cache``): what every study, command and benchmark that reuses fields calls."""
    return tl_field(env, freq_hz, source_depth_m, rmax_m=rmax_m, dr_m=dr_m, dz_m=dz_m, ndz=ndz,
                    store=TLDiskCache(cache))
