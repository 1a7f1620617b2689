"""Motion models. Cartesian kinematic state order: [x, y, vx, vy] (m, m/s).

Constant velocity with continuous white-noise acceleration of power spectral density q (m^2/s^3)
(Bar-Shalom, Li, Kirubarajan 2001, sec. 6.2.2; Park, Song, Lee 2017, eq. 1):

    F = [[I, T I], [0, I]],      Q = q [[T^3/3 I, T^2/2 I], [T^2/2 I, T I]]
"""

from __future__ import annotations

import numpy as np


def cv_transition(dt_s: float) -> np.ndarray:
    """F (4 x 4) of the constant-velocity model over ``dt_s`` seconds."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt_s
    return F


def cv_process_noise(dt_s: float, q: float) -> np.ndarray:
    """Q (4 x 4) of the continuous white-noise acceleration model with intensity ``q`` (m^2/s^3)."""
    T = float(dt_s)
    a, b, c = T**3 / 3.0, T**2 / 2.0, T
    return q * np.array([[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]], dtype=float)


def cv_process_noise_stack(dt_s: float, qs) -> np.ndarray:
    """Q for several intensities at once: shape (len(qs), 4, 4) (one per IMM mode)."""
    return np.stack([cv_process_noise(dt_s, q) for q in np.atleast_1d(qs)])


#: position-measurement matrix for [x, y, vx, vy]
H_POSITION = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
