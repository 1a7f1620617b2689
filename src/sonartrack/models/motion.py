"""Motion models. Kinematic state order: positions, then velocities ([x, y, vx, vy] in 2-D, m and m/s;
[bearing, bearing rate] in 1-D, deg and deg/s for the bearing tracker).

Constant velocity with continuous white-noise acceleration of power spectral density q per axis
(Bar-Shalom, Li, Kirubarajan 2001, sec. 6.2.2; Park, Song, Lee 2017, eq. 1), for ``dims`` axes:

    F = [[I, T I], [0, I]],      Q = q [[T^3/3 I, T^2/2 I], [T^2/2 I, T I]]

(unit of q: position unit^2 / s^3, m^2/s^3 in 2-D).
"""

from __future__ import annotations

import numpy as np


def cv_transition(dt_s: float, dims: int = 2) -> np.ndarray:
    """F (2 dims x 2 dims) of the constant-velocity model over ``dt_s`` seconds."""
    F = np.eye(2 * dims)
    for i in range(dims):
        F[i, dims + i] = dt_s
    return F


def cv_process_noise(dt_s: float, q: float, dims: int = 2) -> np.ndarray:
    """Q (2 dims x 2 dims) of the continuous white-noise acceleration model with intensity ``q``."""
    T = float(dt_s)
    a, b, c = T**3 / 3.0, T**2 / 2.0, T
    if dims == 1:
        return q * np.array([[a, b], [b, c]])
    if dims == 2:
        return q * np.array([[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]], dtype=float)
    return q * np.kron(np.array([[a, b], [b, c]]), np.eye(dims))


def cv_process_noise_stack(dt_s: float, qs, dims: int = 2) -> np.ndarray:
    """Q for several intensities at once: shape (len(qs), 2 dims, 2 dims) (one per IMM mode)."""
    return np.stack([cv_process_noise(dt_s, q, dims) for q in np.atleast_1d(qs)])


#: position-measurement matrix for [x, y, vx, vy]
H_POSITION = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
