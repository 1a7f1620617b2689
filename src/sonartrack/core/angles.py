"""Angles: the single wrap function every angular residual goes through.

Convention (DESIGN.md): bearing clockwise from north, ``bearing = atan2(dx, dy)``, in (-pi, pi].
"""

import numpy as np

TWO_PI = 2.0 * np.pi


def wrap_angle(angle_rad):
    """Wrap angles to the half-open interval (-pi, pi].

    ``wrap(a) = a - 2 pi * ceil((a - pi) / (2 pi))``: exact at the boundaries, so ``wrap(pi) == pi``
    and ``wrap(-pi) == pi``. Every angular residual in the package goes through this function.

    Parameters
    ----------
    angle_rad : float or array_like
        Angles (rad), any shape.

    Returns
    -------
    float or ndarray
        Wrapped angles (rad), same shape; a float for a scalar input.
    """
    a = np.asarray(angle_rad, dtype=float)
    wrapped = a - TWO_PI * np.ceil((a - np.pi) / TWO_PI)
    return wrapped if wrapped.ndim else float(wrapped)


def bearing_rad(dx, dy):
    """Bearing of a displacement, clockwise from north: ``atan2(dx, dy)`` in (-pi, pi].

    Parameters
    ----------
    dx : float or array_like
        East component of the displacement from the observer to the target (m).
    dy : float or array_like
        North component (m), broadcast with ``dx``.

    Returns
    -------
    float or ndarray
        Bearing (rad, clockwise from north, 0 = north, pi/2 = east).
    """
    return wrap_angle(np.arctan2(dx, dy))


def heading_unit(heading_rad):
    """Unit vector ``[east, north] = [sin h, cos h]`` of a heading measured clockwise from north.

    Parameters
    ----------
    heading_rad : float or array_like, shape (...)
        Heading (rad, clockwise from north).

    Returns
    -------
    ndarray, shape (..., 2)
        Unit vectors [east, north].
    """
    h = np.asarray(heading_rad, dtype=float)
    return np.stack([np.sin(h), np.cos(h)], axis=-1)
