"""The N-channel recording of a passive scene, synthesised block by block (pressure in pascals).

Element n (0 = front) sits s_n = ((N - 1) / 2 - n) d ahead of the array centre on the array axis. A
plane wave from cone angle theta reaches it at

    tau_n = -s_n cos(theta) / c          (relative to the centre; so tau_{n+1} - tau_n = d cos(theta) / c,
                                          the two-sensor convention of acoustics/signals.py with sensor 1
                                          in front: the rear element hears a source ahead later)

Per block (``block_s``, 1 s by default) the geometry is held at the block centre (sim/passive_scene.py)
and each element's spectrum is built in the frequency domain on the rfft bins of the band [f_lo, f_hi):

    X_n(f) = sum_ships S_s(f) exp(-2 pi i f tau_{s,n}) + A_n(f)

S_s(f) and A_n(f) are independent complex Gaussian bins, scaled so that the one-sided power spectral
density is flat at the received level: E|X_k|^2 = 2 c^2 with c^2 = P fs n_b / 4 gives a variance
P (f_hi - f_lo) after the inverse FFT (P in Pa^2/Hz: RL_bb for a ship, NL for the ambient noise, which is
independent between elements). The delay is an exact phase ramp, circular within the block: the wave's
first |tau| (<= half the array's length / c, 12.5 ms for the default array) wraps from the block's end,
and noise blocks join without smoothing, as in the two-sensor simulator of paper P0.

Tonal lines are added in the time domain, phase-continuous across blocks: with the received frequency
f(t) and amplitude a(t) linear within a block (between the values at the block edges),

    phi(t) = phi_k + 2 pi (f_k t + (f_{k+1} - f_k) t^2 / (2 T_k)),   x_n(t) += a(t) cos(phi(t) - 2 pi f tau_n)

with a = sqrt(2 RL_t) (a sinusoid of power RL_t). Blocks are yielded one at a time, so memory does not grow
with the recording's length; the block plan (delays and levels, a few numbers per block and ship) is
computed once up front.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from sonartrack.sim.passive_scene import ReceivedLevels, received_levels, scene_geometry
from sonartrack.sim.scene import PassiveSceneSettings

#: (1 uPa)^2 in Pa^2: levels in dB re 1 uPa become pascals
UPA2_PA2 = 1e-12


@dataclass(frozen=True, slots=True)
class BlockPlan:
    """What each block needs, computed up front (B blocks, S ships, N elements).

    ``start`` and ``length`` in samples (B,); ``delays_s`` (B, S, N) at the block centres;
    ``broadband_psd`` (B, S) in Pa^2/Hz; tonal amplitude (Pa) and received frequency (Hz) at the block
    edges (B + 1, S), zero amplitude for a ship without a tonal."""

    start: np.ndarray
    length: np.ndarray
    delays_s: np.ndarray
    broadband_psd: np.ndarray
    tonal_amplitude: np.ndarray
    tonal_hz: np.ndarray

    @property
    def n_blocks(self) -> int:
        """Number of blocks B."""
        return int(self.start.size)


def element_offsets_m(n_elements: int, spacing_m: float) -> np.ndarray:
    """Positions of the elements along the array axis from the centre, front (element 1) positive.

    ``s_n = ((N - 1) / 2 - n) d``, n = 0 .. N - 1.

    Parameters
    ----------
    n_elements : int
        N.
    spacing_m : float
        Element spacing d (m).

    Returns
    -------
    ndarray, shape (N,)
        Offsets (m).
    """
    return ((n_elements - 1) / 2.0 - np.arange(n_elements)) * spacing_m


def plane_wave_delays_s(cone_rad, offsets_m: np.ndarray, sound_speed_mps: float) -> np.ndarray:
    """Plane-wave delays ``tau_n = -s_n cos(theta) / c`` relative to the array centre (module docstring).

    Parameters
    ----------
    cone_rad : float or array_like, shape (...)
        Cone angle theta (rad, 0..pi from the array axis, 0 ahead).
    offsets_m : ndarray, shape (N,)
        Element offsets s_n (m, :func:`element_offsets_m`).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    ndarray, shape (..., N)
        Delays (s); a source ahead reaches the front element first.
    """
    return -np.cos(np.asarray(cone_rad, dtype=float))[..., None] * offsets_m / sound_speed_mps


def block_bounds(scene: PassiveSceneSettings) -> tuple[np.ndarray, np.ndarray, float]:
    """Start sample and length of every synthesis block; the last block may be shorter.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (duration, block length, sample rate).

    Returns
    -------
    start : ndarray of int, shape (B,)
        First sample of each block.
    length : ndarray of int, shape (B,)
        Samples in each block.
    fs : float
        Sample rate (Hz).
    """
    fs = scene.sample_rate_hz
    n_total = int(round(scene.duration_s * fs))
    nb = int(round(scene.block_s * fs))
    start = np.arange(0, n_total, nb)
    return start, np.minimum(nb, n_total - start), fs


def plan_blocks(scene: PassiveSceneSettings, store=None) -> BlockPlan:
    """Delays and levels of every block, computed up front (geometry at block centres, tonal values at block edges).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    store : optional
        Cache of RAM fields (sim/passive_scene.py).

    Returns
    -------
    BlockPlan
        Block bounds (samples), delays (s), broadband PSD (Pa^2/Hz), tonal amplitudes (Pa) and
        frequencies (Hz).
    """
    start, length, fs = block_bounds(scene)
    centres = (start + length / 2.0) / fs
    edges = np.append(start, start[-1] + length[-1]) / fs
    g_mid = scene_geometry(scene, centres)
    lv_mid = received_levels(scene, g_mid, store)
    lv_edge: ReceivedLevels = received_levels(scene, scene_geometry(scene, edges), store)
    offsets = element_offsets_m(scene.array.elements, scene.spacing_m)
    delays = plane_wave_delays_s(g_mid.cone_rad.T, offsets, scene.sound_speed_mps)  # (B, S, N)
    has_tonal = np.isfinite(lv_edge.tonal_db)
    amplitude = np.where(has_tonal, np.sqrt(2.0 * UPA2_PA2 * 10.0 ** (np.nan_to_num(lv_edge.tonal_db) / 10.0)), 0.0)
    return BlockPlan(start, length, delays, UPA2_PA2 * 10.0 ** (lv_mid.broadband_db.T / 10.0),
                     amplitude.T, np.nan_to_num(lv_edge.tonal_hz).T)


def _band_bins(scene: PassiveSceneSettings, nb: int) -> tuple[np.ndarray, np.ndarray]:
    """(all rfft frequencies of a block, mask of the band's bins [f_lo, f_hi), DC excluded)."""
    f = np.fft.rfftfreq(nb, 1.0 / scene.sample_rate_hz)
    lo, hi = scene.band_hz
    return f, (f >= lo) & (f < hi) & (f > 0)


def _gaussian_bins(rng: np.random.Generator, shape) -> np.ndarray:
    g = rng.standard_normal(tuple(shape) + (2,))
    return g[..., 0] + 1j * g[..., 1]


def _broadband_block(rng, plan: BlockPlan, k: int, f_band: np.ndarray, scale_per_psd: float,
                     ambient_scale: float, n_elements: int) -> np.ndarray:
    """Band bins (N, n_band) of block k: the ships' delayed noise plus independent ambient noise."""
    n_band = f_band.size
    amplitude = np.sqrt(scale_per_psd * plan.broadband_psd[k])[:, None]
    ships = _gaussian_bins(rng, (plan.delays_s.shape[1], n_band)) * amplitude
    x = np.einsum("sf,snf->nf", ships, _phase_ramps(plan.delays_s[k], f_band)) if ships.size else 0.0
    return x + ambient_scale * _gaussian_bins(rng, (n_elements, n_band))


def _phase_ramps(delays_s: np.ndarray, f_band: np.ndarray) -> np.ndarray:
    """exp(-2 pi i f tau_n) (S, N, n_band) for delays (S, N) that step uniformly along the array.

    tau_n = tau_0 + n (tau_1 - tau_0) on a uniform line, so the ramp is exp(-2 pi i f tau_0) times the
    n-th power of exp(-2 pi i f (tau_1 - tau_0)): a cumulative product, two complex exponentials per ship
    instead of N (rounding grows by ~1e-16 per element)."""
    first = np.exp(-2j * np.pi * delays_s[:, :1, None] * f_band)
    step = np.exp(-2j * np.pi * (delays_s[:, 1:2, None] - delays_s[:, :1, None]) * f_band)
    factors = np.concatenate([first, np.broadcast_to(step, (delays_s.shape[0], delays_s.shape[1] - 1, f_band.size))],
                             axis=1)
    return np.cumprod(factors, axis=1)


def _tonal_block(plan: BlockPlan, k: int, phase0: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(tonal samples (N, m) of block k, phases at the block's end) (module doc)."""
    m = int(plan.length[k])
    dur = m / fs
    t = np.arange(m) / fs
    f0, f1 = plan.tonal_hz[k], plan.tonal_hz[k + 1]
    a0, a1 = plan.tonal_amplitude[k], plan.tonal_amplitude[k + 1]
    phi = phase0[:, None] + 2.0 * np.pi * (f0[:, None] * t + (f1 - f0)[:, None] * t**2 / (2.0 * dur))
    amp = a0[:, None] + (a1 - a0)[:, None] * (t / dur)
    psi = 2.0 * np.pi * 0.5 * (f0 + f1)[:, None] * plan.delays_s[k]  # (S, N)
    weights = np.concatenate([np.cos(psi), np.sin(psi)]).T  # (N, 2S)
    waves = np.concatenate([amp * np.cos(phi), amp * np.sin(phi)])  # (2S, m)
    end = np.mod(phase0 + 2.0 * np.pi * dur * 0.5 * (f0 + f1), 2.0 * np.pi)
    # einsum's own loop, not a BLAS matrix product: a BLAS product this small (N x 2S x m) runs 20-70x slower when
    # its threads compete for busy cores (measured 40-86 ms against 4 ms a block at 32 x 8 kHz)
    return np.einsum("nk,km->nm", weights, waves), end


def array_blocks(scene: PassiveSceneSettings, rng: np.random.Generator, store=None,
                 plan: BlockPlan | None = None) -> Iterator[np.ndarray]:
    """The recording, block by block, synthesised in the frequency domain (module docstring).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    rng : numpy.random.Generator
        Random stream (noise and tonal phases).
    store : optional
        Cache of RAM fields.
    plan : BlockPlan, optional
        A precomputed plan (:func:`plan_blocks`).

    Yields
    ------
    ndarray, shape (N, m)
        Pressure (Pa) of each element over the block's m samples.
    """
    plan = plan_blocks(scene, store) if plan is None else plan
    fs = scene.sample_rate_hz
    nb = int(round(scene.block_s * fs))
    f, band = _band_bins(scene, nb)
    f_band = f[band]
    scale_per_psd = fs * nb / 4.0  # c^2 = P fs n_b / 4 (module doc)
    ambient_scale = np.sqrt(scale_per_psd * UPA2_PA2 * 10.0 ** (scene.noise_level_db / 10.0))
    n = scene.array.elements
    phase = rng.uniform(0.0, 2.0 * np.pi, len(scene.ships))
    spectrum = np.zeros((n, f.size), dtype=complex)
    has_tonal = bool(np.any(plan.tonal_amplitude > 0))
    for k in range(plan.n_blocks):
        spectrum[:, band] = _broadband_block(rng, plan, k, f_band, scale_per_psd, ambient_scale, n)
        x = np.fft.irfft(spectrum, nb, axis=1)[:, : plan.length[k]]
        if has_tonal:
            tonal, phase = _tonal_block(plan, k, phase, fs)
            x += tonal
        yield x


def simulate_recording(scene: PassiveSceneSettings, rng: np.random.Generator, store=None) -> np.ndarray:
    """The whole recording in memory (short scenes and tests; files use :func:`array_blocks`).

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene.
    rng : numpy.random.Generator
        Random stream.
    store : optional
        Cache of RAM fields.

    Returns
    -------
    ndarray, shape (N, n_samples)
        Pressure (Pa).
    """
    return np.concatenate(list(array_blocks(scene, rng, store)), axis=1)
