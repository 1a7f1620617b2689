"""Transmission loss TL(range, depth) from the RAM parabolic-equation model (``pyram``), with a disk cache.

Collins' RAM (split-step Pade PE, as in pyram, Collins 1993) gives the field of a point source at depth
zs over a range-independent environment (:mod:`sonartrack.acoustics.environment`): flat bottom, fluid
seabed half-space. RAM has no volume absorption, so Thorp's seawater absorption (dB/km, f in kHz)

    alpha(f) = 0.11 f^2 / (1 + f^2) + 44 f^2 / (4100 + f^2) + 2.75e-4 f^2 + 0.003

is added as alpha r / 1000 (0.008 dB/km at 200 Hz: small against spreading, kept for honesty).

Grid (our defaults, from a convergence check against the Pekeris mode sum in the tests): range step
dr = 6 wavelengths, depth step dz = wavelength / 20, the field kept every 10th depth point (wavelength
/ 2: 3.75 m at 200 Hz) and every range step. pyram's own defaults (8 wavelengths, wavelength / 10)
are 2 dB off the exact Pekeris field at 20 km after 1 km averaging; ours 0.2 dB (dz matters most). Fields are cached as ``.npz`` in ``$SONARTRACK_CACHE_DIR/tl`` (default
``.sonartrack-cache/tl``), written atomically and keyed by a hash of every input (environment
values, frequency, source depth, grid, pyram version), so Monte Carlo workers and reruns never
recompute one. pyram is imported only on a cache miss (it compiles with numba).

By reciprocity TL(source at zs -> receiver at zr, r) = TL(zr -> zs, r): for passive sonar the target
is the source at its depth and the array the receiver.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.acoustics.environment import Environment
from sonartrack.core.errors import require

#: bump when the way fields are computed changes (part of the cache key)
TL_VERSION = 2
RANGE_STEP_WAVELENGTHS = 6.0
DEPTH_STEP_WAVELENGTHS = 0.05
DEPTH_DECIMATION = 10


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
        """TL along range at one receiver depth (linear in depth between grid rows)."""
        z = self.depths_m
        require(0 <= depth_m <= z[-1] + 1e-9, f"receiver depth {depth_m:g} m is outside the water column (0..{z[-1]:g} m)")
        i = int(np.clip(np.searchsorted(z, depth_m) - 1, 0, len(z) - 2))
        w = float(np.clip((depth_m - z[i]) / (z[i + 1] - z[i]), 0.0, 1.0))
        return (1 - w) * self.tl_db[i] + w * self.tl_db[i + 1]


def thorp_absorption_db_per_km(freq_hz) -> np.ndarray:
    """Thorp's seawater absorption (dB/km) at frequency ``freq_hz`` (Hz)."""
    f = np.asarray(freq_hz, dtype=float) / 1e3
    f2 = f * f
    return 0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003


def cache_dir(path: str | Path | None = None) -> Path:
    """Folder of cached TL fields: ``path``, else $SONARTRACK_CACHE_DIR/tl, else .sonartrack-cache/tl."""
    if path is not None:
        return Path(path)
    return Path(os.environ.get("SONARTRACK_CACHE_DIR", ".sonartrack-cache")) / "tl"


def _pyram_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pyram")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"


def field_key(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float, dr_m: float, dz_m: float,
              ndz: int) -> str:
    spec = {"env": env.key(), "freq_hz": float(freq_hz), "zs": float(source_depth_m), "rmax_m": float(rmax_m),
            "dr_m": float(dr_m), "dz_m": float(dz_m), "ndz": int(ndz), "pyram": _pyram_version(), "v": TL_VERSION}
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:24]


