"""Coordinated turn at a known rate: the linear transition of [x, y, vx, vy] and its exact white-noise process noise.

A target turning at a constant rate w (rad/s, counter-clockwise positive in x east, y north) keeps its speed
while its velocity rotates: ``dp/dt = v``, ``dv/dt = Omega v + a`` with ``Omega = [[0, -w], [w, 0]]`` and ``a``
white acceleration noise of power spectral density q per axis. With w known the model is linear (Bar-Shalom, Li,
Kirubarajan 2001, sec. 11.7.1, eq. 11.7.1-4; Li & Jilkov 2003, "Survey of maneuvering target tracking. Part I",
sec. V.A, eq. 49), over a step T with s = sin wT, c = cos wT:

    F = [[1, 0,  s/w,      -(1-c)/w],
         [0, 1,  (1-c)/w,   s/w    ],
         [0, 0,  c,        -s      ],
         [0, 0,  s,         c      ]]

The process noise is the exact integral ``Q = q int_0^T Phi(t) G G^T Phi(t)^T dt`` (G = [0; I]) of that
system, worked here in closed form (the velocity part rotates, an orthogonal map, so isotropic noise stays
isotropic):

    Q_pp = q 2 (wT - s) / w^3 I,     Q_vv = q T I,
    Q_pv = q [[(1-c)/w^2, (wT-s)/w^2], [-(wT-s)/w^2, (1-c)/w^2]]

Both tend to the constant-velocity model's F and Q (models/motion.py: T, T^3/3, T^2/2) as w -> 0. They are computed
through functions of x = wT that stay accurate there: sin x / x and (1 - cos x) / x^2 = (sin(x/2) / (x/2))^2 / 2 by
``np.sinc``, and (x - sin x) / x^3 by its Taylor series below |x| = 1/2 (the difference loses digits there).
"""

from __future__ import annotations

import numpy as np


def _sin_x(x: float) -> float:
    """sin x / x (1 at 0)."""
    return float(np.sinc(x / np.pi))


def _one_minus_cos_x2(x: float) -> float:
    """(1 - cos x) / x^2 (1/2 at 0)."""
    return 0.5 * float(np.sinc(x / (2.0 * np.pi))) ** 2


def _x_minus_sin_x3(x: float) -> float:
    """(x - sin x) / x^3 (1/6 at 0): sum_k (-1)^k x^2k / (2k + 3)! below |x| = 1/2 (terms to x^14: < 1e-17)."""
    if abs(x) >= 0.5:
        return (x - np.sin(x)) / x**3
    term, total, x2 = 1.0 / 6.0, 0.0, x * x
    for k in range(8):
        total += term
        term *= -x2 / ((2 * k + 4) * (2 * k + 5))
    return total


def ct_transition(dt_s: float, turn_rate_rad_s: float) -> np.ndarray:
    """Transition matrix F of the coordinated turn at a known rate (module docstring; Bar-Shalom et al. 2001, eq.
    11.7.1-4).

    Parameters
    ----------
    dt_s : float
        Step T (s).
    turn_rate_rad_s : float
        Turn rate w (rad/s; counter-clockwise positive with x east, y north); 0 gives the constant-velocity F.

    Returns
    -------
    ndarray, shape (4, 4)
        F for the state [x, y, vx, vy] (m, m/s).
    """
    T = float(dt_s)
    x = float(turn_rate_rad_s) * T
    sw, cw = T * _sin_x(x), T * x * _one_minus_cos_x2(x)  # sin(wT) / w, (1 - cos wT) / w
    c, s = np.cos(x), np.sin(x)
    return np.array([[1.0, 0.0, sw, -cw], [0.0, 1.0, cw, sw], [0.0, 0.0, c, -s], [0.0, 0.0, s, c]])


def ct_process_noise(dt_s: float, q: float, turn_rate_rad_s: float) -> np.ndarray:
    """Exact process noise Q of the coordinated turn with white acceleration noise q per axis (module docstring).

    Parameters
    ----------
    dt_s : float
        Step T (s).
    q : float
        Power spectral density of the acceleration noise per axis (m^2/s^3).
    turn_rate_rad_s : float
        Turn rate w (rad/s); 0 gives the constant-velocity Q (models/motion.py ``cv_process_noise``).

    Returns
    -------
    ndarray, shape (4, 4)
        Q in the state order [x, y, vx, vy].
    """
    T = float(dt_s)
    x = float(turn_rate_rad_s) * T
    f3 = _x_minus_sin_x3(x)
    pp, b, d = 2.0 * T**3 * f3, T**2 * _one_minus_cos_x2(x), T**2 * x * f3  # 2(wT-s)/w^3, (1-c)/w^2, (wT-s)/w^2
    return q * np.array([[pp, 0.0, b, d], [0.0, pp, -d, b], [b, -d, T, 0.0], [d, b, 0.0, T]])
