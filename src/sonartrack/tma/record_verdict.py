"""A TMA solution judged by its own record: the checks of tma/record_checks.py turned into a verdict, shared by
``sonartrack tma`` (tma/motion_verdict.py) and the passive chain (systems/passive/targets.py).

* :func:`determination_checked` -- a determined ML range whose residuals disagree with the stated noise has its
  covariance widened by their measured scale (or, beyond :data:`~sonartrack.tma.record_checks.MAX_RESIDUAL_SCALE`,
  is not determined); one whose profile likelihood is flatter than its covariance claims is not determined;
* :func:`batch_held` -- a sequential filter held to the batch ML of the same record: the ML's reason where it is
  not determined, else :data:`~sonartrack.tma.verdict.DISAGREES_WITH_BATCH` when their final positions differ
  beyond what their covariances allow, else the filter's last covariance raised to the ML's;
* :func:`undetermined` -- every row of a result not determined, with the reason and a warning beginning
  :data:`UNSUPPORTED_RANGE`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.core.linalg import covariance_max
from sonartrack.models.motion import cv_transition
from sonartrack.tma.record_checks import (
    MAX_RESIDUAL_SCALE,
    PROFILE_FAR_FACTOR,
    PROFILE_MIN_RISE,
    PROFILE_SIGMAS,
    RESIDUAL_ALPHA,
    range_profile_rise,
    residual_check,
    residual_scale,
)
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult, correlation_inflation
from sonartrack.tma.verdict import DISAGREES_WITH_BATCH, FLAT_LIKELIHOOD, INCONSISTENT_RESIDUALS, with_reasons

#: how the warning of a range the record does not support begins (:func:`determination_checked`)
UNSUPPORTED_RANGE = "range not supported by the record:"


def _filter_name(result: TmaResult) -> str:
    """The filter's name as the warnings print it ("IMM-MGEKF")."""
    return str(result.solution.method).upper()


def _residual_inflation(result: TmaResult, relative_sigma=1.0) -> tuple[float, float, str | None]:
    """(kappa, s2, note) of a determined ML solution: kappa the correlation inflation it states, s2 >= 1 the
    variance factor its residuals measure beyond kappa (1 when they are consistent), and the residual test's line
    when s2 > 1; the residuals whitened by each bearing's ``relative_sigma`` (:func:`line_array_relative_sigma`)."""
    t, z, own, at_t = fit_at_bearings(result)
    e = wrap_angle(z - np.arctan2(at_t[:, 0] - own[:, 0], at_t[:, 1] - own[:, 1])) / relative_sigma
    kappa = correlation_inflation(e) if result.settings.batch.correlation_inflation else 1.0
    check = residual_check(t, e, float(np.deg2rad(result.settings.sigma_bearing_deg)), inflation=kappa)
    if check.consistent:
        return kappa, 1.0, None
    return kappa, residual_scale(check), check.note()


def fit_at_bearings(result: TmaResult):
    """(times, bearings, sensor positions, the solution's states) at the record's bearings."""
    t = np.asarray(result.record.time_s, float)
    z = np.asarray(result.record.bearing_rad, float)
    ts, state = np.asarray(result.solution.time_s, float), np.asarray(result.solution.state, float)
    own = result.ownship.position_at(t)
    return t, z, own, np.stack([np.interp(t, ts, state[:, k]) for k in range(4)], axis=1)


def _flat_likelihood_note(result: TmaResult, variance_factor: float, relative_sigma=1.0) -> str | None:
    """Why a determined ML range is not what its record supports by the profile test, or None."""
    t, z, own, at_t = fit_at_bearings(result)
    sigma = float(np.deg2rad(result.settings.sigma_bearing_deg)) * np.broadcast_to(relative_sigma, t.shape)
    cols = solution_columns(result.solution, result.ownship)
    r, sd = float(cols["range_m"][-1]), float(cols["range_std_m"][-1])
    far = max(PROFILE_FAR_FACTOR * r, r + PROFILE_SIGMAS * sd)
    rise = range_profile_rise(t, z, own, sigma, at_t[-1], far) / variance_factor
    if rise >= PROFILE_MIN_RISE:
        return None
    return (f"the bearings fit a target at {far / 1e3:.1f} km almost as well as at {r / 1e3:.2f} km (likelihood "
            f"rise {rise:.1f} < {PROFILE_MIN_RISE:g}, the 95 % point of chi-square(1)): the record does not support "
            f"± {sd / 1e3:.2f} km")