def tl_field(env: Environment, freq_hz: float, source_depth_m: float, rmax_m: float = 50_000.0, dr_m: float | None = None,
             dz_m: float | None = None, ndz: int = DEPTH_DECIMATION, cache: str | Path | None = None,
             use_cache: bool = True) -> TLField:
    """TL field of a source at ``source_depth_m`` out to ``rmax_m`` (module doc); cached on disk."""
    require(freq_hz > 0, f"frequency must be positive, got {freq_hz:g} Hz")
    require(0 < source_depth_m < env.water_depth_m,
            f"source depth {source_depth_m:g} m must lie inside the water column (0..{env.water_depth_m:g} m)")
    require(rmax_m > 0, f"maximum range must be positive, got {rmax_m:g} m")
    wavelength = 1500.0 / freq_hz
    dr = float(dr_m) if dr_m is not None else RANGE_STEP_WAVELENGTHS * wavelength
    dz = float(dz_m) if dz_m is not None else DEPTH_STEP_WAVELENGTHS * wavelength
    require(dr > 0 and dz > 0 and rmax_m > 2 * dr, "range and depth steps must be positive and smaller than the range")
    key = field_key(env, freq_hz, source_depth_m, rmax_m, dr, dz, ndz)
    path = cache_dir(cache) / f"{key}.npz"
    if use_cache and path.is_file():
        try:
            with np.load(path) as f:
                return TLField(f["ranges_m"], f["depths_m"], f["tl_db"].astype(float), float(freq_hz),
                               float(source_depth_m), env.name)
        except (OSError, ValueError, KeyError):
            pass  # a damaged cache file is recomputed and replaced
    ranges, depths, tl = _run_pyram(env, freq_hz, source_depth_m, rmax_m, dr, dz, ndz)
    tl = tl + thorp_absorption_db_per_km(freq_hz) * ranges[None, :] / 1e3
    if use_cache:
        from sonartrack.io.atomic import atomic_path

        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            np.savez(tmp, ranges_m=ranges, depths_m=depths, tl_db=tl.astype(np.float32))
        tl = tl.astype(np.float32).astype(float)  # identical to what the cache returns next time
    return TLField(ranges, depths, tl, float(freq_hz), float(source_depth_m), env.name)


def _run_pyram(env: Environment, freq_hz, zs, rmax, dr, dz, ndz):
    """Call pyram on copies of every array (it modifies some inputs in place)."""
    from pyram.PyRAM import PyRAM

    D = float(env.water_depth_m)
    wavelength = 1500.0 / freq_hz
    z_ss = np.array(env.depth_m, dtype=float, copy=True)
    cw = np.array(env.sound_speed_mps, dtype=float, copy=True)[:, None]
    z_sb = np.array([0.0, 40.0 * wavelength])  # below the deepest water point; pyram adds its absorbing layer under it
    cb = np.full((2, 1), float(env.bottom_sound_speed_mps))
    rhob = np.full((2, 1), float(env.bottom_density_gcc))
    attn = np.full((2, 1), float(env.bottom_attenuation_db_per_wavelength))
    rbzb = np.array([[0.0, D], [float(rmax), D]])
    model = PyRAM(float(freq_hz), float(zs), float(zs), z_ss, np.array([0.0]), cw, z_sb, np.array([0.0]), cb, rhob, attn,
                  rbzb, rmax=float(rmax), dr=float(dr), dz=float(dz), ndz=int(ndz), zmplt=D)
    res = model.run()
    depths = np.asarray(res["Depths"], dtype=float)
    ranges = np.asarray(res["Ranges"], dtype=float)
    tl = np.asarray(res["TL Grid"], dtype=float)
    del wavelength
    return ranges, depths, tl


def transmission_loss(env: Environment, freq_hz: float, source_depth_m: float, receiver_depth_m: float, ranges_m,
                      *, rmax_m: float | None = None, average_m: float = 0.0, cache: str | Path | None = None) -> np.ndarray:
    """TL (dB) at ``ranges_m`` between the two depths (interpolated from the cached field).

    ``average_m`` > 0 averages the intensity over a window of that length in range first (the usual
    way to compare PE results and to remove the interference detail a passive sonar integrates over).
    Below the first range step the TL is spherical spreading 20 log10(r / 1 m).
    """
    r = np.asarray(ranges_m, dtype=float)
    require(bool(np.all(np.isfinite(r)) and np.all(r >= 0)), "ranges must be finite and non-negative")
    rmax = float(rmax_m) if rmax_m is not None else max(float(np.max(r, initial=0.0)) * 1.05, 2_000.0)
    f = tl_field(env, freq_hz, source_depth_m, rmax_m=rmax, cache=cache)
    line = f.at_depth(receiver_depth_m)
    if average_m > 0:
        line = smooth_tl(f.ranges_m, line, average_m)
    out = np.interp(r, f.ranges_m, line)
    near = r < f.ranges_m[0]
    out[near] = 20.0 * np.log10(np.maximum(r[near], 1.0))
    return out


def smooth_tl(ranges_m, tl_db, window_m: float) -> np.ndarray:
    """Incoherent range average: -10 log10 of the running mean of 10^(-TL/10) over ``window_m``."""
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
