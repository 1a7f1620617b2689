"""A passive target's legs: the zigs of its side-resolved bearings and the leg-wise ML over them (tma/zig.py,
tma/legs.py), for every target of the chain (systems/passive/targets.py :func:`~.targets.solve_target`).

Record. The chain's bearings come every window (1 s by default) with errors that are correlated from window to
window and a noise that follows the line array's law (sigma_n = sigma_u r_n, :func:`~.targets.line_array_relative_
sigma`). The zig test's threshold is calibrated on white bearings 20-60 s apart (tma/zig.py), and its sequential
fits on thousands of bearings cost minutes; so the test runs on block means over :data:`LEG_BLOCK_S` (the chain's
residual block, tma/record_checks.py ``RESIDUAL_BLOCK_S``): per block, at its weighted mean time t_b,

    z_b = h_cv(t_b) + sum_n w_n e_n / sum_n w_n,   w_n = 1 / r_n^2,   sigma_b^2 = (sigma_u^2 kappa + f^2 m) / sum_n w_n

with e_n the residuals of the chain's noise-law CV fit (:func:`~.targets.u_weighted_fit`), h_cv(t_b) its bearing from
the array's position at t_b (so that the bearing's curvature over the block does not enter the mean) and kappa the
correlation inflation of the weighted residuals (tma/solve.py ``correlation_inflation``, as the ML's covariance
states it; an AR(1) error's block mean has variance sigma^2 kappa / m), m the block's bearings and f the front
end's bias floor :data:`BLOCK_BIAS_FLOOR_RAD` (a bias b_n = f r_n common to the block adds f^2 m / sum w_n). The
test's false-alarm rate is the chain's ``zig_false_alarm_per_hour`` setting. A record of fewer than 8 blocks (240 s)
is not tested. Where the test finds a
zig, the CV fit's sigma_u and kappa hold the zig's misfit too (the 2-leg world of tests/systems/passive/
test_target_legs.py: the legs' range sd 2.3 km for an error of 0.05 km); so the noise is measured again about the
legs (sigma_u^2 = sum (e_n / r_n)^2 / (n - P), P the legs' parameters and change times), the block means taken about
the legs, and the test and leg fit run again on them: that second run's zigs and legs are the answer.

Answers. With a zig: the legs (tma/legs.py :func:`~sonartrack.tma.legs.fit_legs`, change times refined) give rows of
method ``legs`` at the record's bearing times (state and covariance from the leg fit; the covariance widened by
the block residuals' scale when they exceed their stated noise, undetermined beyond
:data:`~sonartrack.tma.record_checks.MAX_RESIDUAL_SCALE`; a row whose range sd exceeds the verdict's
``max_range_sd_fraction`` of its range is undetermined), and every constant-velocity answer of the target (the ML
and, through :func:`~sonartrack.tma.record_verdict.batch_held`, the IMM-MGEKF held to it) is not determined, reason
``target manoeuvred: zig at T s (A-B)`` (:data:`~sonartrack.tma.verdict.MANOEUVRED`). Without one: nothing changes.

Checks. The legs' rows pass what the chain's ML passes (systems/passive/targets.py :func:`~.targets.legs_checked`):
the ML's side verdict (side jackknife, axis crossings, side not yet decided) and a cone angle fixed to the array
hold for them too; the legs are refitted with each tenth of the record left out (:func:`legs_jackknife`: a block
another source's, a block they rest on, or a spread their covariance does not cover). A leg fit whose residuals
reject it (a zig missed) or that has a leg no ship sails is not determined, and the current leg's covariance
holds the zig the test may have missed (tma/missed_zig.py). A zig found where the track visits the array's axis
(:func:`~sonartrack.tma.sides.crossing_events`) is tested against a crossing there (:func:`crossing_explains`):
the tracker's cone angle, clipped or jittering at endfire, turns a crossing into the mirror's bearings, which the
test reads as a zig; when the crossing explains the bearings as well, the zig is not counted (``crossings``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.tma.legs import LegFit, _state_map, fit_legs, leg_bearing_model
from sonartrack.tma.record_checks import MAX_RESIDUAL_SCALE, RESIDUAL_ALPHA, RESIDUAL_BLOCK_S
from sonartrack.tma.record_verdict import undetermined
from sonartrack.tma.records import TmaSolution
from sonartrack.tma.side_jackknife import SideJackknife, time_blocks
from sonartrack.tma.sides import VISIT_GAP_S, fit_cv_target
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult, correlation_inflation
from sonartrack.tma.verdict import INCONSISTENT_RESIDUALS, MANOEUVRED, UNOBSERVABLE, with_reasons
from sonartrack.tma.zig import Zig, detect_zigs

#: the block over which the chain's bearings are averaged for the zig test (module doc)
LEG_BLOCK_S = RESIDUAL_BLOCK_S
#: the least sd of a block mean at broadside (rad; r_n times it off broadside, as the line array's noise law): the
#: front end's sub-beam peak positions carry a bias that varies with the cone angle's place between beams and with
#: other ships' lobes (acoustics/beamforming.py: 0.13 deg rms, correlated over tens of scans, on the passive-chain
#: study), which averaging over a block does not remove. On the shipped zigzag scene (seed 5) the merchant's block
#: means about its constant-velocity ML swung by +-0.06 deg over 100-200 s after the turn, 10 of their white-noise
#: sds (0.007 deg, sigma_u 0.02 deg): five false zigs. Added in quadrature (module doc)
BLOCK_BIAS_FLOOR_RAD = float(np.deg2rad(0.05))
#: fewest blocks the zig test runs on (tma/zig.py :func:`~sonartrack.tma.zig.detect_zigs` needs 8)
MIN_LEG_BLOCKS = 8


@dataclass(frozen=True, slots=True)
class TargetLegs:
    """A target's zigs and legs: ``zigs`` (empty: none found, or not tested -- ``message`` says which), ``fit`` the
    leg-wise ML on the block means (None without a zig), ``result`` its rows (method ``legs``) at the record's
    bearing times (None without a zig)."""

    zigs: tuple[Zig, ...]
    fit: LegFit | None
    result: TmaResult | None
    message: str
    #: the block means the legs were fitted on (times s, bearings rad, array centre (m, 2) m, sd rad), None without
    #: a zig: what :func:`legs_jackknife` refits
    blocks: tuple | None = None
    #: zigs the test found at a visit of the array's axis that a crossing there explains as well (not counted)
    crossings: tuple[Zig, ...] = ()

    def leg_of(self, time_s) -> np.ndarray:
        """The 0-based leg index at each time (0 everywhere without a zig): leg k runs up to its change time."""
        t = np.asarray(time_s, float)
        if self.fit is None:
            return np.zeros(t.shape, int)
        return np.searchsorted(self.fit.change_times_s, t, side="left").astype(int)

    def note(self) -> str:
        """The summary line's words on the zigs: "zig at 612 s (598-630), 2 legs; current leg 231 ± 3 deg, 8.1 ±
        0.4 kn, range 7.21 ± 0.40 km (legs)", or "" without a zig."""
        if not self.zigs or self.fit is None:
            return ""
        zigs = ", ".join(zig_text(z) for z in self.zigs)
        leg = self.fit.legs[-1]
        text = (f"zig{'s' if len(self.zigs) > 1 else ''} at {zigs}, {len(self.fit.legs)} legs; current leg "
                f"{leg.course_deg:.0f} ± {leg.course_sd_deg:.0f} deg, {leg.speed_kn:.1f} ± {leg.speed_sd_kn:.1f} kn")
        cols = solution_columns(self.result.solution, self.result.ownship)
        if cols["range_determined"][-1]:
            return text + f", range {cols['range_m'][-1] / 1e3:.2f} ± {cols['range_std_m'][-1] / 1e3:.2f} km (legs)"
        return text + f" (legs: range not determined, {cols['undetermined_reason'][-1]})"