def determination_checked(result: TmaResult, relative_sigma=1.0) -> TmaResult:
    """An ML range that its record does not support is reported as not determined; residuals larger than the stated
    noise widen the stated covariance.

    Two tests (tma/record_checks.py), on the solution's own bearings and the noise it states. First the
    residuals must agree with that noise (:func:`~sonartrack.tma.record_checks.residual_check`: chi-square of
    the residuals and of their 30 s block means, 99.9 % limits). Where they do not (bearings biased for a while,
    e.g. by a louder ship nearby), the covariance is multiplied by the measured variance factor s2
    (:func:`~sonartrack.tma.record_checks.residual_scale`, which passes both tests) and the inflation is
    reported; beyond :data:`~sonartrack.tma.record_checks.MAX_RESIDUAL_SCALE` the residuals are no noise and
    the range is not determined (reason "inconsistent residuals"). Then the likelihood must fall off as the
    (inflated) covariance would have it: held at twice the range (or at the stated range + 3 sd, if farther), the
    best fit must be worse by at least the 95 % point of chi-square(1) in units of that covariance
    (:func:`~sonartrack.tma.record_checks.range_profile_rise`; reason "flat likelihood"). A far target seen
    through a small maneuver has a likelihood flat towards long ranges, so its first-order covariance at a near
    estimate claims a narrow interval the data do not give (on the default scene's first 300 s: the tanker at
    13.9 km estimated 2.44 +- 0.87 km, its likelihood at 5.0 km only 2.2 worse).

    Parameters
    ----------
    result : TmaResult
        The batch ML solution.
    relative_sigma : float or ndarray (n,)
        Each bearing's noise relative to the stated one (``settings.sigma_bearing_deg``), as the fit weighted it
        (:func:`line_array_relative_sigma`; 1: equal weights).

    Returns
    -------
    TmaResult
        ``result`` when its range was undetermined or both tests pass; else a copy with the covariance inflated
        (and the note as a warning), or with every row undetermined and the reason as a warning.
    """
    if not result.solution.range_flags().any():
        return result
    kappa, s2, note = _residual_inflation(result, relative_sigma)
    if s2 > MAX_RESIDUAL_SCALE:
        return undetermined(result, INCONSISTENT_RESIDUALS, f"{note} (more than {MAX_RESIDUAL_SCALE:g} times)")
    if note is not None:
        solution = replace(result.solution, covariance=np.asarray(result.solution.covariance) * s2)
        result = replace(result, solution=solution, warnings=result.warnings + (
            f"{note}: covariance inflated by {s2:.3g} (the residuals' measured scale)",))
        cols = solution_columns(result.solution, result.ownship)
        if not cols["range_std_m"][-1] < cols["range_m"][-1]:
            return undetermined(result, INCONSISTENT_RESIDUALS, f"{note}: inflated by {s2:.3g}, the range's standard "
                                 "deviation exceeds the range")
    flat = _flat_likelihood_note(result, kappa * s2, relative_sigma)
    return result if flat is None else undetermined(result, FLAT_LIKELIHOOD, flat)


def position_gap(x_a, p_a, x_b, p_b) -> tuple[np.ndarray, float]:
    """(x_a - x_b in position m, its squared Mahalanobis distance in P_a + P_b) of two [x, y, vx, vy] estimates of one
    target at one time; NaN distance when P_a + P_b is singular. P_a + P_b bounds the covariance of the difference of
    two estimates from one record (their cross-covariance, dropped, is positive), so the test keeps rather than
    rejects (:func:`axis_checked`, :func:`batch_held`)."""
    d = np.asarray(x_a, float)[:2] - np.asarray(x_b, float)[:2]
    P = np.asarray(p_a, float)[:2, :2] + np.asarray(p_b, float)[:2, :2]
    try:
        return d, float(d @ np.linalg.solve(P, d))
    except np.linalg.LinAlgError:
        return d, float("nan")


def undetermined(result: TmaResult, reason: str, why: str) -> TmaResult:
    """``result`` with every row undetermined for ``reason``, and the warning ``why`` (after
    :data:`UNSUPPORTED_RANGE`)."""
    solution = with_reasons(result.solution, np.full(len(result.solution.time_s), reason, dtype=object))
    return replace(result, solution=solution, warnings=result.warnings + (f"{UNSUPPORTED_RANGE} {why}",))


