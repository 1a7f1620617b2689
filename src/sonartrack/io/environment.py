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


#: the keys a TOML profile may hold (acoustics/environment.py ``environment_from_mapping``); others are refused
PROFILE_KEYS = frozenset({
    "name", "description", "season", "sources", "depth_m", "sound_speed_mps", "temperature_c", "salinity_psu",
    "water_depth_m", "latitude_deg", "longitude_deg", "bottom_sound_speed_mps", "bottom_density_gcc",
    "bottom_attenuation_db_per_wavelength",
})
#: the deepest ocean is 11 km: depths beyond this are another unit
MAX_DEPTH_M = 12_000.0


def _csv_columns(p: Path) -> dict:
    """The profile columns of a CSV file as lists (io/tables.py checks: one line per problem)."""
    from sonartrack.io.tables import numeric_column, read_table

    what = "profile"
    df = read_table(p, what)
    cols = set(df.columns)
    require("depth_m" in cols, f"profile {p.name} needs a depth_m column (has {', '.join(map(str, df.columns))})")
    depth = numeric_column(df, "depth_m", what, p, hi=MAX_DEPTH_M, fix="metres below the surface")
    data = {"name": p.stem, "description": f"user profile {p.name}", "depth_m": depth.tolist()}
    if "sound_speed_mps" in cols:
        data["sound_speed_mps"] = numeric_column(df, "sound_speed_mps", what, p, lo=0.0, hi=1e4, lo_open=True,
                                                 fix="metres per second, about 1450-1550").tolist()
    elif {"temperature_c", "salinity_psu"} <= cols:
        data["temperature_c"] = numeric_column(df, "temperature_c", what, p, lo=-5.0, hi=40.0,
                                               fix="degrees Celsius").tolist()
        data["salinity_psu"] = numeric_column(df, "salinity_psu", what, p, lo=0.0, hi=45.0, fix="PSU").tolist()
    else:
        raise InputError(f"profile {p.name} needs sound_speed_mps, or temperature_c and salinity_psu, next to depth_m")
    return data


def _toml_profile(p: Path) -> dict:
    """A TOML profile's keys (unknown keys refused: a misspelt key would silently take its default)."""
    from sonartrack.io import toml as toml_io

    data = toml_io.load(p)
    unknown = sorted(set(data) - PROFILE_KEYS)
    require(not unknown, f"profile {p}: unknown key(s) {', '.join(unknown)}: the keys are "
                         f"{', '.join(sorted(PROFILE_KEYS))}")
    return data


def read_profile(path: str | Path, water_depth_m: float | None = None) -> Environment:
    """A user environment from a TOML or CSV sound-speed profile file (module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.toml`` or ``.csv`` file.
    water_depth_m : float, optional
        Water depth (m), overriding the file's (default: the file's, else its deepest sample).

    Returns
    -------
    Environment
        The environment (values checked by ``environment_from_mapping``).

    Raises
    ------
    InputError
        If the file is missing, malformed, or holds an unknown key or a bad value.
    """
    p = Path(path)
    require(not p.is_dir(), f"profile file {p} is a directory: give the .toml or .csv file inside it")
    require(p.is_file(), f"profile file not found: {p}")
    data = _toml_profile(p) if p.suffix.lower() == ".toml" else _csv_columns(p)
    if water_depth_m is not None:
        data["water_depth_m"] = float(water_depth_m)
    try:
        data.setdefault("water_depth_m", float(np.max(np.asarray(data["depth_m"], dtype=float))))
        return environment_from_mapping(data, source=p.name)
    except InputError:
        raise
    except (KeyError, TypeError, ValueError) as exc:  # a TOML value of the wrong type (text for a number)
        raise InputError(f"profile {p}: a value is missing or not a number ({type(exc).__name__}: {exc}): every "
                         "depth, speed and seabed value must be a number") from None


def environment_from_name_or_file(name_or_path: str | Path, water_depth_m: float | None = None) -> Environment:
    """A shipped environment by name (``yellow-summer``) or a profile file (a name ending .toml or .csv).

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        Environment name or profile file.
    water_depth_m : float, optional
        Water depth (m) for a profile file (ignored for a shipped environment).

    Returns
    -------
    Environment
        The shipped environment (:func:`~sonartrack.acoustics.environment.load_environment`), or the file's
        (:func:`read_profile`).

    Raises
    ------
    InputError
        If the name is unknown or the file is bad.
    """
    if Path(name_or_path).suffix.lower() in PROFILE_SUFFIXES:
        return read_profile(name_or_path, water_depth_m)
    return load_environment(str(name_or_path))


def cache_dir(path: str | Path | None = None) -> Path:
    """Folder of cached TL fields: ``path``, else ``$SONARTRACK_CACHE_DIR/tl``, else ``.sonartrack-cache/tl``.

    Parameters
    ----------
    path : str or pathlib.Path, optional
        Explicit folder.

    Returns
    -------
    pathlib.Path
        The folder (not created).
    """
    if path is not None:
        return Path(path)
    return Path(os.environ.get("SONARTRACK_CACHE_DIR", ".sonartrack-cache")) / "tl"


class TLDiskCache:
    """A :class:`~sonartrack.acoustics.transmission_loss.FieldStore` on disk (``folder``: see :func:`cache_dir`)."""

    def __init__(self, folder: str | Path | None = None):
        self.folder = cache_dir(folder)

    def path(self, key: str) -> Path:
        """File of the field with key ``key``.

        Parameters
        ----------
        key : str
            Field key (``acoustics.transmission_loss.field_key``).

        Returns
        -------
        pathlib.Path
            ``<folder>/<key>.npz``.
        """
        return self.folder / f"{key}.npz"

    def load(self, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """A cached field, or None if absent or damaged (then recomputed and replaced by the caller).

        Parameters
        ----------
        key : str
            Field key.

        Returns
        -------
        tuple of ndarray or None
            (ranges (m), depths (m), TL (dB) on that grid).
        """
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            with np.load(path) as f:
                return f["ranges_m"], f["depths_m"], f["tl_db"]
        except (OSError, ValueError, KeyError):
            return None  # a damaged cache file is recomputed and replaced

    def save(self, key: str, ranges_m: np.ndarray, depths_m: np.ndarray, tl_db: np.ndarray) -> None:
        """Store a field atomically (the parameters of
        :meth:`FieldStore.save <sonartrack.acoustics.transmission_loss.FieldStore.save>`: key, grids in m, TL in dB)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(self.path(key)) as tmp:
            np.savez(tmp, ranges_m=ranges_m, depths_m=depths_m, tl_db=tl_db)


def cached_tl_field(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float = 50_000.0,
                    dr_m: float | None = None, dz_m: float | None = None, ndz: int = DEPTH_DECIMATION,
                    cache: str | Path | None = None) -> TLField:
    """:func:`~sonartrack.acoustics.transmission_loss.tl_field` through the disk cache (module docstring).

    What every study, command and benchmark that reuses fields calls. ``env``, ``freq_hz`` (Hz),
    ``source_depth_m`` (m), ``rmax_m`` (m), ``dr_m``, ``dz_m`` (m) and ``ndz`` are
    :func:`~sonartrack.acoustics.transmission_loss.tl_field`'s.

    Parameters
    ----------
    cache : str or pathlib.Path, optional
        Cache folder (see :func:`cache_dir`).

    Returns
    -------
    TLField
        TL (dB) over range and depth.
    """
    return tl_field(env, freq_hz, source_depth_m, rmax_m=rmax_m, dr_m=dr_m, dz_m=dz_m, ndz=ndz,
                    store=TLDiskCache(cache))
