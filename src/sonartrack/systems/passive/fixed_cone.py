"""The fixed-cone test: bearings that one cone angle fixed in the array's frame explains as well as a
constant-velocity target (a source moving with the array: own-ship or array noise) leave the range not determined
(moved out of systems/passive/targets.py, which runs it on every target before its ML is judged).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.systems.passive.line_array_noise import SIGMA_U_FLOOR_RAD
from sonartrack.tma.record_checks import (
    RESIDUAL_ALPHA,
)
from sonartrack.tma.record_verdict import (  # the checks shared with ``sonartrack tma``; re-exported for the chain
    UNSUPPORTED_RANGE,  # noqa: F401
)
from sonartrack.tma.record_verdict import fit_at_bearings as _fit_at_bearings
from sonartrack.tma.solve import TmaResult

#: fewest bearings for the fixed-cone test (:func:`fixed_cone_note`): the CV fit's 4 parameters and 2 dof left
MIN_FIXED_CONE_POINTS = 6


def fixed_cone_cost(cone_rad, relative_sigma) -> float:
    """J_0 = min_c sum_n ((theta_n - c) / r_n)^2: the weighted cost of one cone angle c fixed in the array's frame,
    in the units of the line array's noise law (:func:`line_array_relative_sigma`, r_n; the residual of the bearing
    h_n +- c is +-(theta_n - c), so this is the bearing cost of :func:`u_weighted_fit` for that model). Quadratic in
    c: c is the weighted mean of theta_n with weights 1 / r_n^2 (unfolded cone angles alike; a track through
    endfire has no one cone angle and costs much)."""
    theta = np.asarray(cone_rad, float)
    w = 1.0 / np.asarray(relative_sigma, float) ** 2 * np.ones_like(theta)
    c = float(np.sum(w * theta) / np.sum(w))
    return float(np.sum(w * (theta - c) ** 2))


def fixed_cone_f(j0: float, j_cv: float, n: int, alpha: float = RESIDUAL_ALPHA) -> tuple[float, float]:
    """(F, its critical value at ``1 - alpha``) of the extra sum of squares of the CV target's 3 more parameters
    over one fixed cone angle (Bates & Watts, Nonlinear Regression Analysis and Its Applications, 1988, sec. 3.10;
    the form of systems/passive/narrowband.py's join test):

        F = ((J_0 - J_cv) / 3) / (s2 = max(J_cv / (n - 4), sigma_u floor^2))   ~   F(3, n - 4)

    with J the weighted costs of :func:`fixed_cone_cost` and of the CV ML, s2 as :func:`u_weighted_fit` measures
    sigma_u^2. F below the critical value (also negative: the fixed cone fits better; or NaN): the CV target is not
    needed to explain the bearings."""
    from scipy.special import fdtri  # the F quantile without scipy.stats' import cost

    s2 = max(j_cv / (n - 4), SIGMA_U_FLOOR_RAD**2)
    return (j0 - j_cv) / 3.0 / s2, float(fdtri(3, n - 4, 1.0 - alpha))


def fixed_cone_note(bearings_ml: TmaResult, cone_rad, relative_sigma) -> str | None:
    """Why a track's bearings give no range because one cone angle fixed in the array's frame explains them as well
    as the CV target does, or None (:func:`solve_target` then reports every row of its ML undetermined, reason
    :data:`~sonartrack.tma.verdict.FIXED_CONE`, and fits no bearings + frequency ML).

    A source moving with the array (own-ship or array self-noise, a towed body, an artefact of the processing) keeps
    its cone angle whatever the array does, and a source at any range along that cone gives the same cone angles:
    the bearings hold no range however the array turns (the maneuver that makes a CV target observable, Nardone &
    Aidala 1981, moves this source with it). The CV ML still fits it, as a target near the array moving with it, and
    its covariance states a range. The test (:func:`fixed_cone_f`): the CV fit's 3 more parameters must lower the
    weighted cost of the bearings significantly (F at 1 - :data:`RESIDUAL_ALPHA`) below that of one fixed cone
    angle (:func:`fixed_cone_cost`), both with the line array's noise law (``relative_sigma``). On a straight leg the
    fixed cone is a CV target moving with the array (the models are nested); through a turn it is not, and a fixed
    cone fitting better than the CV target (F < 0) says the same. Made whatever the ML's own verdict, since a
    bearings + frequency ML would be fitted next: a source moving with the array has no Doppler, its line's
    frequency is its own, whatever it does, and holds no range either.

    Parameters
    ----------
    bearings_ml : TmaResult
        The bearings-only CV ML of the track's bearings (its weighted cost J_cv).
    cone_rad : ndarray (n,)
        The record's cone angles (rad; unfolded through endfire alike).
    relative_sigma : float or ndarray (n,)
        Each bearing's noise relative to sigma_u, as the ML weighted it.

    Returns
    -------
    str or None
        The test's line when the fixed cone explains the bearings, else None (also with too few bearings or a CV
        fit that is not finite).
    """
    n = len(np.asarray(cone_rad))
    if n < MIN_FIXED_CONE_POINTS:
        return None
    _, z, own, at_t = _fit_at_bearings(bearings_ml)
    e = wrap_angle(z - np.arctan2(at_t[:, 0] - own[:, 0], at_t[:, 1] - own[:, 1])) / relative_sigma
    j_cv = float(np.sum(e**2))
    if not np.isfinite(j_cv):
        return None
    f, critical = fixed_cone_f(fixed_cone_cost(cone_rad, relative_sigma), j_cv, n)
    if f >= critical:
        return None
    return (f"one cone angle fixed to the array explains the {n} bearings as well as the CV target (F = {f:.3g} < "
            f"{critical:.3g}, the {1 - RESIDUAL_ALPHA:.3g} point of F(3, {n - 4})): a source moving with the array, "
            "at any range along its cone")