def block_means(t, z, xy, relative_sigma, position_m, sigma_u: float, block_s: float = LEG_BLOCK_S):
    """The record's bearings as block means about a fitted track (module doc).

    Parameters
    ----------
    t, z : ndarray (n,)
        Times (s) and the chosen side's true bearings (rad).
    xy : ndarray (n, 2)
        The array centre (m) at those times.
    relative_sigma : ndarray (n,)
        r_n, each bearing's noise relative to sigma_u.
    position_m : callable
        Times (k,) -> the fitted target's positions (k, 2) (m): the chain's CV fit, or the legs.
    sigma_u : float
        The bearing noise at broadside (rad).
    block_s : float
        The block length (s).

    Returns
    -------
    tuple of ndarray
        Block times (m,), bearings (m,) rad, array centre (m, 2), sd (m,) rad.
    """
    w = 1.0 / np.asarray(relative_sigma, float) ** 2 * np.ones(len(t))
    e = _residuals(t, z, xy, position_m)
    kappa = correlation_inflation(e * np.sqrt(w))
    _, idx = np.unique(np.floor((t - t[0]) / block_s).astype(int), return_inverse=True)
    sw = np.bincount(idx, w)
    tb = np.bincount(idx, w * t) / sw
    own = np.column_stack([np.interp(tb, t, xy[:, 0]), np.interp(tb, t, xy[:, 1])])
    pb = position_m(tb)
    zb = wrap_angle(np.arctan2(pb[:, 0] - own[:, 0], pb[:, 1] - own[:, 1]) + np.bincount(idx, w * e) / sw)
    count = np.bincount(idx)
    return tb, zb, own, np.sqrt((sigma_u**2 * kappa + BLOCK_BIAS_FLOOR_RAD**2 * count) / sw)


