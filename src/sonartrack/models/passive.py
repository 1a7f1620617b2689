"""Passive bearing + frequency measurements of a relative state, their Jacobians, and the MGEKF's
modified matrix.

State order (models/relative_motion.py): X = [x, y, vx, vy, f0] -- target position and velocity
relative to the observer (m, m/s; x east, y north) and the emitted frequency f0 (Hz).

Measurement (Yoo & Song, paper P2, eq. 3, written with the bearing clockwise from north as in
DESIGN.md)::

    bearing    b = atan2(x, y)                                   (+ v_b, v_b ~ N(0, sigma_b^2))
    frequency  f = f0 (1 - rdot / c),  rdot = (x vx + y vy) / r,  r = sqrt(x^2 + y^2)
                                                                  (+ v_f, v_f ~ N(0, sigma_f^2))

Jacobian rows (r^2 = x^2 + y^2, s = x vx + y vy, w = y vx - x vy)::

    db/dX = [ y / r^2, -x / r^2, 0, 0, 0 ]
    drdot/dX(kinematic) = [ y w / r^3, -x w / r^3, x / r, y / r ]
    df/dX = [ -(f0/c) y w / r^3, (f0/c) x w / r^3, -(f0/c) x / r, -(f0/c) y / r, 1 - rdot / c ]

Modifiability (Song & Speyer 1985; DIGEST P2). h is *modifiable* when h(X) - h(X_hat) =
g(z, X_hat) (X - X_hat) for every X that produces the noise-free measurement z = h(X).

* Bearing row -- modifiable. With X on the bearing line (x = r sin z, y = r cos z) and
  X_hat = r_hat [sin b_hat, cos b_hat]::

      cos z (x - x_hat) - sin z (y - y_hat) = r_hat sin(z - b_hat)
      x_hat sin z + y_hat cos z             = r_hat cos(z - b_hat)

  so ``g = [cos z, -sin z, 0, 0, 0] / (x_hat sin z + y_hat cos z)`` gives g (X - X_hat) =
  tan(z - b_hat) = tan(h(X) - h(X_hat)): the Song & Speyer bearing function (DIGEST P2), exact
  in the tangent of the residual and equal to h(X) - h(X_hat) to O(d^3), d = z - b_hat. Scaling g
  by d / tan d (both known from z and X_hat) makes the relation exact in the residual itself
  (``exact=True``). As X_hat -> X, g -> the Jacobian row [y/r^2, -x/r^2, 0, 0, 0].

* Frequency row -- NOT modifiable while f0 is a state. If it were, every X with h_f(X) = z_f would
  satisfy the single linear equation g X = z_f - h_f(X_hat) + g X_hat, i.e. the level set would lie
  in a hyperplane of R^5. It does not: the states (r sin a, r cos a, 0, 0, z_f) lie on it for
  every r, a (spanning the x and y directions); (1, 0, c (1 - z_f / f0), vy, f0) lies on it for
  every vy and f0 > 0, and along f0 the point moves on the curve (c (1 - z_f/f0), f0), which spans
  both the vx and the f0 directions. The level set's affine hull is all of R^5, so only g = 0 could
  work, and g = 0 fails whenever z_f != h_f(X_hat). Using the bearing measurement as well gives
  no usable g either: on the bearing ray the level set f0 (c - vx sin z - vy cos z) = c z_f is
  curved in (vx, vy, f0), so its affine hull is the whole ray x R^3 and the only g left is the
  degenerate one along the across-the-line direction n = [cos z, -sin z, 0, 0, 0],
  g = (z_f - h_f(X_hat)) / (n . (X - X_hat)) n = -(z_f - h_f(X_hat)) / (n . X_hat) n, which divides by
  the estimate's distance from the measured bearing line (unbounded exactly when the filter is doing
  well) and ignores velocity and f0. With f0 *known* the level set would be flat (the radial velocity
  vx sin z + vy cos z = c (1 - z_f / f0)) and a proper g with velocity components would exist; it is
  the bilinear f0 * rdot term that breaks modifiability. The MGEKF therefore
  uses the EKF Jacobian for the frequency row. tests/models/test_passive.py checks both results
  numerically.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle

#: speed of sound used by the frequency model unless told otherwise (m/s; DIGEST P2)
SOUND_SPEED_MPS = 1500.0

#: the modified-matrix denominator r_hat cos(z - b_hat) below this fraction of r_hat (|z - b_hat|
#: above ~84 deg) means the estimate is nowhere near the bearing line; g would blow up, so the
#: Jacobian row is used instead.
MIN_COS_DELTA = 0.1


def bf_measurement(X, c: float = SOUND_SPEED_MPS):
    """Bearing + frequency measurement ``h(X) = [atan2(x, y), f0 (1 - rdot / c)]`` (paper P2, eq. 3).

    Parameters
    ----------
    X : array_like, shape (..., 5)
        Relative states [x, y, vx, vy, f0] (m, m/s, Hz; x east, y north, target minus observer).
    c : float, default 1500.0
        Sound speed (m/s).

    Returns
    -------
    ndarray, shape (..., 2)
        Bearing (rad, clockwise from north, in (-pi, pi]) and received frequency (Hz).
    """
    X = np.asarray(X, dtype=float)
    x, y, vx, vy, f0 = (X[..., i] for i in range(5))
    r = np.hypot(x, y)
    rdot = (x * vx + y * vy) / r
    return np.stack([np.arctan2(x, y), f0 * (1.0 - rdot / c)], axis=-1)


def bearing_measurement(X):
    """Bearing ``h_b(X) = atan2(x, y)`` of relative states.

    Parameters
    ----------
    X : array_like, shape (..., >= 2)
        Relative states, first two entries x east and y north (m).

    Returns
    -------
    ndarray, shape (...)
        Bearing (rad, clockwise from north, in (-pi, pi]).
    """
    X = np.asarray(X, dtype=float)
    return np.arctan2(X[..., 0], X[..., 1])


def bf_jacobian(X, c: float = SOUND_SPEED_MPS):
    """Jacobian dh/dX of :func:`bf_measurement` (rows in the module docstring).

    Parameters
    ----------
    X : array_like, shape (..., 5)
        Relative states [x, y, vx, vy, f0] (m, m/s, Hz).
    c : float, default 1500.0
        Sound speed (m/s).

    Returns
    -------
    ndarray, shape (..., 2, 5)
        Rows: bearing (rad per state unit), frequency (Hz per state unit).
    """
    X = np.asarray(X, dtype=float)
    x, y, vx, vy, f0 = (X[..., i] for i in range(5))
    r2 = x * x + y * y
    r = np.sqrt(r2)
    r3 = r2 * r
    w = y * vx - x * vy
    rdot = (x * vx + y * vy) / r
    k = f0 / c
    H = np.zeros(X.shape[:-1] + (2, 5))
    H[..., 0, 0] = y / r2
    H[..., 0, 1] = -x / r2
    H[..., 1, 0] = -k * y * w / r3
    H[..., 1, 1] = k * x * w / r3
    H[..., 1, 2] = -k * x / r
    H[..., 1, 3] = -k * y / r
    H[..., 1, 4] = 1.0 - rdot / c
    return H


def bearing_modified_row(z_b, X_hat, exact: bool = False):
    """Song & Speyer's modified row g(z, X_hat) for the bearing measurement (Song & Speyer 1985; DIGEST P2).

    ``g = [cos z, -sin z, 0, 0, 0] / (x_hat sin z + y_hat cos z)`` (see the module docstring):
    g (X - X_hat) = tan(z - b_hat) for every X on the bearing line z. With ``exact=True`` the row is
    scaled by d / tan d, d = wrap(z - b_hat), so that g (X - X_hat) = z - b_hat exactly. Where the
    denominator is below ``MIN_COS_DELTA * r_hat`` the Jacobian row is returned.

    Parameters
    ----------
    z_b : float or array_like, shape (...)
        Measured bearing (rad, clockwise from north).
    X_hat : array_like, shape (..., n), n >= 2
        Estimated relative state (x, y first, m).
    exact : bool, default False
        Scale the row so the relation holds in the residual rather than its tangent.

    Returns
    -------
    ndarray, shape (..., n)
        g (rad per state unit); zero beyond the position entries.
    """
    X_hat = np.asarray(X_hat, dtype=float)
    z = np.asarray(z_b, dtype=float)
    x, y = X_hat[..., 0], X_hat[..., 1]
    sz, cz = np.sin(z), np.cos(z)
    den = x * sz + y * cz
    r = np.hypot(x, y)
    ok = den > MIN_COS_DELTA * r
    safe = np.where(ok, den, 1.0)
    scale = 1.0 / safe
    if exact:
        d = np.asarray(wrap_angle(z - np.arctan2(x, y)))
        td = np.tan(d)
        small = np.abs(d) < 1e-8
        scale = scale * np.where(small, 1.0, d / np.where(small, 1.0, td))
    g = np.zeros(X_hat.shape[:-1] + (X_hat.shape[-1],))
    g[..., 0] = np.where(ok, cz * scale, y / (r * r))
    g[..., 1] = np.where(ok, -sz * scale, -x / (r * r))
    return g


def modified_matrix(z, X_hat, H, exact: bool = False):
    """The MGEKF's modified matrix G: H with its bearing row (row 0) replaced by g(z_b, X_hat).

    The frequency row (if any) keeps its Jacobian, since it is not modifiable (module docstring).

    Parameters
    ----------
    z : array_like, shape (..., m)
        Measurement, bearing (rad, clockwise from north) in entry 0.
    X_hat : array_like, shape (..., 5)
        Predicted relative state.
    H : array_like, shape (..., m, 5)
        Jacobian at X_hat.
    exact : bool, default False
        Passed to :func:`bearing_modified_row`.

    Returns
    -------
    ndarray, shape (..., m, 5)
        G (a new array).
    """
    z = np.asarray(z, dtype=float)
    G = np.array(H, dtype=float, copy=True)
    G[..., 0, :] = bearing_modified_row(z[..., 0], X_hat, exact=exact)
    return G


def bf_residual(z, hx):
    """Measurement residual ``z - h`` with the bearing component (index 0) wrapped to (-pi, pi].

    Parameters
    ----------
    z : array_like, shape (..., m)
        Measurement (bearing in rad, then frequency in Hz).
    hx : array_like, shape (..., m)
        Predicted measurement.

    Returns
    -------
    ndarray, shape (..., m)
        Residual (a new array).
    """
    nu = np.asarray(z, dtype=float) - np.asarray(hx, dtype=float)
    nu = np.array(nu, copy=True)
    nu[..., 0] = wrap_angle(nu[..., 0])
    return nu
