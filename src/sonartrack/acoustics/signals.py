"""Two-sensor receiver signals: broadband sources at given bearings, ambient noise, multipath (paper P0).

Sensors 1 and 2 sit on the array axis a distance d apart; a plane wave from cone angle theta (0-180
deg from the axis, pointing from sensor 1 to sensor 2) reaches sensor 2 later by

    D = d cos(theta) / c       (so r2(t) = s(t - D) + n2(t), and theta = arccos(c D / d))

Each source is band-limited Gaussian noise (flat spectrum in ``band_hz``) of power ``10^(snr/10)``
against unit-variance channel noise. The delay is applied exactly in the frequency domain
(a phase ramp), block by block: each 1 s block (``block_s``) uses the source's bearing at the block
centre, so moving sources are piecewise static, which is what a 1 s correlator sees. A multipath
arrival is a further plane wave from another cone angle (``bearing_offset_deg`` away), delayed by
``extra_delay_s`` and scaled by ``relative_amplitude``: its correlation peak appears at its own angle.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require


@dataclass(frozen=True, slots=True)
class Multipath:
    """A further arrival of a source: delayed by ``extra_delay_s`` (s), scaled by ``relative_amplitude``
    (linear, against the direct arrival), from a cone angle ``bearing_offset_deg`` (deg) away from the
    direct one (module docstring).
    """
    extra_delay_s: float
    relative_amplitude: float
    bearing_offset_deg: float


@dataclass(frozen=True, slots=True)
class SourceSpec:
    """A source: cone angle (deg, or a function of time s -> deg), SNR per channel (dB), multipath arrivals."""

    bearing_deg: float | Callable[[float], float]
    snr_db: float
    multipath: tuple = ()

    def bearing_at(self, t_s: float) -> float:
        """The source's cone angle at time ``t_s`` (s), clipped to [0, 180] deg.

        Returns
        -------
        float
            Cone angle (deg from the array axis, 0 pointing from sensor 1 to sensor 2).
        """
        b = self.bearing_deg(t_s) if callable(self.bearing_deg) else self.bearing_deg
        return float(np.clip(b, 0.0, 180.0))


def simulate_two_channel(rng: np.random.Generator, *, duration_s: float, fs_hz: float, spacing_m: float,
                         sound_speed_mps: float = 1500.0, sources=(), noise_std: float = 1.0,
                         band_hz: tuple[float, float] = (100.0, 1000.0), block_s: float = 1.0) -> np.ndarray:
    """Two sensors' signals: broadband sources by plane-wave delay ``D = d cos(theta) / c``, plus noise (paper P0).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    duration_s, fs_hz : float
        Length (s) and sample rate (Hz).
    spacing_m : float
        Sensor spacing d (m).
    sound_speed_mps : float, default 1500.0
        Sound speed c (m/s).
    sources : sequence of SourceSpec
        Sources (cone angle, SNR per channel in dB, multipath).
    noise_std : float, default 1.0
        Standard deviation of each channel's independent noise.
    band_hz : tuple of float, default (100.0, 1000.0)
        Band of the sources (Hz), within 0..fs/2.
    block_s : float, default 1.0
        Block over which each source's angle is held (s).

    Returns
    -------
    ndarray, shape (2, n)
        Samples of sensor 1 and sensor 2, n = round(duration_s fs_hz). InputError if the spacing, rate,
        duration or band are invalid.
    """
    require(spacing_m > 0, f"sensor spacing must be positive, got {spacing_m:g} m")
    require(fs_hz > 0 and duration_s > 0, "sample rate and duration must be positive")
    require(0 <= band_hz[0] < band_hz[1] <= fs_hz / 2, f"band {band_hz} Hz must lie within 0..fs/2 = {fs_hz / 2:g} Hz")
    n_total = int(round(duration_s * fs_hz))
    nb = int(round(block_s * fs_hz))
    out = noise_std * rng.normal(size=(2, n_total))
    f = np.fft.rfftfreq(nb, 1.0 / fs_hz)
    band = (f >= band_hz[0]) & (f <= band_hz[1])
    n_band = int(band.sum())
    for start in range(0, n_total, nb):
        m = min(nb, n_total - start)
        t_mid = (start + m / 2) / fs_hz
        for src in sources:
            power = 10.0 ** (src.snr_db / 10.0) * noise_std**2
            arrivals = [(0.0, 1.0, src.bearing_at(t_mid))]
            arrivals += [(mp.extra_delay_s, mp.relative_amplitude,
                          float(np.clip(src.bearing_at(t_mid) + mp.bearing_offset_deg, 0, 180)))
                         for mp in src.multipath]
            # white in band; Parseval for irfft: var = 2 sum |X_k|^2 / nb^2, and E|X_k|^2 = 2 c^2 here
            spec = np.zeros(len(f), dtype=complex)
            spec[band] = (rng.normal(size=n_band) + 1j * rng.normal(size=n_band))
            spec *= nb * np.sqrt(power / (4.0 * max(n_band, 1)))
            for extra, amp, theta in arrivals:
                D = spacing_m * np.cos(np.deg2rad(theta)) / sound_speed_mps
                s1 = np.fft.irfft(spec * np.exp(-2j * np.pi * f * extra), nb)
                s2 = np.fft.irfft(spec * np.exp(-2j * np.pi * f * (extra + D)), nb)
                out[0, start:start + m] += amp * s1[:m]
                out[1, start:start + m] += amp * s2[:m]
    return out
