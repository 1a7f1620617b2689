"""Transmission loss TL(range, depth) from the RAM parabolic-equation model (``pyram``).

Collins' RAM (split-step Pade PE, as in pyram, Collins 1993) gives the field of a point source at depth
zs over a range-independent environment (:mod:`sonartrack.acoustics.environment`): flat bottom, fluid
seabed half-space. RAM has no volume absorption, so Thorp's seawater absorption (dB/km, f in kHz)

    alpha(f) = 0.11 f^2 / (1 + f^2) + 44 f^2 / (4100 + f^2) + 2.75e-4 f^2 + 0.003

is added as alpha r / 1000 (0.008 dB/km at 200 Hz: small against spreading, kept for honesty).

Grid (our defaults, from a convergence check against the Pekeris mode sum in the tests): range step
dr = 6 wavelengths, depth step dz = wavelength / 20, the field kept every 10th depth point (wavelength
/ 2: 3.75 m at 200 Hz) and every range step. pyram's own defaults (8 wavelengths, wavelength / 10)
are 2 dB off the exact Pekeris field at 20 km after 1 km averaging; ours 0.2 dB (dz matters most).
TL is kept in single precision (float32, 1e-5 dB steps at 100 dB), whether or not it came from a
store, so that a result never depends on whether a cache was warm.

Fields are expensive (seconds to minutes), so :func:`tl_field` takes an optional ``store`` (any
object with ``load(key)`` and ``save(key, ranges_m, depths_m, tl_db)``, :class:`FieldStore`): it
looks the field up by :func:`field_key`, a hash of every input (environment values, frequency,
source depth, grid, pyram version), and saves what it computes. The disk store that Monte Carlo
workers and reruns share is :class:`sonartrack.io.environment.TLDiskCache`; this module does no file
I/O. pyram is imported only when a field is computed (it compiles with numba).

By reciprocity TL(source at zs -> receiver at zr, r) = TL(zr -> zs, r): for passive sonar the target
is the source at its depth and the array the receiver.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sonartrack.acoustics.environment import Environment
from sonartrack.core.errors import require

#: bump when the way fields are computed changes (part of the cache key)
TL_VERSION = 2
RANGE_STEP_WAVELENGTHS = 6.0
DEPTH_STEP_WAVELENGTHS = 0.05
DEPTH_DECIMATION = 10
#: nominal sound speed (m/s) that turns the frequency into the wavelength of the grid steps
GRID_SOUND_SPEED_MPS = 1500.0


@dataclass(frozen=True, slots=True)
class TLField:
    """TL (dB) on a depth x range grid for one source depth and frequency, absorption included."""

    ranges_m: np.ndarray
    depths_m: np.ndarray
    tl_db: np.ndarray
    freq_hz: float
    source_depth_m: float
    env_name: str

    def at_depth(self, depth_m: float) -> np.ndarray:
        """TL along range at one receiver depth (linear in depth between grid rows).

        Parameters
        ----------
        depth_m : float
            Receiver depth (m), inside the water column.

        Returns
        -------
        ndarray, shape (n_ranges,)
            TL (dB) at ``ranges_m``.

        Raises
        ------
        InputError
            If the depth is outside the grid.
        """
        z = self.depths_m
        require(0 <= depth_m <= z[-1] + 1e-9,
                f"receiver depth {depth_m:g} m is outside the water column (0..{z[-1]:g} m)")
        i = int(np.clip(np.searchsorted(z, depth_m) - 1, 0, len(z) - 2))
        w = float(np.clip((depth_m - z[i]) / (z[i + 1] - z[i]), 0.0, 1.0))
        return (1 - w) * self.tl_db[i] + w * self.tl_db[i + 1]


class FieldStore(Protocol):
    """Where computed TL fields are kept between calls (e.g. :class:`sonartrack.io.environment.TLDiskCache`)."""

    def load(self, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The field stored under ``key``, or None (absent or unreadable).

        Parameters
        ----------
        key : str
            Field key (:func:`field_key`).

        Returns
        -------
        tuple of ndarray or None
            (ranges_m, depths_m, tl_db).
        """

    def save(self, key: str, ranges_m: np.ndarray, depths_m: np.ndarray, tl_db: np.ndarray) -> None:
        """Keep a field under ``key``.

        Parameters
        ----------
        key : str
            Field key.
        ranges_m : ndarray
            Range grid (m).
        depths_m : ndarray
            Depth grid (m).
        tl_db : ndarray, shape (n_depths, n_ranges)
            TL (dB).
        """