def _residuals(t, z, xy, position_m) -> np.ndarray:
    """wrap(z - h(t)) of bearings z from ``xy`` to the fitted track (rad)."""
    p = position_m(t)
    return wrap_angle(z - np.arctan2(p[:, 0] - xy[:, 0], p[:, 1] - xy[:, 1]))


def measured_sigma_u(t, z, xy, relative_sigma, position_m, n_params: int, floor_rad: float) -> float:
    """sigma_u^2 = sum_n (e_n / r_n)^2 / (n - n_params), as the chain measures it about its CV fit
    (:func:`~.targets.u_weighted_fit`), floored at ``floor_rad``."""
    e = _residuals(t, z, xy, position_m) / relative_sigma
    return max(float(np.sqrt(np.sum(e**2) / max(len(t) - n_params, 1))), floor_rad)


def legs_rows(fit: LegFit, t, record, ownship, settings) -> TmaResult:
    """The leg-wise solution's rows (solution method ``legs``) at times ``t``: state and covariance from ``fit``;
    ``record``, ``ownship`` and ``settings`` those of the target's ML."""
    c = fit.change_times_s
    pos, _ = fit.position_at(t)
    k = np.searchsorted(c, t, side="left")
    vel = np.asarray(fit.params[2:], float).reshape(-1, 2)[k]
    L = np.stack([_state_map(fit.params, c, fit.t0_s, ti, fit.refined) for ti in t])
    with np.errstate(invalid="ignore"):
        cov = L @ fit.covariance @ np.swapaxes(L, 1, 2)
        # the current leg's widening for a zig the test may have missed (tma/missed_zig.py), on its rows
        end = _state_map(fit.params, c, fit.t0_s, fit.t_end_s, fit.refined)
        cov[k == len(c)] += fit.legs[-1].state_cov - end @ fit.covariance @ end.T
    solution = TmaSolution(time_s=np.asarray(t, float), state=np.column_stack([pos, vel]), covariance=cov,
                           method="legs")
    return TmaResult(solution=solution, record=record, ownship=ownship, settings=settings)


def _checked_rows(result: TmaResult, fit: LegFit, max_range_sd_fraction: float) -> TmaResult:
    """The legs' rows with their verdict: the block residuals' scale (covariance widened by it when their chi-square
    exceeds its 1 - RESIDUAL_ALPHA point, undetermined beyond MAX_RESIDUAL_SCALE), then each row's range sd."""
    scale = fit.objective / max(fit.dof, 1)
    if fit.dof > 0 and fit.objective > chi2_quantile(1.0 - RESIDUAL_ALPHA, fit.dof):
        if scale > MAX_RESIDUAL_SCALE:
            return undetermined(result, INCONSISTENT_RESIDUALS, f"the legs' block residuals are {scale:.3g} times "
                                f"their stated variance (more than {MAX_RESIDUAL_SCALE:g})")
        sol = result.solution
        result = replace(result, solution=replace(sol, covariance=np.asarray(sol.covariance) * scale),
                         warnings=result.warnings + (f"legs: covariance widened by the block residuals' scale "
                                                     f"{scale:.3g}",))
    if not fit.converged:
        return undetermined(result, UNOBSERVABLE, "the leg-wise ML did not converge")
    if fit.motion_note or not all(leg.determined for leg in fit.legs):  # a zig missed, or a leg no ship sails
        reason = fit.motion_note or next(leg.reason for leg in fit.legs if not leg.determined)
        return undetermined(result, reason.split(":")[0], f"legs: {reason}")
    cols = solution_columns(result.solution, result.ownship)
    with np.errstate(invalid="ignore"):
        loose = ~(cols["range_std_m"] <= max_range_sd_fraction * cols["range_m"])
    return replace(result, solution=with_reasons(result.solution, np.where(loose, UNOBSERVABLE, "")))


