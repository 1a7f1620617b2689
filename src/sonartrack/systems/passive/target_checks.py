"""The passive chain's checks of a determined bearings-only ML by stretches of its record: the delete-a-block
jackknife of the side decision and final state (:func:`jackknife_checked`), the stretches near the array's axis
(:func:`axis_checked`) and the side's history (:func:`side_checked`) (moved out of systems/passive/targets.py, which
runs them on every target).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.core.gaussian import chi2_quantile
from sonartrack.systems.passive.line_array_noise import endfire_reach_rad
from sonartrack.tma.record_checks import (
    RESIDUAL_ALPHA,
)
from sonartrack.tma.record_verdict import (  # the checks shared with ``sonartrack tma``; re-exported for the chain
    UNSUPPORTED_RANGE,  # noqa: F401
    position_gap,
)
from sonartrack.tma.record_verdict import undetermined as _undetermined
from sonartrack.tma.side_jackknife import side_jackknife
from sonartrack.tma.sides import (
    SideDecision,
    axis_end_stretches,
    crossing_alternative,
    fit_cv_target,
    near_axis_times,
)
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult
from sonartrack.tma.verdict import (
    INCONSISTENT_RESIDUALS,
    NOT_ONE_TARGET,
    SIDE_UNRESOLVED,
    with_reasons,
)


def jackknife_checked(result: TmaResult, side: SideDecision, record, min_log_lr: float,
                      beamwidth_deg: float) -> TmaResult:
    """A determined bearings-only ML solution checked by the delete-a-block jackknife of its side decision and final
    state (tma/side_jackknife.py :func:`~sonartrack.tma.side_jackknife.side_jackknife`: ten equal stretches of the
    record's time).

    The range is not determined when leaving out one block

    * leaves the side undecided or decides the other one (reason "side unresolved"): the decision rests on it;
    * or shows that the block is not this target's (reason :data:`~sonartrack.tma.verdict.NOT_ONE_TARGET`): the
      rest of the record predicts its bearings more than a beamwidth away (rms) and more than 3 of the
      prediction's own standard deviations. Two sources a beamwidth apart are resolved as two by the array (the
      Rayleigh limit), so bearings that far from one constant-velocity target's track are another ship's, or
      the mirror's after an axis crossing the record missed.

    Otherwise, when the jackknife covariance P_J of the final position is larger than P allows (a chi-square test
    at 1e-3, :func:`_jackknife_widened`), the covariance is widened to cover it: multiplied by lambda = the largest
    eigenvalue of P^-1 P_J (2 x 2 position blocks at the last time), so that P lambda - P_J is positive
    semi-definite; the range is then not determined (reason "inconsistent residuals")
    when its standard deviation reaches the range. The white-noise covariance, even inflated by the residuals'
    lag-1 correlation and scale (:func:`determination_checked`), misses errors correlated over tens of scans, a bias
    over part of the record and another ship's bearings (passive-chain study: 16 of 61 determined solutions more
    than 5 of their sds off); the jackknife sees them as far as they move the estimate.

    Parameters
    ----------
    result : TmaResult
        The bearings-only ML solution of the decided side's bearings.
    side : SideDecision
        The side decision on the same record (both fits).
    record : tuple of ndarray
        (times s, starboard bearings rad, port bearings rad, array centre (n, 2) m) of the record.
    min_log_lr : float
        The side decision's threshold on |ln LR|.
    beamwidth_deg : float
        The array's broadside beamwidth (deg).

    Returns
    -------
    TmaResult
        ``result`` unchanged when undetermined already, on an undecided side or too short for the jackknife;
        else with the covariance widened (and a warning), or every row undetermined with the reason.
    """
    t = record[0]
    if not result.solution.range_flags().any() or side.side == "unresolved" or len(t) < 2 * MIN_JACKKNIFE_BEARINGS:
        return result
    jk = side_jackknife(*record, side)
    span = f"of the record's {len(jk.log_lr)} stretches of time"
    if not jk.stable(side.side, min_log_lr):
        j = int(np.argmin((1.0 if side.side == "starboard" else -1.0) * np.nan_to_num(jk.log_lr)))
        return _undetermined(result, SIDE_UNRESOLVED, f"without the {ordinal(j + 1)} {span} the side is not decided "
                             f"{side.side} (ln LR {jk.log_lr[j]:+.3g}): the decision rests on it")
    return _jackknife_verdict(result, jk, beamwidth_deg, span, "another source's or the mirror's", len(jk.log_lr))


def axis_checked(result: TmaResult, side: SideDecision, record, min_log_lr: float, beamwidth_deg: float
                 ) -> TmaResult:
    """A determined ML solution of a track that comes within the endfire beam of the array's axis, checked against a
    crossing of the axis there that the record does not show.

    Within a beam of endfire (:func:`endfire_reach_rad`) the peaks of a ship crossing the axis stop short of it
    (clipped at the steering grid's end), so neither the tracker nor the side decision need see the crossing
    (tma/sides.py :func:`~sonartrack.tma.sides.axis_end_stretches`). Two tests; the range is not determined
    (reason "side unresolved") when either finds the solution resting on a side the record does not decide:

    * a track that begins or ends that near the axis: the side of those scans is decided by nothing (the motion
      after a crossing is not in the record). They are left out and the decided side refitted
      (:func:`~sonartrack.tma.sides.fit_cv_target`, covariance scaled by the side decision's sigma^2), what both
      hypotheses share; the solution must agree with it;
    * a crossing at a scan near the axis (:func:`~sonartrack.tma.sides.crossing_alternative`, the bearings weighted
      by the line array's noise law sigma_u / sin(theta)) that the record does not reject (ln LR of the decided
      side over it below ``min_log_lr``, the side decision's own threshold) must place the target where the
      solution does; one that the record decides over the side taken (ln LR at or below ``-min_log_lr``) leaves
      the range not determined wherever it places the target.

    Agreement: the difference of the final positions within the 99.9 % point of chi-square(2) in the summed
    covariance (P + P_other, which bounds the covariance of the difference of two estimates from one record).

    Parameters
    ----------
    result : TmaResult
        The ML solution of the decided side's bearings.
    side : SideDecision
        The side decision (its sigma).
    record : tuple of ndarray
        (times s, decided side's bearings rad, mirror's bearings rad, array centre (n, 2) m, cone angles rad).
    min_log_lr, beamwidth_deg : float
        The side decision's threshold on |ln LR|, and the array's broadside beamwidth (deg).

    Returns
    -------
    TmaResult
        ``result``, or every row undetermined with the reason as a warning.
    """
    t, chosen, other, xy, cone = record
    if not result.solution.range_flags().any() or side.side == "unresolved":
        return result
    reach = endfire_reach_rad(beamwidth_deg)
    note = _end_stretch_note(result, side, (t, chosen, xy, cone), reach)
    if note is None:
        alt = crossing_alternative(t, chosen, other, xy, cone, near_axis_times(t, cone, reach), reach)
        if alt is not None and alt.log_lr < min_log_lr:
            d, m2 = _elsewhere(result, alt.fit, t[-1], alt.sigma_u)
            # not (m2 <= q): a crossing the record does not reject and whose place cannot be computed decides nothing
            if not m2 <= chi2_quantile(1.0 - RESIDUAL_ALPHA, 2) or alt.log_lr <= -min_log_lr:
                note = (f"within a beam of the array's axis at {alt.time_s - t[0]:.0f} s into the track the target may "
                        f"have crossed it (ln LR {alt.log_lr:+.3g} of the side taken over that crossing), which places "
                        f"it {np.hypot(*d):.0f} m elsewhere ({np.sqrt(m2):.3g} sd): the side after it is not decided")
    return result if note is None else _undetermined(result, SIDE_UNRESOLVED, note)


def _elsewhere(result: TmaResult, fit, t_end: float, sigma_rad: float) -> tuple[np.ndarray, float]:
    """(position difference m, its squared Mahalanobis distance in P + P_fit) of a unit-noise CV fit scaled by
    sigma^2 against the solution's final row (:func:`axis_checked`)."""
    x, p = fit.state_at(t_end)
    return position_gap(x[0], p[0] * sigma_rad**2, result.solution.state[-1], result.solution.covariance[-1])


def _end_stretch_note(result: TmaResult, side: SideDecision, record, reach_rad: float) -> str | None:
    """Why the solution rests on a stretch near the axis at the record's start or end, or None
    (:func:`axis_checked`, first test)."""
    t, chosen, xy, cone = record
    for near in axis_end_stretches(cone, reach_rad):
        keep = ~near
        if keep.sum() < 2 * MIN_JACKKNIFE_BEARINGS:
            continue
        fit = fit_cv_target(chosen[keep], t[keep], xy[keep])
        if fit is None:
            continue
        d, m2 = _elsewhere(result, fit, t[-1], side.sigma_bearing_rad)
        if m2 > chi2_quantile(1.0 - RESIDUAL_ALPHA, 2):
            return (f"the track {'ends' if near[-1] else 'begins'} within a beam of the array's axis "
                    f"({int(near.sum())} scans), where it may have crossed unseen: without those scans the target "
                    f"is {np.hypot(*d):.0f} m elsewhere ({np.sqrt(m2):.3g} sd)")
    return None


def _foreign_block_note(jk, beamwidth_deg: float, span: str, whose: str) -> str | None:
    """Why the block of a jackknife (tma/side_jackknife.py :class:`~sonartrack.tma.side_jackknife.SideJackknife`)
    that the rest of the record predicts worst is not this target's, or None
    (:meth:`~sonartrack.tma.side_jackknife.SideJackknife.foreign_block` with the beamwidth)."""
    j = jk.foreign_block(float(np.deg2rad(beamwidth_deg)))
    if j is None:
        return None
    return (f"the rest of the record predicts the bearings of the {ordinal(j + 1)} {span} "
            f"{np.rad2deg(jk.block_rms_rad[j]):.3g} deg away (rms; the prediction's sd "
            f"{np.rad2deg(jk.block_sd_rad[j]):.2g} deg), more than a beamwidth ({beamwidth_deg:.2g} deg): they are "
            f"{whose}")


def _jackknife_verdict(result: TmaResult, jk, beamwidth_deg: float, span: str, whose: str, blocks: int) -> TmaResult:
    """``result`` undetermined (not one target) when the jackknife's worst-predicted block is ``whose``
    (:func:`_foreign_block_note`), else widened to the jackknife's spread over its ``blocks`` blocks
    (:func:`_jackknife_widened`)."""
    foreign = _foreign_block_note(jk, beamwidth_deg, span, whose)
    if foreign is not None:
        return _undetermined(result, NOT_ONE_TARGET, foreign)
    return _jackknife_widened(result, jk.covariance, blocks, span)


def _jackknife_widened(result: TmaResult, p_jack, blocks: int, span: str) -> TmaResult:
    """``result`` with its covariance multiplied by lambda, the largest eigenvalue of P^-1 P_J (final position), when
    the jackknife's spread exceeds what P allows, and undetermined when the range's sd then reaches the range
    (:func:`jackknife_checked`). The test: for g independent Gaussian blocks of covariance g P the delete-a-block
    jackknife covariance P_J is their sample covariance over g, so (g - 1) P^-1 P_J is Wishart with g - 1 degrees of
    freedom and (g - 1) tr(P^-1 P_J) ~ chi-square(2 (g - 1)) (Shao & Tu, The Jackknife and Bootstrap, 1995, sec.
    2.1); P is widened only above its upper :data:`~sonartrack.systems.passive.checks.RESIDUAL_ALPHA` point, as the
    residual test inflates only when it fails (a clean record keeps its white-noise covariance)."""
    P = np.asarray(result.solution.covariance, float)
    ratio = np.linalg.solve(P[-1, :2, :2], p_jack[:2, :2])
    if not (blocks - 1) * float(np.trace(ratio)) > chi2_quantile(1.0 - RESIDUAL_ALPHA, 2 * (blocks - 1)):
        return result
    lam = float(np.max(np.linalg.eigvals(ratio).real))
    result = replace(result, solution=replace(result.solution, covariance=P * lam), warnings=result.warnings + (
        f"block jackknife: covariance widened by {lam:.3g} to cover the spread of the final position with each "
        f"{span} left out",))
    cols = solution_columns(result.solution, result.ownship)
    if not cols["range_std_m"][-1] < cols["range_m"][-1]:
        return _undetermined(result, INCONSISTENT_RESIDUALS, f"widened by {lam:.3g} by the block jackknife, the "
                             "range's standard deviation exceeds the range")
    return result


#: a record needs this many bearings per half for the jackknife (:func:`jackknife_checked`)
MIN_JACKKNIFE_BEARINGS = 10


def ordinal(k: int) -> str:
    """1 -> "1st", 2 -> "2nd", 3 -> "3rd", 4 -> "4th" ... (k up to 20)."""
    return f"{k}{ {1: 'st', 2: 'nd', 3: 'rd'}.get(k, 'th')}"


def side_checked(result: TmaResult, side: SideDecision, resolved_s: float, *, causal: bool) -> TmaResult:
    """A solution's rows whose array side is not decided made undetermined (reason "side unresolved").

    Parameters
    ----------
    result : TmaResult
        A solution on the chosen side's bearings.
    side : SideDecision
        The side decision (``side_at``: "unresolved" everywhere when it was never decided).
    resolved_s : float
        First time from which the decision held (:func:`side_resolved_time`; NaN if never).
    causal : bool
        The solution at a time uses the bearings up to then only (a sequential filter): its rows before
        ``resolved_s`` were computed on a side the data had not decided yet, and are undetermined too.

    Returns
    -------
    TmaResult
        ``result`` with those rows undetermined.
    """
    t = np.asarray(result.solution.time_s, float)
    open_side = side.side_at(t) == "unresolved"
    if causal:
        open_side |= ~(t >= resolved_s)
    if not open_side.any():
        return result
    reasons = np.where(open_side, SIDE_UNRESOLVED, "").astype(object)
    return replace(result, solution=with_reasons(result.solution, reasons))
