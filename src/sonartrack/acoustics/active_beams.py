"""Conventional beamforming of a line array's complex-baseband pings onto a cone-angle grid.

Geometry as the passive front end (acoustics/beamforming.py, sim/array_signals.py): element n (0 = front)
sits s_n = ((N - 1)/2 - n) d ahead of the array centre; a plane wave from cone angle theta (0 = ahead along
the axis, 180 = astern) reaches it at tau_n(theta) = -s_n cos(theta) / c relative to the centre.

Baseband at carrier f_c: a delay tau multiplies the baseband spectrum at offset f by
exp(-2 pi i (f_c + f) tau), so the true-time-delay beam (Van Trees, Optimum Array Processing, sec. 2.2) is

    Y_b(f) = (1/N) sum_n exp(+2 pi i (f_c + f) tau_n(theta_b)) X_n(f)

(averaged, so an echo on the beam's axis keeps its amplitude and the element noise power drops N-fold).
The steering is taken at the centre of blocks of adjacent bins (one small matrix product per block): a block
of width W Hz errs in phase by at most pi W (N - 1) d / (2 c), and blocks are made as wide as keeps that below
``STEERING_PHASE_RAD`` (0.13 Hz, 4 bins of a 6400-point ping at 200 Hz, for the default 7.5 m array; one bin for
a 15.5 m array), so the beams are the true-time-delay beams to 0.001 rad. The step matters: the phase error is a
staircase in frequency, which spreads each sample's power over the whole ping: at 0.01 rad an impulse on a beam
leaked 75 dB down (16 x 0.5 m) and 69 dB down (32 x 0.5 m) at every other delay, so the 161 dB direct blast of a
towed source left ~86 dB at every delay, above the beams' noise (~71 dB at 60 dB re 1 uPa^2/Hz); at 0.001 rad
94 and 84 dB down, per bin 96 and 84 dB (the tails of the off-grid fractional delays). The weights are cached (each
ping of a run has the same size, carrier and beams), so the finer step costs ~2 ms (16 elements) to ~30 ms
(32 elements, per bin) a ping (6400 bins, 61 beams; measured with 0.01 rad: 6 and 9 ms). For a narrowband plane wave
from theta_0 the beam pattern of the uniform line is the closed form

    |Y(theta)| / |Y(theta_0)| = |sin(N x) / (N sin x)|,   x = pi f d (cos theta - cos theta_0) / c.
"""

from __future__ import annotations

import functools

import numpy as np

from sonartrack.acoustics.line_array import LineArray
from sonartrack.core.errors import require

__all__ = ["LineArray", "beam_pattern", "beamform_spectra", "cone_grid_deg", "element_offsets_m",
           "plane_wave_delays_s", "steering_weights"]

#: largest phase error of the block-wise steering (rad; module doc)
STEERING_PHASE_RAD = 0.001


def element_offsets_m(array: LineArray) -> np.ndarray:
    """s_n = ((N - 1)/2 - n) d (m), front positive: the offsets (N,) along the axis from the centre of the elements of
    ``array`` (N elements d apart); element 0 (the front) first."""
    return ((array.elements - 1) / 2.0 - np.arange(array.elements)) * array.spacing_m


def cone_grid_deg(n_beams: int) -> np.ndarray:
    """``n_beams`` cone angles uniform in 0..180 deg.

    Parameters
    ----------
    n_beams : int
        Beams, at least 2.

    Returns
    -------
    ndarray, shape (n_beams,)
        Cone angles (deg from the array axis, 0 = ahead), endpoints included.
    """
    require(n_beams >= 2, f"the cone grid needs at least 2 beams, got {n_beams}")
    return np.linspace(0.0, 180.0, int(n_beams))


def plane_wave_delays_s(cone_rad, offsets_m: np.ndarray, sound_speed_mps: float) -> np.ndarray:
    """tau_n = -s_n cos(theta) / c (module doc).

    Parameters
    ----------
    cone_rad : float or array_like (...,)
        Cone angles of arrival (rad, 0 = ahead).
    offsets_m : ndarray (N,)
        Element offsets s_n (m, :func:`element_offsets_m`).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    ndarray (..., N)
        Arrival time at each element relative to the array centre (s).
    """
    return -np.cos(np.asarray(cone_rad, dtype=float))[..., None] * offsets_m / sound_speed_mps


def steering_weights(freqs_hz: np.ndarray, array: LineArray, cone_deg: np.ndarray,
                     sound_speed_mps: float) -> np.ndarray:
    """(1/N) exp(+2 pi i f tau_n(theta_b)) (module doc).

    Parameters
    ----------
    freqs_hz : ndarray (F,)
        Absolute frequencies f (Hz).
    array : LineArray
        Element count and spacing.
    cone_deg : ndarray (B,)
        Beam cone angles (deg).
    sound_speed_mps : float
        Sound speed (m/s).

    Returns
    -------
    ndarray (F, B, N), complex
        The weights of each beam at each frequency.
    """
    tau = plane_wave_delays_s(np.deg2rad(cone_deg), element_offsets_m(array), sound_speed_mps)  # (B, N)
    f = np.asarray(freqs_hz, dtype=float)
    return np.exp(2j * np.pi * f[:, None, None] * tau[None]) / array.elements


