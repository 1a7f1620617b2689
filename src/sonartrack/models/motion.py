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
    """Transition matrix ``F = [[I, T I], [0, I]]`` of the constant-velocity model (Bar-Shalom et al. 2001, sec. 6.2.2).

    Parameters
    ----------
    dt_s : float
        Step T (s).
    dims : int, default 2
        Number of position axes (2: state [x, y, vx, vy]; 1: [bearing, bearing rate]).

    Returns
    -------
    ndarray, shape (2 dims, 2 dims)
        F.
    """
    F = np.eye(2 * dims)
    for i in range(dims):
        F[i, dims + i] = dt_s
    return F


def cv_process_noise(dt_s: float, q: float, dims: int = 2) -> np.ndarray:
    """Process noise ``Q = q [[T^3/3 I, T^2/2 I], [T^2/2 I, T I]]`` of continuous white-noise acceleration.

    Bar-Shalom, Li, Kirubarajan 2001, sec. 6.2.2; Park, Song, Lee 2017, eq. 1.

    Parameters
    ----------
    dt_s : float
        Step T (s).
    q : float
        Power spectral density of the acceleration noise per axis (position unit^2 / s^3: m^2/s^3 in 2-D).
    dims : int, default 2
        Number of position axes.

    Returns
    -------
    ndarray, shape (2 dims, 2 dims)
        Q, in the state order positions then velocities.
    """
    T = float(dt_s)
    a, b, c = T**3 / 3.0, T**2 / 2.0, T
    if dims == 1:
        return q * np.array([[a, b], [b, c]])
    if dims == 2:
        return q * np.array([[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]], dtype=float)
    return q * np.kron(np.array([[a, b], [b, c]]), np.eye(dims))


def cv_process_noise_stack(dt_s: float, qs, dims: int = 2) -> np.ndarray:
    """Process noise matrices for several intensities at once (one per IMM mode).

    Parameters
    ----------
    dt_s : float
        Step T (s).
    qs : float or array_like, shape (r,)
        Acceleration noise power spectral densities (m^2/s^3 in 2-D).
    dims : int, default 2
        Number of position axes.

    Returns
    -------
    ndarray, shape (r, 2 dims, 2 dims)
        Q for each intensity (see :func:`cv_process_noise`).
    """
    return np.stack([cv_process_noise(dt_s, q, dims) for q in np.atleast_1d(qs)])


#: position-measurement matrix for [x, y, vx, vy]
H_POSITION = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