def thorp_absorption_db_per_km(freq_hz) -> np.ndarray:
    """Thorp's seawater absorption ``alpha(f) = 0.11 f^2/(1 + f^2) + 44 f^2/(4100 + f^2) + 2.75e-4 f^2 + 0.003``.

    f in kHz in the formula (module docstring).

    Parameters
    ----------
    freq_hz : float or array_like
        Frequency (Hz).

    Returns
    -------
    ndarray
        Absorption (dB/km).
    """
    f = np.asarray(freq_hz, dtype=float) / 1e3
    f2 = f * f
    return 0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003


def _pyram_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pyram")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"


def field_key(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float, dr_m: float, dz_m: float,
              ndz: int) -> str:
    """A short hash of everything that changes a field (the store key).

    Parameters
    ----------
    env : Environment
        The environment (its values, through ``env.key()``).
    freq_hz : float
        Frequency (Hz).
    source_depth_m : float
        Source depth (m).
    rmax_m : float
        Largest range (m).
    dr_m, dz_m : float
        Range and depth steps (m).
    ndz : int
        Depth decimation.

    Returns
    -------
    str
        First 24 hex digits of a SHA-256 (the pyram version and ``TL_VERSION`` included).
    """
    spec = {"env": env.key(), "freq_hz": float(freq_hz), "zs": float(source_depth_m), "rmax_m": float(rmax_m),
            "dr_m": float(dr_m), "dz_m": float(dz_m), "ndz": int(ndz), "pyram": _pyram_version(), "v": TL_VERSION}
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:24]


def grid_steps_m(freq_hz: float, dr_m: float | None = None, dz_m: float | None = None) -> tuple[float, float]:
    """Range and depth steps: the given ones, else 6 and 1/20 wavelengths at 1500 m/s (module docstring).

    Parameters
    ----------
    freq_hz : float
        Frequency (Hz).
    dr_m, dz_m : float, optional
        Explicit steps (m).

    Returns
    -------
    tuple of float
        (range step, depth step) in m.
    """
    wavelength = GRID_SOUND_SPEED_MPS / freq_hz
    dr = float(dr_m) if dr_m is not None else RANGE_STEP_WAVELENGTHS * wavelength
    dz = float(dz_m) if dz_m is not None else DEPTH_STEP_WAVELENGTHS * wavelength
    return dr, dz


def tl_field(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float = 50_000.0,
             dr_m: float | None = None, dz_m: float | None = None, ndz: int = DEPTH_DECIMATION,
             store: FieldStore | None = None) -> TLField:
    """TL field (RAM, Collins 1993, plus Thorp absorption) of a source at ``source_depth_m`` out to ``rmax_m``.

    Taken from ``store`` if it holds the field, else computed with pyram and saved there (module docstring).

    Parameters
    ----------
    env : Environment
        Range-independent environment.
    freq_hz : float
        Frequency (Hz), > 0.
    source_depth_m : float
        Source depth (m), inside the water column.
    rmax_m : float, default 50000.0
        Largest range (m).
    dr_m, dz_m : float, optional
        Range and depth steps (m); default :func:`grid_steps_m`.
    ndz : int, default 10
        Keep every ndz-th depth point.
    store : FieldStore, optional
        Cache of fields.

    Returns
    -------
    TLField
        TL (dB) on a depth x range grid (float32 precision).

    Raises
    ------
    InputError
        If an input is out of range.
    """
    require(freq_hz > 0, f"frequency must be positive, got {freq_hz:g} Hz")
    require(0 < source_depth_m < env.water_depth_m,
            f"source depth {source_depth_m:g} m must lie inside the water column (0..{env.water_depth_m:g} m)")
    require(rmax_m > 0, f"maximum range must be positive, got {rmax_m:g} m")
    dr, dz = grid_steps_m(freq_hz, dr_m, dz_m)
    require(dr > 0 and dz > 0 and rmax_m > 2 * dr, "range and depth steps must be positive and smaller than the range")
    key = field_key(env, freq_hz, source_depth_m, rmax_m, dr, dz, ndz)
    found = store.load(key) if store is not None else None
    if found is not None:
        ranges, depths, tl32 = found
    else:
        ranges, depths, tl = _run_pyram(env, freq_hz, source_depth_m, rmax_m, dr, dz, ndz)
        tl32 = (tl + thorp_absorption_db_per_km(freq_hz) * ranges[None, :] / 1e3).astype(np.float32)
        if store is not None:
            store.save(key, ranges, depths, tl32)
    return TLField(ranges, depths, np.asarray(tl32).astype(float), float(freq_hz), float(source_depth_m), env.name)


