"""The line array's bearing noise law and the ML weighted by it: sigma_theta = sigma_u / max(|sin theta|, 0.05),
white in u = cos(theta) (moved out of systems/passive/targets.py, whose ML uses it).

A line array measures u = cos(theta) with about the same error at every cone angle theta, so the cone angle's error
grows as 1 / |sin theta| towards endfire (Van Trees, Optimum Array Processing, 2002, sec. 2.4);
:func:`line_array_relative_sigma` is that law relative to broadside, :func:`u_weighted_fit` the bearings-only ML of
the decided side's bearings with each weighted by it and sigma_u measured from the weighted residuals, and
:func:`endfire_reach_rad` how far from the axis the endfire beam reaches.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.tma.record_verdict import (  # the checks shared with ``sonartrack tma``; re-exported for the chain
    UNSUPPORTED_RANGE,  # noqa: F401
    )


def endfire_reach_rad(beamwidth_deg: float) -> float:
    """How far from the array's axis (rad) its endfire beam reaches: arccos(1 - du / 2) for the broadside half-power
    width du = ``beamwidth_deg`` in rad, the width in u = cos(theta) of every beam (Van Trees, Optimum Array
    Processing, 2002, sec. 2.4)."""
    return float(np.arccos(max(1.0 - 0.5 * np.deg2rad(beamwidth_deg), -1.0)))


#: |sin theta| below which the noise law sigma_theta = sigma_u / |sin theta| is not followed further
#: (:func:`line_array_relative_sigma`; 2.9 deg from the axis). Measured on the passive-chain study's peaks (32 trials,
#: seed 2017, every matched target's cone-angle errors against the truth, 1.4826 MAD): sd_theta |sin theta| is
#: 0.021-0.041 deg in every band of |sin theta| from 0-0.1 to 0.95-1 (sd_theta 0.64 deg below 0.1, 0.030 deg at
#: broadside), so the law holds to within a few degrees of the axis; a floor at the endfire beam's reach
#: (:func:`endfire_reach_rad`, |sin| 0.18-0.32 for the study's 1.8-6 deg beams) understated the noise there ~4 times
MIN_SIN_CONE = 0.05
#: smallest sigma_u (rad) the weighted ML may measure (:func:`u_weighted_fit`): 0.02 deg, below every band of the
#: table above (0.021-0.041 deg in u), so it only keeps a noise-free record finite. The side decision's 0.1 deg floor
#: (tma/sides.py ``SIGMA_FLOOR_RAD``, a floor on sigma_theta) is 2.5-5 times the measured sigma_u: used for sigma_u it
#: overstated the ML covariance 6-25 times (passive-chain study: median ML NEES 0.37 against chi-square(4)'s 3.36;
#: with this floor 0.91, ML ANEES 1.5 -> 2.4, 37 % -> 64 % of the single NEES inside chi2(4) 95 %)
SIGMA_U_FLOOR_RAD = float(np.deg2rad(0.02))


def line_array_relative_sigma(cone_rad, min_sin: float = MIN_SIN_CONE) -> np.ndarray:
    """Each cone angle's noise relative to broadside: 1 / max(|sin theta|, ``min_sin``).

    A line array measures the direction cosine u = cos(theta) with one noise sigma_u at every steering angle (its
    beam has one width in u, Van Trees, Optimum Array Processing, 2002, sec. 2.4; the CRB of u, sec. 8.5), so
    sigma_theta = sigma_u / |sin theta|, floored at :data:`MIN_SIN_CONE` so that a peak on the axis keeps a finite
    weight. E.g. at 30 deg twice broadside's, at 90 deg 1, at 0 deg 20.

    Parameters
    ----------
    cone_rad : ndarray (n,)
        Cone angles (rad; unfolded angles alike: |sin| is the same for every image through the axis).
    min_sin : float
        The floor of |sin theta|.

    Returns
    -------
    ndarray (n,)
        sigma_theta / sigma_u (>= 1).
    """
    return 1.0 / np.maximum(np.abs(np.sin(np.asarray(cone_rad, float))), min_sin)


def u_weighted_fit(chosen_rad, time_s, sensor_xy, relative_sigma, start) -> tuple[object, float] | None:
    """The decided side's constant-velocity ML with each bearing weighted by the line array's noise law
    (:func:`line_array_relative_sigma`): min sum_n (wrap(z_n - h_n(x)) / r_n)^2 (paper P3, eq. 4, with per-bearing
    sigma_n = sigma_u r_n), started from the side decision's equal-weight fit. sigma_u^2 = J / (n - 4), the
    unbiased estimate from the weighted residuals (as the side decision measures sigma, tma/sides.py), floored at
    :data:`SIGMA_U_FLOOR_RAD` (a floor in u, not the side decision's floor in bearing); the covariance is
    (H^T W H)^-1 sigma_u^2.

    Parameters
    ----------
    chosen_rad, time_s : ndarray (n,)
        The decided side's true bearings (rad) and their times (s).
    sensor_xy : ndarray (n, 2)
        The array centre (m).
    relative_sigma : ndarray (n,)
        r_n, each bearing's noise relative to sigma_u.
    start : BatchEstimate
        The side decision's fit of the same record.

    Returns
    -------
    (BatchEstimate, float) or None
        The fit (covariance scaled by sigma_u^2) and sigma_u (rad); None when the fit fails.
    """
    from sonartrack.tma.batch_ml import ml_bearings_only

    t = np.asarray(time_s, float)
    try:
        with np.errstate(invalid="ignore", over="ignore"):
            est = ml_bearings_only(chosen_rad, t, sensor_xy, relative_sigma, x_init=start.x0, check=False)
    except (InputError, np.linalg.LinAlgError, FloatingPointError):
        return None
    if not (np.isfinite(est.objective) and np.all(np.isfinite(est.x0))):
        return None
    sigma_u = max(float(np.sqrt(est.objective / max(len(t) - 4, 1))), SIGMA_U_FLOOR_RAD)
    return replace(est, covariance=np.asarray(est.covariance) * sigma_u**2), sigma_u
