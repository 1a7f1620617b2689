"""Lobe images: a weaker detection at a stronger echo's travel time, where the array's beam pattern puts that echo.

A uniform line of N elements d apart, steered to u_b = cos(cone_b), answers a plane wave from u_e = cos(cone_e) at
frequency f with the amplitude |sin(N x) / (N sin x)|, x = pi f d (u_b - u_e) / c (Van Trees, Optimum Array
Processing, 2002, eq. 2.96; acoustics/active_beams.py ``beam_pattern``). Where sin x = 0 away from u_b = u_e
(u_b = u_e +- k c / (f d), k >= 1: a grating lobe, in the visible region |u| <= 1 once d > c / (2 f) for the echoes
near endfire, and everywhere at d >= c / f) the gain is 1: the echo is heard at full strength in a second beam;
elsewhere the sidelobes are bounded by the envelope 1 / (N |sin x|) (-13 dB for the first one). Every beam that hears
it places the echo's travel time at its own cone, so one strong echo (a clutter point, a target) gives detections
at several cones, each a pair of mirror contacts in its own place, and the tracker confirms the ones that recur
(issue 34: an 8-element array at 0.33 lambda, 1 kHz, clutter points of TS 29-30 dB; study active-chain trial 1).

The chain knows its array and band, so it knows where an echo's images fall and how strong they can be.
:func:`cell_images` (the test the front end uses) asks, for a detection of a ping at travel time t and Doppler
cell j, whether its echo's power P (the largest beam power within half a main lobe of its cone) is explained by the
power P' of some beam b' outside its main lobe at the same t (within half the delay resolution) and j (+-1):

    P' > P   and   P <= P' G(b, b') 10^(margin_db / 10),

G the conventional beamformer's power pattern (:func:`pattern_power`, element weights ``weights``, uniform by
default as the front end's) from b''s direction into the detection's beam, its largest over the band [f_lo, f_hi]
and over b''s own width (:func:`beam_gain_matrix`). P' is read from the cells, not from the other detections: the
source need not be detected (a CW clutter point sits on its own beam's reverberation ridge, which the front end
notches, so its power is read before the notch, ``PingCells.power``; a detection whose echo peaks in a notched cell
of another beam within half its main lobe is that echo's skirt, and is withheld with it). :func:`lobe_images` is the
older test between detections (the sidelobe envelope between a pair of detections of the same ping). The price of
either: a real echo at the same travel time as a stronger one, no stronger than that one's pattern there allows, is
lost on that ping (tests/detection/test_lobe_cells.py shows both sides).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np


@dataclass(frozen=True, slots=True)
class LobeBand:
    """The array and band that set an echo's lobes: ``elements`` N, ``spacing_m`` d (m), the band ``f_lo_hz`` ..
    ``f_hi_hz`` (Hz), ``sound_speed_mps`` c; ``delay_tol_s`` (s) how close in travel time an image is to its echo
    (the delay resolution), ``margin_db`` (dB) allowed above the pattern's prediction; ``weights`` the elements'
    shading (None: uniform, the front end's conventional beamformer)."""

    elements: int
    spacing_m: float
    f_lo_hz: float
    f_hi_hz: float
    sound_speed_mps: float
    delay_tol_s: float
    margin_db: float = 3.0
    weights: tuple[float, ...] | None = None

    def gain(self, u_beam: np.ndarray, u_echo: np.ndarray, n_freq: int = 9) -> np.ndarray:
        """Largest power gain over the band of the sidelobe envelope min(1, 1 / (N sin x)^2) (module doc), for every
        pair of broadcast ``u_beam`` (cosine of the listening beam's cone) and ``u_echo`` (the echo's)."""
        du = np.asarray(u_beam, float) - np.asarray(u_echo, float)
        f = np.linspace(self.f_lo_hz, self.f_hi_hz, n_freq) if self.f_hi_hz > self.f_lo_hz else np.array(
            [self.f_lo_hz])
        x = np.pi * self.spacing_m * f.reshape((-1,) + (1,) * du.ndim) * du[None] / self.sound_speed_mps
        n_sin2 = (self.elements * np.sin(x)) ** 2
        env = np.where(n_sin2 > 1.0, 1.0 / np.maximum(n_sin2, 1e-300), 1.0)
        return env.max(axis=0)


def lobe_images(cone_deg, travel_time_s, doppler_cell, power, band: LobeBand) -> np.ndarray:
    """The detections of ONE ping that are lobe images of a stronger one (module doc).

    Parameters
    ----------
    cone_deg, travel_time_s : array (n,)
        The detections' cone angles (deg) and travel times (s).
    doppler_cell : array (n,)
        Their Doppler cell indices (all 0 for an LFM).
    power : array (n,)
        Their matched-filter power (any common scale).
    band : LobeBand
        The array and band.

    Returns
    -------
    numpy.ndarray
        (n,) bool: True for an image.
    """
    u = np.cos(np.deg2rad(np.asarray(cone_deg, float)))
    t, j = np.asarray(travel_time_s, float), np.asarray(doppler_cell, np.int64)
    p = np.asarray(power, float)
    n = len(u)
    if n < 2:
        return np.zeros(n, bool)
    near = (np.abs(t[:, None] - t[None, :]) <= band.delay_tol_s) & (np.abs(j[:, None] - j[None, :]) <= 1)
    stronger = p[None, :] > p[:, None]  # [image candidate, source]
    pairs = near & stronger
    if not pairs.any():
        return np.zeros(n, bool)
    allowed = p[None, :] * band.gain(u[:, None], u[None, :]) * 10.0 ** (band.margin_db / 10.0)
    return (pairs & (p[:, None] <= allowed)).any(axis=1)


def pattern_power(band: LobeBand, du: np.ndarray, n_freq: int = 9) -> np.ndarray:
    """The conventional beamformer's power response |sum_n w_n exp(i 2 pi f n d du / c)|^2 / (sum_n w_n)^2 at each
    direction-cosine difference ``du`` = u_beam - u_echo, for every frequency of the band (``n_freq`` of them,
    f_lo .. f_hi; the element weights ``band.weights``, uniform when None): shape (n_freq,) + du.shape. With
    uniform weights it is (sin(N x) / (N sin x))^2, x = pi f d du / c (Van Trees, Optimum Array Processing, 2002,
    eq. 2.96; acoustics/active_beams.py ``beam_pattern``)."""
    du = np.asarray(du, float)
    f = np.linspace(band.f_lo_hz, band.f_hi_hz, n_freq) if band.f_hi_hz > band.f_lo_hz else np.array([band.f_lo_hz])
    w = np.ones(band.elements) if band.weights is None else np.asarray(band.weights, float)
    n = np.arange(band.elements) - 0.5 * (band.elements - 1)
    phase = 2.0 * np.pi * band.spacing_m / band.sound_speed_mps * f.reshape((-1,) + (1,) * du.ndim) * du[None]
    amp = np.tensordot(np.exp(1j * phase[..., None] * n), w, axes=([-1], [0])) / w.sum()
    return np.abs(amp) ** 2


@lru_cache(maxsize=16)
def main_lobe_u(band: LobeBand) -> float:
    """Half-width of the main lobe in direction cosine: the first null (first local minimum) of the pattern at the
    band's top frequency (c / (N d f_hi) for uniform weights; wider for a shaded array)."""
    grid = np.linspace(0.0, 4.0 * band.sound_speed_mps / (band.elements * band.spacing_m * band.f_hi_hz), 801)
    p = pattern_power(replace(band, f_lo_hz=band.f_hi_hz), grid)[0]
    dip = np.nonzero((p[1:-1] <= p[:-2]) & (p[1:-1] <= p[2:]))[0]
    return float(grid[dip[0] + 1]) if dip.size else float(grid[-1])


@lru_cache(maxsize=16)
def beam_gain_matrix(band: LobeBand, u_beams: tuple) -> np.ndarray:
    """(B, B) power gain G[b, b'] (beams at direction cosines ``u_beams``) with which beam b hears an echo from
    beam b''s direction: the pattern's largest value over the band and over the directions beam b' answers for
    (u_b' +- half its step to its neighbours in u: the echo's direction is known only to a beam), 0 inside beam b's
    own main lobe (:func:`main_lobe_u`: a stronger beam there is the same echo's main lobe, not an image's source)."""
    u = np.asarray(u_beams, float)
    step = np.abs(np.diff(u))
    half = 0.5 * np.maximum(np.r_[step, step[-1:]], np.r_[step[:1], step]) if len(u) > 1 else np.zeros(1)
    offsets = np.linspace(-1.0, 1.0, 7)
    du = u[:, None, None] - (u[None, :, None] + half[None, :, None] * offsets[None, None, :])
    gain = pattern_power(band, du).max(axis=(0, 3))
    gain[np.abs(u[:, None] - u[None, :]) < main_lobe_u(band)] = 0.0
    return gain


def cell_images(cells, beam, delay_cell, doppler_cell, cone_deg=None, band: LobeBand | None = None) -> np.ndarray:
    """The detections of ONE ping's ``cells`` (a :class:`~sonartrack.detection.cells.PingCells`) that are sidelobe
    or grating-lobe images of a stronger echo (module doc), as a bool mask.

    Parameters
    ----------
    cells : PingCells
        The ping's cells: ``power`` (the matched-filter power before any notch) or ``statistic`` x ``level``.
    beam, delay_cell, doppler_cell : int arrays (n,)
        The detections' cells.
    cone_deg : array (n,), optional
        Their cone angles (deg; from the beams' power): the echo's strength P is the largest power of the beams
        within half a main lobe of it (a detection on the shoulder of its echo's main lobe is that echo; half, so
        that another echo's main lobe is not taken for it), the pattern taken at that beam. Not given: the beams'.
    band : LobeBand, optional
        The array and band (not given: ``cells.lobes``; neither: no image).

    Returns
    -------
    numpy.ndarray
        (n,) bool: True for an image.
    """
    band = cells.lobes if band is None else band
    b, d, j = (np.asarray(i, np.int64) for i in (beam, delay_cell, doppler_cell))
    if band is None or not len(b):
        return np.zeros(len(b), bool)
    n_d, n_j = cells.statistic.shape[1:]
    delays = np.asarray(cells.delay_s, float)
    step = float(np.median(np.diff(delays))) if n_d > 1 else band.delay_tol_s
    w = max(int(round(0.5 * band.delay_tol_s / step)), 1)
    dd = np.clip(d[:, None] + np.arange(-w, w + 1)[None, :], 0, n_d - 1)  # (n, 2w + 1)
    jj = np.clip(j[:, None] + np.arange(-1, 2)[None, :], 0, n_j - 1)  # (n, 3)
    source = _power(cells, slice(None), dd[:, :, None], jj[:, None, :]).max(axis=(2, 3))  # (B, n)
    u = np.cos(np.deg2rad(np.asarray(cells.cone_deg, float)))
    u_det = u[b] if cone_deg is None else np.cos(np.deg2rad(np.asarray(cone_deg, float)))
    near = np.abs(u[:, None] - u_det[None, :]) <= 0.5 * main_lobe_u(band)  # (B, n): half the detection's main lobe
    at = np.where(near, source, -1.0).argmax(axis=0)  # the beam of the echo's peak near its cone
    own = source[at, np.arange(len(b))]  # the echo's strength, compared with what its sources put in that beam
    gain = beam_gain_matrix(band, tuple(u.tolist()))[at].T  # (B, n)
    explained = np.where(source > own[None, :], source * gain, 0.0).max(axis=0)
    image = own <= explained * 10.0 ** (band.margin_db / 10.0)
    if cells.power is not None:  # the skirt of an echo the front end notched (s = 0 at its peak): withheld with it
        image |= (at != b) & (cells.statistic[at, d, j] <= 0.0)
    return image


def drop_cell_images(det, cells):
    """``det`` (detections of one ping, carrying ``beam``, ``delay_cell``, ``doppler_cell``) without the images
    :func:`cell_images` finds (as it is when ``cells.lobes`` is None)."""
    if cells.lobes is None or len(det) < 1:
        return det
    image = cell_images(cells, det.beam, det.delay_cell, det.doppler_cell, det.cone_deg)
    return type(det)(**{f: np.asarray(getattr(det, f))[~image] for f in type(det).__slots__})


def _power(cells, *idx) -> np.ndarray:
    """The cells' matched-filter power at ``idx``: ``cells.power`` when kept (a CW's, before the ridge notch), else
    s mu (or s when no level is kept)."""
    if cells.power is not None:
        return np.asarray(cells.power[idx], float)
    s = np.asarray(cells.statistic[idx], float)
    return s * cells.level[idx] if cells.level is not None else s