def beamform_spectra(spectra: np.ndarray, fs_hz: float, carrier_hz: float, array: LineArray,
                     cone_deg: np.ndarray, sound_speed_mps: float, chunk: int | None = None) -> np.ndarray:
    """Beam spectra Y_b(f) (B, F) of element spectra X_n(f) (N, F) (FFT order, baseband) (module doc).

    Parameters
    ----------
    spectra : ndarray (N, F)
        FFT of each element's baseband samples (``np.fft.fft`` bin order).
    fs_hz : float
        Sample rate (Hz): bin k is at baseband f = fftfreq(F, 1 / fs)[k].
    carrier_hz : float
        Carrier f_c (Hz): the absolute frequency of bin k is f_c + f.
    array : LineArray
        Element count and spacing (acoustics/line_array.py; the count must match N).
    cone_deg : ndarray (B,)
        Beam cone angles (deg, 0 = ahead).
    sound_speed_mps : float
        Sound speed at the array (m/s).
    chunk : int, optional
        Adjacent bins sharing one steering vector (default: as many as keep the phase error below
        ``STEERING_PHASE_RAD``).

    Returns
    -------
    ndarray (B, F), complex64
        The beams' spectra.
    """
    n, n_fft = spectra.shape
    require(n == array.elements, f"the ping has {n} channels but the array {array.elements} elements")
    if chunk is None:
        chunk = steering_chunk(n_fft, fs_hz, array, sound_speed_mps)
    order, w = _block_weights(n_fft, float(fs_hz), float(carrier_hz), array.elements, float(array.spacing_m),
                              tuple(np.asarray(cone_deg, float).tolist()), float(sound_speed_mps), int(chunk))
    n_chunks = w.shape[0]
    padded = np.zeros((n, n_chunks * chunk), dtype=np.complex64)
    padded[:, :n_fft] = spectra[:, order]
    blocks = padded.reshape(n, n_chunks, chunk).transpose(1, 0, 2)  # (C, N, chunk)
    beams = np.matmul(w, blocks).transpose(1, 0, 2).reshape(len(cone_deg), -1)[:, :n_fft]
    out = np.empty_like(beams)
    out[:, order] = beams
    return out


def steering_chunk(n_fft: int, fs_hz: float, array: LineArray, sound_speed_mps: float) -> int:
    """Adjacent bins that share one steering vector: as many as keep the phase error below ``STEERING_PHASE_RAD``.

    Parameters
    ----------
    n_fft : int
        Bins of the ping's spectrum.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        Element count and spacing (m).
    sound_speed_mps : float
        Sound speed (m/s).

    Returns
    -------
    int
        Bins per block (>= 1): a block of W Hz errs by at most pi W (N - 1) d / (2 c) rad (module doc).
    """
    half_aperture_s = (array.elements - 1) * array.spacing_m / (2.0 * sound_speed_mps)
    return max(int(STEERING_PHASE_RAD / max(np.pi * half_aperture_s * fs_hz / n_fft, 1e-300)), 1)


@functools.lru_cache(maxsize=2)
def _block_weights(n_fft, fs_hz, carrier_hz, elements, spacing_m, cone_deg, sound_speed_mps, chunk):
    """(bin order, steering weights (C, B, N) complex64 at each block's centre); cached: every ping of a run has the
    same spectrum size, carrier and beams, so the weights are computed once."""
    order = np.argsort(np.fft.fftfreq(n_fft, 1.0 / fs_hz), kind="stable")
    f_sorted = np.fft.fftfreq(n_fft, 1.0 / fs_hz)[order]
    sums = np.add.reduceat(f_sorted, np.arange(0, n_fft, chunk))
    counts = np.diff(np.r_[np.arange(0, n_fft, chunk), n_fft])
    w = steering_weights(carrier_hz + sums / counts, LineArray(elements, spacing_m), np.array(cone_deg),
                         sound_speed_mps).astype(np.complex64)
    order.flags.writeable = False
    w.flags.writeable = False
    return order, w


def beam_pattern(cone_deg, source_cone_deg: float, n_elements: int, spacing_m: float, freq_hz: float,
                 sound_speed_mps: float) -> np.ndarray:
    """Closed-form |sin(N x) / (N sin x)| of a uniform line steered to ``cone_deg`` (module doc).

    Here x = pi f d (cos theta - cos theta_s) / c.

    Parameters
    ----------
    cone_deg : float or array_like
        Steering cone angles theta (deg from the array axis).
    source_cone_deg : float
        The source's cone angle theta_s (deg).
    n_elements : int
        Elements N.
    spacing_m : float
        Element spacing d (m).
    freq_hz : float
        Frequency f (Hz).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    ndarray
        Amplitude response in 0..1 (1 where sin x = 0), shape of ``cone_deg``.
    """
    x = np.pi * freq_hz * spacing_m * (np.cos(np.deg2rad(cone_deg)) - np.cos(np.deg2rad(source_cone_deg))) \
        / sound_speed_mps
    s = np.sin(x)
    small = np.abs(s) < 1e-12
    return np.abs(np.where(small, 1.0, np.sin(n_elements * x) / (n_elements * np.where(small, 1.0, s))))