def batch_held(seq: TmaResult, ml: TmaResult, alpha: float = RESIDUAL_ALPHA) -> TmaResult:
    """A sequential filter's solution (the passive chain's IMM-MGEKF) held to the batch ML of the same record.

    Both estimate one target from one record, the batch at once with every bearing and with the record's checks
    (side, observability, one target, residuals, jackknife) behind its verdict, so the filter cannot determine what
    the batch does not:

    * when the ML's last row is not determined, every row of the filter that has no reason yet takes the ML's
      (the record does not determine the range, whatever the filter's own covariance says: seen as NEES of 10^2 to
      10^6 on such rows);
    * when it is, the filter's last position must lie within the ``1 - alpha`` point of chi-square(2) of the ML's,
      carried to the filter's last time along the ML's constant velocity, in P_ml + P_seq (the track-to-track test
      of Bar-Shalom & Li, Multitarget-Multisensor Tracking, 1995, sec. 8.2, with the cross-covariance dropped: the
      two estimates share their data, so the difference's true covariance P_ml + P_seq - 2 P_cross is smaller and
      this test keeps a filter it could reject, not the reverse); else its last row is
      :data:`~sonartrack.tma.verdict.DISAGREES_WITH_BATCH`;
    * when they agree, the filter's last covariance is raised to the ML's (carried as above) along every direction
      in which it claims less (:func:`~sonartrack.core.linalg.covariance_max`): the batch has every measurement of
      the record and no process noise, so to first order it is the better informed of the two, and its covariance
      has been checked against the record (residual scale, block jackknife), which the filter's has not. Seen on
      the passive-chain study: the filter's last bearing follows a slow bias of the last minute's bearings with a
      cross-range sd of 4 m at 7 km (NEES 82); the ML's block jackknife widens its own covariance to cover it.

    Parameters
    ----------
    seq : TmaResult
        The sequential filter's solution.
    ml : TmaResult
        The batch ML's, on the same record (its bearings-only or bearings + frequency version).
    alpha : float
        False-alarm probability of the agreement test.

    Returns
    -------
    TmaResult
        ``seq`` with those rows undetermined (and a warning when the two disagree), or with its last covariance
        raised (and a warning when by more than 1 % in sd).
    """
    n = len(seq.solution.time_s)
    ml_reason = ml.solution.reasons()[-1]
    if ml_reason:
        return replace(seq, solution=with_reasons(seq.solution, np.full(n, ml_reason, dtype=object)))
    if not seq.solution.range_flags()[-1]:
        return seq
    F = cv_transition(float(seq.solution.time_s[-1]) - float(ml.solution.time_s[-1]))
    P_ml = F @ np.asarray(ml.solution.covariance[-1], float) @ F.T
    d, m2 = position_gap(seq.solution.state[-1], seq.solution.covariance[-1],
                         F @ np.asarray(ml.solution.state[-1], float), P_ml)
    if m2 <= chi2_quantile(1.0 - alpha, 2):
        return _covariance_floored(seq, P_ml)
    reasons = np.full(n, "", dtype=object)
    reasons[-1] = DISAGREES_WITH_BATCH
    why = (f"the {_filter_name(seq)}'s last position is {np.hypot(*d):.0f} m from the batch ML's "
           f"({np.sqrt(m2):.3g} sd of the two together): the filter's range is not supported by the record")
    return replace(seq, solution=with_reasons(seq.solution, reasons), warnings=seq.warnings + (why,))


def _covariance_floored(seq: TmaResult, P_ml) -> TmaResult:
    """``seq`` with its last covariance at least ``P_ml`` (:func:`batch_held`); the batch's where the filter's is
    not positive definite."""
    P = np.array(seq.solution.covariance, float)
    try:
        P[-1] = covariance_max(P[-1], P_ml)
    except np.linalg.LinAlgError:
        P[-1] = P_ml
    ratio = np.sqrt(np.diag(P[-1])[:2] / np.diag(np.asarray(seq.solution.covariance[-1], float))[:2])
    with np.errstate(invalid="ignore"):
        widest = float(np.nanmax(np.where(np.isfinite(ratio), ratio, np.inf)))
    warnings = seq.warnings
    if widest > 1.01:
        warnings += (f"the {_filter_name(seq)}'s last covariance claimed less than the batch ML's on the same "
                     f"record: raised to it (position sd x {widest:.3g})",)
    return replace(seq, solution=replace(seq.solution, covariance=P), warnings=warnings)
