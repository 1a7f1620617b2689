"""Lobe images: a weaker detection at a stronger one's travel time, where the array's beam pattern puts its echo.

A uniform line of N elements d apart, steered to u_b = cos(cone_b), answers a plane wave from u_e = cos(cone_e) at
frequency f with the amplitude |sin(N x) / (N sin x)|, x = pi f d (u_b - u_e) / c (acoustics/active_beams.py
``beam_pattern``). Where sin x = 0 away from u_b = u_e (u_b = u_e +- k c / (f d), k >= 1: a grating lobe, in the
visible region |u| <= 1 once d > c / (2 f) for the echoes near endfire, and everywhere at d >= c / f) the gain is 1:
the echo is heard at full strength in a second beam; elsewhere the sidelobes are bounded by the envelope
1 / (N |sin x|) (-13 dB for the first one). Every beam that hears it places the echo's travel time at its own cone,
so one strong echo (a clutter point, a target) gives detections at several cones, each a pair of mirror contacts in
its own place, and the tracker confirms the ones that recur (issue 34: an 8-element array at 0.8 lambda).

The chain knows its array and band, so it knows where an echo's images fall and how strong they can be: a detection
j of a ping is an image of a stronger detection i of the same ping when

    |t_j - t_i| <= delay_tol_s,   |Doppler cell j - Doppler cell i| <= 1,   P_j <= P_i G(u_j, u_i) 10^(margin_db / 10),

P the matched-filter power at the detection's cell (s mu: the CFAR's mu differs between beams), G the largest
power gain over the band [f_lo, f_hi] of the envelope min(1, 1 / (N sin x)^2) (the envelope rather than the exact
pattern: the nulls move with the cone's error and the band). The image is dropped. The price: a real echo at
the same travel time as a stronger one, no stronger than its lobe there allows, is lost on that ping.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class LobeBand:
    """The array and band that set an echo's lobes: ``elements`` N, ``spacing_m`` d (m), the band ``f_lo_hz`` ..
    ``f_hi_hz`` (Hz), ``sound_speed_mps`` c; ``delay_tol_s`` (s) how close in travel time an image is to its echo
    (the delay resolution), ``margin_db`` (dB) allowed above the envelope's prediction."""

    elements: int
    spacing_m: float
    f_lo_hz: float
    f_hi_hz: float
    sound_speed_mps: float
    delay_tol_s: float
    margin_db: float = 3.0

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