def _pyram_inputs(env: Environment, freq_hz: float, rmax_m: float) -> dict:
    """pyram's environment arguments, each a fresh copy (pyram modifies some inputs in place)."""
    depth = float(env.water_depth_m)
    wavelength = GRID_SOUND_SPEED_MPS / freq_hz
    return {
        "z_ss": np.array(env.depth_m, dtype=float, copy=True), "rp_ss": np.array([0.0]),
        "cw": np.array(env.sound_speed_mps, dtype=float, copy=True)[:, None],
        # seabed layer below the deepest water point; pyram adds its absorbing layer under it
        "z_sb": np.array([0.0, 40.0 * wavelength]), "rp_sb": np.array([0.0]),
        "cb": np.full((2, 1), float(env.bottom_sound_speed_mps)),
        "rhob": np.full((2, 1), float(env.bottom_density_gcc)),
        "attn": np.full((2, 1), float(env.bottom_attenuation_db_per_wavelength)),
        "rbzb": np.array([[0.0, depth], [float(rmax_m), depth]]),
    }


def _run_pyram(env: Environment, freq_hz, zs, rmax, dr, dz, ndz):
    """(ranges m, depths m, TL dB without absorption) from pyram, source and receiver depth both ``zs``."""
    from pyram.PyRAM import PyRAM

    a = _pyram_inputs(env, freq_hz, rmax)
    model = PyRAM(float(freq_hz), float(zs), float(zs), a["z_ss"], a["rp_ss"], a["cw"], a["z_sb"], a["rp_sb"], a["cb"],
                  a["rhob"], a["attn"], a["rbzb"], rmax=float(rmax), dr=float(dr), dz=float(dz), ndz=int(ndz),
                  zmplt=float(env.water_depth_m))
    res = model.run()
    return (np.asarray(res["Ranges"], dtype=float), np.asarray(res["Depths"], dtype=float),
            np.asarray(res["TL Grid"], dtype=float))


def transmission_loss(env: Environment, freq_hz: float, source_depth_m: float, receiver_depth_m: float, ranges_m,
                      *, rmax_m: float | None = None, average_m: float = 0.0,
                      store: FieldStore | None = None) -> np.ndarray:
    """TL between two depths at given ranges, interpolated from the field (module docstring).

    ``average_m`` > 0 averages the intensity over a window of that length in range first (the usual
    way to compare PE results and to remove the interference detail a passive sonar integrates over).
    Below the first range step the TL is spherical spreading 20 log10(r / 1 m).

    Parameters
    ----------
    env : Environment
        The environment.
    freq_hz : float
        Frequency (Hz).
    source_depth_m : float
        Source depth (m).
    receiver_depth_m : float
        Receiver depth (m).
    ranges_m : array_like
        Ranges (m), finite and >= 0.
    rmax_m : float, optional
        Largest range of the field (m); default 1.05 x the largest range, at least 2 km.
    average_m : float, default 0.0
        Incoherent range-averaging window (m); 0 for none.
    store : FieldStore, optional
        Cache of fields.

    Returns
    -------
    ndarray
        TL (dB), shape of ``ranges_m``.

    Raises
    ------
    InputError
        If a range is negative or not finite (or as :func:`tl_field`).
    """
    r = np.asarray(ranges_m, dtype=float)
    require(bool(np.all(np.isfinite(r)) and np.all(r >= 0)), "ranges must be finite and non-negative")
    rmax = float(rmax_m) if rmax_m is not None else max(float(np.max(r, initial=0.0)) * 1.05, 2_000.0)
    f = tl_field(env, freq_hz, source_depth_m, rmax_m=rmax, store=store)
    line = f.at_depth(receiver_depth_m)
    if average_m > 0:
        line = smooth_tl(f.ranges_m, line, average_m)
    out = np.interp(r, f.ranges_m, line)
    near = r < f.ranges_m[0]
    out[near] = 20.0 * np.log10(np.maximum(r[near], 1.0))
    return out


def smooth_tl(ranges_m, tl_db, window_m: float) -> np.ndarray:
    """Incoherent range average: ``-10 log10`` of the running mean of ``10^(-TL/10)`` over ``window_m``.

    Parameters
    ----------
    ranges_m : array_like, shape (n,)
        Range grid (m), uniform.
    tl_db : array_like, shape (n,)
        TL along range (dB).
    window_m : float
        Window length (m); a window under one step leaves TL unchanged.

    Returns
    -------
    ndarray, shape (n,)
        Averaged TL (dB); the ends use edge padding.
    """
    r = np.asarray(ranges_m, dtype=float)
    dr = float(np.median(np.diff(r)))
    n = max(int(round(window_m / dr)), 1)
    if n == 1:
        return np.asarray(tl_db, dtype=float)
    intensity = 10.0 ** (-np.asarray(tl_db, dtype=float) / 10.0)
    kernel = np.ones(n) / n
    pad = n // 2
    padded = np.pad(intensity, (pad, n - 1 - pad), mode="edge")
    return -10.0 * np.log10(np.convolve(padded, kernel, mode="valid"))