def manoeuvred_reason(zigs) -> str:
    """The reason of a CV answer that the zigs reject: "target manoeuvred: zig at 612 s (598-630)"."""
    return f"{MANOEUVRED}: zig at " + ", ".join(zig_text(z) for z in zigs)


def zig_text(zig: Zig) -> str:
    """"612 s (598-630)": the zig's time and its interval, widened to hold the time (tma/zig.py reads the interval
    from a profile on the midpoints between bearings, here 30 s apart, and the time from the joint leg fit, which
    lies between them: the interval alone can miss it)."""
    lo, hi = min(zig.interval_s[0], zig.time_s), max(zig.interval_s[1], zig.time_s)
    return f"{zig.time_s:.0f} s ({lo:.0f}-{hi:.0f})"


def target_legs(t, chosen, xy, relative_sigma, cv_fit, sigma_u: float, ml: TmaResult, *,
                false_alarm_per_hour: float, max_range_sd_fraction: float, sigma_floor_rad: float = 0.0,
                other=None, axis_visits_s=()) -> TargetLegs:
    """Zigs and legs of one target's record (module doc).

    Parameters
    ----------
    t, chosen : ndarray (n,)
        The record's times (s) and the chosen side's true bearings (rad).
    xy : ndarray (n, 2)
        The array centre (m).
    relative_sigma : ndarray (n,)
        Each bearing's noise relative to ``sigma_u`` (the line array's law).
    cv_fit : BatchEstimate or None
        The chain's noise-law CV fit (None: no test).
    sigma_u : float
        Its sigma_u (rad).
    ml : TmaResult
        The target's ML (its ownship and settings carried to the legs' rows).
    false_alarm_per_hour : float
        The zig test's stated false-alarm rate.
    max_range_sd_fraction : float
        A legs row whose range sd exceeds this fraction of its range is not determined.
    sigma_floor_rad : float
        The least sigma_u measured about the legs (the chain's ``SIGMA_U_FLOOR_RAD``).
    other : ndarray (n,) or None
        The mirror side's bearings (rad): with ``axis_visits_s``, a zig at a visit of the array's axis is tested
        against a crossing there (:func:`crossing_explains`).
    axis_visits_s : sequence of float
        Times (s) of the track's visits of the array's axis (tma/sides.py
        :func:`~sonartrack.tma.sides.crossing_events`).

    Returns
    -------
    TargetLegs
        The zigs and legs; no zig with the reason in ``message`` when the record is too short or the test fails.
    """
    t, chosen, xy = np.asarray(t, float), np.asarray(chosen, float), np.asarray(xy, float)
    if cv_fit is None:
        return TargetLegs((), None, None, "no constant-velocity fit to test")
    if t[-1] - t[0] < MIN_LEG_BLOCKS * LEG_BLOCK_S:
        return TargetLegs((), None, None, f"record shorter than {MIN_LEG_BLOCKS * LEG_BLOCK_S:.0f} s: no zig test")
    record = (t, chosen, xy, relative_sigma)
    try:
        with np.errstate(all="ignore"):
            report, blocks = _two_pass_report(record, cv_fit, sigma_u, false_alarm_per_hour, sigma_floor_rad)
            crossed = ()
            if report.zigs and report.legs is not None and other is not None and len(axis_visits_s):
                report, crossed = _without_crossings(report, blocks, record, np.asarray(other, float),
                                                     np.asarray(axis_visits_s, float), sigma_u)
    except (InputError, np.linalg.LinAlgError, ValueError) as failure:
        return TargetLegs((), None, None, f"zig test not run: {failure}")
    if not report.zigs or report.legs is None:
        note = f"; {len(crossed)} axis crossing(s) not counted as zigs" if crossed else ""
        return TargetLegs(report.zigs, None, None, (report.message or "no zig") + note, crossings=crossed)
    rows = legs_rows(report.legs, t, ml.record, ml.ownship, ml.settings)
    rows = _checked_rows(rows, report.legs, max_range_sd_fraction)
    return TargetLegs(report.zigs, report.legs, rows, "", blocks=blocks, crossings=crossed)


