"""Angles: the single wrap function every angular residual goes through.

Convention (DESIGN.md): bearing clockwise from north, ``bearing = atan2(dx, dy)``, in (-pi, pi].
"""

import numpy as np

TWO_PI = 2.0 * np.pi


def wrap_angle(angle_rad):
    """Wrap angles to the half-open interval (-pi, pi].

    ``wrap(a) = a - 2 pi * ceil((a - pi) / (2 pi))``: exact at the boundaries, so ``wrap(pi) == pi``
    and ``wrap(-pi) == pi``. Works elementwise on scalars and arrays.
    """
    a = np.asarray(angle_rad, dtype=float)
    wrapped = a - TWO_PI * np.ceil((a - np.pi) / TWO_PI)
    return wrapped if wrapped.ndim else float(wrapped)


def bearing_rad(dx, dy):
    """Bearing clockwise from north of the displacement (dx east, dy north), in (-pi, pi]."""
    return wrap_angle(np.arctan2(dx, dy))


def heading_unit(heading_rad):
    """Unit vector [east, north] of a heading measured clockwise from north."""
    h = np.asarray(heading_rad, dtype=float)
    return np.stack([np.sin(h), np.cos(h)], axis=-1)
