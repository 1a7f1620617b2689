"""Ocean environments for propagation modelling: the six Korean-seas cases of paper P3, and user profiles.

An :class:`Environment` is a range-independent water column (depths and sound speeds, from T/S via
TEOS-10 where given) over a flat bottom and a homogeneous fluid seabed half-space. The shipped cases
are tables of this package, ``sonartrack/data/environments/<name>.toml`` (sources in
shared/data/korean_seas_environments.md), read here like any other constant table. A user's own
profile file (TOML or CSV) is read by :mod:`sonartrack.io.environment`, which hands the columns to
:func:`environment_from_mapping`: every check of the values lives here, every file format there.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require

#: seabed of a user profile that does not give one: medium sand (Hamilton 1980 / APL-UW 1994 table)
DEFAULT_BOTTOM = (1650.0, 1.9, 0.8)
#: latitude used for pressure when a user profile gives none (only affects c by < 0.1 m/s)
DEFAULT_LATITUDE_DEG = 35.0


@dataclass(frozen=True, slots=True)
class Environment:
    """A range-independent ocean: water column, flat bottom, fluid seabed half-space."""

    name: str
    description: str
    water_depth_m: float
    depth_m: np.ndarray
    sound_speed_mps: np.ndarray
    bottom_sound_speed_mps: float
    bottom_density_gcc: float
    bottom_attenuation_db_per_wavelength: float
    latitude_deg: float = DEFAULT_LATITUDE_DEG
    longitude_deg: float = 0.0
    season: str = ""
    temperature_c: np.ndarray | None = None
    salinity_psu: np.ndarray | None = None
    sources: str = ""

    def key(self) -> dict:
        """Everything that changes a propagation result, as plain data (for cache keys).

        Returns
        -------
        dict
            Water depth (m), profile depths (m), sound speeds (m/s, rounded to 1e-6) and the seabed values.
        """
        return {"water_depth_m": float(self.water_depth_m), "depth_m": [float(v) for v in self.depth_m],
                "sound_speed_mps": [round(float(v), 6) for v in self.sound_speed_mps],
                "bottom": [float(self.bottom_sound_speed_mps), float(self.bottom_density_gcc),
                           float(self.bottom_attenuation_db_per_wavelength)]}


def _data_dir() -> Path:
    from importlib.resources import files

    return Path(str(files("sonartrack") / "data" / "environments"))


def list_environments() -> list[str]:
    """Names of the shipped environments, east, yellow then south sea.

    Returns
    -------
    list of str
        E.g. ``["east-summer", "east-winter", "yellow-summer", ...]``.
    """
    order = {"east": 0, "yellow": 1, "south": 2}
    names = [p.stem for p in _data_dir().glob("*.toml")]
    return sorted(names, key=lambda n: (order.get(n.split("-")[0], 9), n))


def load_environment(name: str) -> Environment:
    """A shipped environment by name (paper P3's Korean-seas cases).

    Parameters
    ----------
    name : str
        One of :func:`list_environments`.

    Returns
    -------
    Environment
        The environment.

    Raises
    ------
    InputError
        If the name is unknown (the message lists the choices).
    """
    names = list_environments()
    if name not in names:
        raise InputError(f"unknown environment '{name}': choose one of {', '.join(names)}, or give --profile FILE")
    # a table shipped with the package (not user input): the standard library reads it
    data = tomllib.loads((_data_dir() / f"{name}.toml").read_text())
    return environment_from_mapping(data, source=name)


def _checked_depths(d: dict, source: str) -> tuple[np.ndarray, float]:
    """(profile depths, water depth) after the checks a user profile most often fails."""
    try:
        z = np.asarray(d["depth_m"], dtype=float)
    except (KeyError, TypeError, ValueError):
        raise InputError(f"profile {source}: depth_m must be a list of numbers") from None
    require(z.ndim == 1 and z.size >= 1, f"profile {source}: depth_m must be a non-empty list")
    require(bool(np.all(np.isfinite(z))), f"profile {source}: depth_m contains NaN")
    require(bool(np.all(z >= 0)), f"profile {source}: negative depth {z.min():g} m: depths are metres below the "
                                  "surface, positive down")
    require(bool(np.all(np.diff(z) > 0)), f"profile {source}: depths must increase strictly (sort the rows, drop "
                                          "duplicates)")
    depth = float(d.get("water_depth_m", z[-1]))
    require(depth > 0, f"profile {source}: water depth must be positive, got {depth:g} m")
    require(z[-1] >= depth - 1.0, f"profile {source}: the profile stops at {z[-1]:g} m but the water is {depth:g} m "
                                  f"deep: extend it to the bottom (repeat the last value at {depth:g} m if it is "
                                  "well mixed)")
    require(z[0] <= 1.0, f"profile {source}: the profile starts at {z[0]:g} m: add a row at the surface (0 m)")
    return z, depth


def _checked_sound_speed(d: dict, z: np.ndarray, lat: float, lon: float, source: str):
    """(c m/s, temperature or None, salinity or None): the given column, or TEOS-10 from T and S."""
    from sonartrack.acoustics.sound_speed import sound_speed_from_ts

    if "sound_speed_mps" not in d:
        require("temperature_c" in d and "salinity_psu" in d,
                f"profile {source}: give sound_speed_mps, or temperature_c and salinity_psu")
        t = np.asarray(d["temperature_c"], dtype=float)
        s = np.asarray(d["salinity_psu"], dtype=float)
        return sound_speed_from_ts(z, t, s, lat, lon), t, s
    c = np.asarray(d["sound_speed_mps"], dtype=float)
    require(c.shape == z.shape, f"profile {source}: sound_speed_mps needs one value per depth")
    require(bool(np.all(np.isfinite(c))), f"profile {source}: sound_speed_mps contains NaN")
    if np.all(c < 2.0):
        raise InputError(f"profile {source}: sound speeds {c.min():g}..{c.max():g} look like km/s: give m/s "
                         "(about 1450-1550)")
    require(bool(np.all((c > 1300) & (c < 1700))), f"profile {source}: sound speeds {c.min():g}..{c.max():g} m/s are "
                                                    "outside 1300-1700 m/s: check the column")
    return c, None, None


def _checked_seabed(d: dict, source: str) -> tuple[float, float, float]:
    """(sound speed m/s, density g/cm^3, attenuation dB/wavelength), :data:`DEFAULT_BOTTOM` where not given."""
    keys = ("bottom_sound_speed_mps", "bottom_density_gcc", "bottom_attenuation_db_per_wavelength")
    c, rho, attn = (float(d.get(k, default)) for k, default in zip(keys, DEFAULT_BOTTOM, strict=True))
    bottom = (c, rho, attn)
    require(bottom[0] > 0 and bottom[1] > 0 and bottom[2] >= 0, f"profile {source}: seabed values must be positive")
    return bottom


def environment_from_mapping(d: dict, source: str) -> Environment:
    """An :class:`Environment` from plain data (the shipped TOML keys; lists or arrays as values).

    Keys: ``depth_m`` and either ``sound_speed_mps`` or ``temperature_c`` + ``salinity_psu``
    (then c from TEOS-10 at ``latitude_deg``/``longitude_deg``); optional ``water_depth_m`` (default:
    the last depth), seabed keys (default :data:`DEFAULT_BOTTOM`), ``name``, ``description``,
    ``season``, ``sources``. The profile is cut or extended to end exactly at the water depth.

    Parameters
    ----------
    d : dict
        The data (depths in m positive down, speeds in m/s, temperatures in deg C, salinities in PSU,
        seabed speed m/s, density g/cm^3, attenuation dB/wavelength).
    source : str
        Names the input in error messages (one line each).

    Returns
    -------
    Environment
        The checked environment.

    Raises
    ------
    InputError
        On any failed check (unsorted or negative depths, a profile short of the bottom, km/s speeds ...).
    """
    z, depth = _checked_depths(d, source)
    lat = float(d.get("latitude_deg", DEFAULT_LATITUDE_DEG))
    lon = float(d.get("longitude_deg", 0.0))
    c, t, s = _checked_sound_speed(d, z, lat, lon, source)
    bottom = _checked_seabed(d, source)
    # keep the water column to the bottom exactly (RAM needs the profile to reach the deepest point)
    keep = z < depth
    z2 = np.append(z[keep], depth)
    c2 = np.append(c[keep], np.interp(depth, z, c))
    return Environment(name=str(d.get("name", source)), description=str(d.get("description", "")), water_depth_m=depth,
                       depth_m=z2, sound_speed_mps=c2, bottom_sound_speed_mps=bottom[0], bottom_density_gcc=bottom[1],
                       bottom_attenuation_db_per_wavelength=bottom[2], latitude_deg=lat, longitude_deg=lon,
                       season=str(d.get("season", "")), temperature_c=t, salinity_psu=s,
                       sources=str(d.get("sources", "")))