def _two_pass_report(record, cv_fit, sigma_u: float, false_alarm_per_hour: float, sigma_floor_rad: float):
    """(the zig report, the block means it ran on): the test on the block means about the CV fit, and where it finds
    a zig, again on the block means about the legs with the noise measured about them (module doc)."""
    blocks = block_means(*record, lambda tt: cv_fit.state_at(tt)[0][:, :2], sigma_u)
    report = detect_zigs(*blocks, false_alarm_per_hour=false_alarm_per_hour)
    if report.zigs and report.legs is not None:
        track = report.legs.position_at
        sigma_legs = measured_sigma_u(*record, lambda tt: track(tt)[0], len(report.legs.params) + len(report.zigs),
                                      sigma_floor_rad)
        blocks = block_means(*record, lambda tt: track(tt)[0], sigma_legs)
        report = detect_zigs(*blocks, false_alarm_per_hour=false_alarm_per_hour)
    return report, blocks


def crossing_explains(blocks, legs: LegFit, change_times_s, record, other, visit_s: float, sigma_u: float,
                      threshold: float) -> bool:
    """Whether a crossing of the array's axis at ``visit_s`` explains the record as well as the zig there does.

    After a crossing the target's true bearings are the mirror's (the unfolded cone angle reflected about the axis
    gives the other side's bearing), and a crossing the tracker did not follow -- its cone angle clipped at endfire,
    or jittering through it -- turns the chosen side's bearings back: to the zig test a change of bearing rate, that
    is, a zig. The alternative record takes the mirror's bearings after ``visit_s``; its block means (about its own
    noise-law CV fit, with the same noise) are fitted by the legs without this zig (``change_times_s``: the others,
    refined). The zig is the crossing's when that fit's cost exceeds the legs' own by less than the zig test's
    threshold h: the zig is then no longer significant against the crossing (the GLR of the zig over the crossing
    below h).

    Parameters
    ----------
    blocks : tuple
        The legs' block means (times s, bearings rad, array centre (m, 2) m, sd rad).
    legs : LegFit
        The leg fit on them (with the zig).
    change_times_s : ndarray
        The other zigs' times (s).
    record : tuple
        (times s, chosen side's bearings rad, array centre (n, 2) m, relative sigma) of the 1-s record.
    other : ndarray (n,)
        The mirror side's bearings (rad).
    visit_s : float
        The axis visit's time (s).
    sigma_u : float
        The bearing noise at broadside (rad).
    threshold : float
        The zig test's threshold h.

    Returns
    -------
    bool
        True when the crossing explains the bearings as well as the zig.
    """
    t, chosen, xy, rel = record
    alt = np.where(t > visit_s, other, chosen)
    fit = fit_cv_target(alt, t, xy, relative_sigma=rel)
    if fit is None:
        return False
    alt_blocks = block_means(t, alt, xy, rel, lambda tt: fit.state_at(tt)[0][:, :2], sigma_u)
    try:  # the same blocks of the same times: the legs' block sds
        alt_fit = fit_legs(*alt_blocks[:3], blocks[3], change_times_s, refine=bool(len(change_times_s)),
                           motion_alpha=None)
    except InputError:
        return False
    return bool(alt_fit.objective - legs.objective < threshold)


def _without_crossings(report, blocks, record, other, visits, sigma_u: float):
    """(the report with the zigs a crossing explains left out and the legs refitted on the rest, those zigs)
    (:func:`crossing_explains`; a zig is tested when an axis visit lies within ``VISIT_GAP_S`` of its interval)."""
    kept, crossed = list(report.zigs), []
    for zig in report.zigs:
        lo, hi = min(zig.interval_s[0], zig.time_s) - VISIT_GAP_S, max(zig.interval_s[1], zig.time_s) + VISIT_GAP_S
        near = visits[(visits >= lo) & (visits <= hi)]
        rest = np.array([z.time_s for z in kept if z is not zig], float)
        if len(near) and any(crossing_explains(blocks, report.legs, rest, record, other, v, sigma_u, report.threshold)
                             for v in near):
            kept.remove(zig)
            crossed.append(zig)
    if not crossed:
        return report, ()
    legs = None
    if kept:
        legs = fit_legs(*blocks, [z.time_s for z in kept], refine=True)
    return replace(report, zigs=tuple(kept), legs=legs, message="" if kept else "no zig"), tuple(crossed)


def legs_jackknife(blocks, fit: LegFit, t_end_s: float, n_blocks: int = 10) -> SideJackknife | None:
    """The leg fit repeated with each of ``n_blocks`` stretches of the record's time left out (change times held):
    the delete-a-block jackknife of the chain's CV ML (tma/side_jackknife.py
    :func:`~sonartrack.tma.side_jackknife.side_jackknife`) for the legs. Returned as a
    :class:`~sonartrack.tma.side_jackknife.SideJackknife` (``log_lr`` NaN: no side decision):
    each replicate's state at ``t_end_s`` (last leg's velocity), the jackknife covariance P_J of that state, and
    each replicate's prediction of the block means it left out (rms difference, the prediction's rms sd). A
    replicate that cannot be fitted (a leg left without bearings) has NaN. None: fewer than 3 stretches.
    """
    tb, zb, own, sb = (np.asarray(x, float) for x in blocks)
    edges = time_blocks(tb, n_blocks)
    g = len(edges) - 1
    if g < 3:
        return None
    i = np.arange(len(tb))
    reps = np.array([_leg_replicate(blocks, fit, t_end_s, (i < edges[j]) | (i >= edges[j + 1])) for j in range(g)])
    state = reps[:, :4]
    d = state - state.mean(axis=0)
    return SideJackknife(np.full(g, np.nan), state, (g - 1) / g * d.T @ d, reps[:, 4], reps[:, 5])


def _leg_replicate(blocks, fit: LegFit, t_end_s: float, keep) -> np.ndarray:
    """[state at t_end (4), rms of the prediction of the left-out block means, its rms sd] of one replicate of
    :func:`legs_jackknife`, NaN when the legs cannot be fitted without the block."""
    tb, zb, own, sb = blocks
    c = np.asarray(fit.change_times_s, float)
    out = np.full(6, np.nan)
    tk = tb[keep]
    start = np.r_[fit.position_at(tk[:1])[0][0], np.asarray(fit.params[2:], float)]
    try:
        with np.errstate(all="ignore"):
            rep = fit_legs(tk, zb[keep], own[keep], sb[keep], c, refine=False, params_init=start, motion_alpha=None)
    except (InputError, np.linalg.LinAlgError, ValueError):
        return out
    if not (rep.converged and np.all(np.isfinite(rep.params))):
        return out
    out[:2] = rep.position_at([t_end_s])[0][0]
    out[2:4] = rep.params[-2:]
    h, J, _ = leg_bearing_model(rep.params, c, tb[~keep], own[~keep], rep.t0_s)
    scale = max(rep.objective / max(rep.dof, 1), 1.0)
    with np.errstate(invalid="ignore", over="ignore"):
        v = np.einsum("ni,ij,nj->n", J, rep.covariance[:J.shape[1], :J.shape[1]] * scale, J)
    out[4] = float(np.sqrt(np.mean(wrap_angle(zb[~keep] - h) ** 2)))
    out[5] = float(np.sqrt(np.mean(v)))
    return out


def with_legs_verdict(result: TmaResult, legs: TargetLegs) -> TmaResult:
    """A constant-velocity answer of the target, every row not determined when its legs hold a zig."""
    if not legs.zigs or legs.fit is None:
        return result
    reason = manoeuvred_reason(legs.zigs)
    return undetermined(result, reason, f"{reason}: the bearings reject constant velocity ({len(legs.fit.legs)} legs)")
