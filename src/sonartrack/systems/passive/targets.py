"""From a confirmed bearing track to a target: array side, true bearings, and the two TMA solutions.

Per track (its raw peaks, systems/passive/measurements.py):

1. Side. A line array measures the cone angle theta; the target lies on either side of the array axis,
   at true bearing  heading_array + theta  (starboard) or  heading_array - theta  (port). Both mirror
   hypotheses are fitted by a constant-velocity bearings-only ML (tma/sides.py); before the array turns,
   both explain the bearings equally (ln LR ~ 0, unresolved); after the turn only the true side does.
   The decision is re-taken on the growing record every ``SIDE_CHECK_S`` seconds, so the time it was
   resolved is known. A track that passes endfire (the tracker's unfolded cone angle phi) changes side at each
   axis crossing; b = h +- phi is continuous through them, and the crossing hypotheses are decided by the motion
   that follows (tma/sides.py :func:`~sonartrack.tma.sides.resolve_side_through_crossings`).
2. TMA on the chosen side's bearings, sensor = the array centre, both by :func:`~sonartrack.tma.solve.solve_tma`:
   batch ML (paper P3, method ``ml``) from the side decision's multi-start fit (``ml_fit``: the single
   pseudo-linear start of the plain ML can settle in a far local minimum), with the observability check
   reported as flags (``unobservable="flag"``: a track that ends before the array maneuvers still has a
   bearing, only its range is unknown); and the sequential IMM-MGEKF (paper P2), on bearings + the tonal's
   frequency when the track carries a usable tonal line.
   Bearing noise: the line array's, white in u = cos(theta): the decided side's ML is refitted with each bearing
   weighted by sigma_n = sigma_u / max(|sin theta_n|, 0.05) (:func:`u_weighted_fit`,
   :func:`line_array_relative_sigma`), so the scans near endfire, noisy and biased by whatever shares the wide
   endfire beam, weigh little without being dropped; sigma_u is measured from the weighted residuals, so that the
   solution's uncertainty reflects this recording, not a nominal value (the side decision itself and its jackknife
   keep equal weights, tma/sides.py). The ML covariance is
   inflated for the residuals' correlation from window to window (tma/solve.py
   :func:`~sonartrack.tma.solve.correlation_inflation`; setting ``ml_correlation_inflation``).
   Scans at which another track lies within a beam of this one are left out first (:func:`without_neighbour_scans`:
   a louder ship sharing the beam pulls the peak, a bias the ML would take as information). ML residuals larger
   than that stated noise inflate the covariance by their measured scale (reported), or, far larger, leave the
   range not determined, as does a likelihood flatter than the stated covariance claims
   (:func:`determination_checked`). Last, the side decision and the fit are repeated with each tenth of the
   record's time left out (the delete-a-block jackknife, :func:`jackknife_checked`): a side that one tenth decides,
   or a tenth whose bearings the rest places more than a beamwidth away (another ship's, or the mirror's), leaves
   the range not determined; otherwise the covariance is widened to cover the replicates' spread.
   A target found through its tonal line (a narrowband target, ``use_frequency_ml``), whose bearings alone rarely
   determine its range, is solved by the batch ML on bearings + the line's frequency instead (tma/batch_bf.py: the
   Doppler f = f0 (1 - rdot / c) of paper P2, eq. 3, gives the range rate; :func:`frequency_ml`), with the same
   residual and profile-likelihood checks on its own likelihood (f0 free) and the same block jackknife of its final
   state (:func:`bf_jackknife_checked`). Before all these, bearings that one cone angle fixed in the array's frame
   explains as well as the CV target (a source moving with the array: own-ship or array noise) leave the range not
   determined, with no bearings + frequency fit (:func:`fixed_cone_note`).
3. Verdict (tma/verdict.py). Every row of both solutions says whether its range is determined and why not: the
   ML's (unobservable, inconsistent residuals, flat likelihood, cone angle fixed to the array), the IMM-MGEKF's own
   (diverged, inconsistent innovations, unobservable), and for both the side: every row when the side was never
   decided, and for the sequential filter, whose row at a time uses only the bearings up to then, the rows before
   it was decided (:func:`side_checked`).
4. The IMM-MGEKF held to the batch ML of its own record (:func:`batch_reference`: the bearings + frequency ML when
   the filter runs with the tonal's frequency): it takes the batch's reason when the batch does not determine the
   range, is not determined when its last position disagrees with the batch's, and otherwise claims no less
   uncertainty at its last row than the batch, whose covariance the record's residuals and block jackknife have
   checked (:func:`batch_held`).

The pieces live by idea: the noise law and the weighted ML in systems/passive/line_array_noise.py, the checks by
stretches of the record (jackknife, axis, side) in systems/passive/target_checks.py, the fixed-cone test in
systems/passive/fixed_cone.py, the scans, side time and tonal a target is solved from in
systems/passive/target_inputs.py; their names used elsewhere are importable from here too.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.fixed_cone import fixed_cone_cost as fixed_cone_cost
from sonartrack.systems.passive.fixed_cone import fixed_cone_f as fixed_cone_f
from sonartrack.systems.passive.fixed_cone import fixed_cone_note
from sonartrack.systems.passive.line_array_noise import (
    SIGMA_U_FLOOR_RAD,
    line_array_relative_sigma,
    u_weighted_fit,
)
from sonartrack.systems.passive.line_array_noise import (
    endfire_reach_rad as endfire_reach_rad,
)
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveStages
from sonartrack.systems.passive.target_checks import (
    _end_stretch_note as _end_stretch_note,
)
from sonartrack.systems.passive.target_checks import (
    _jackknife_verdict,
    axis_checked,
    jackknife_checked,
    ordinal,
    side_checked,
)
from sonartrack.systems.passive.target_inputs import (
    frequency_record,
    line_tonal,
    side_resolved_time,
    usable_tonal,
    without_neighbour_scans,
)
from sonartrack.systems.passive.target_legs import TargetLegs, legs_jackknife, target_legs, with_legs_verdict
from sonartrack.tma.record_checks import (
    MAX_RESIDUAL_SCALE,
    PROFILE_FAR_FACTOR,
    PROFILE_MIN_RISE,
    PROFILE_SIGMAS,
    residual_check,
    residual_scale,
)
from sonartrack.tma.record_verdict import (  # the checks shared with ``sonartrack tma``; re-exported for the chain
    UNSUPPORTED_RANGE,  # noqa: F401
    batch_held,
    determination_checked,
)
from sonartrack.tma.record_verdict import undetermined as _undetermined
from sonartrack.tma.records import BearingRecord, TmaSolution
from sonartrack.tma.settings import BatchSettings, TmaSettings
from sonartrack.tma.sides import (
    SideDecision,
    crossing_events,
    mirror_bearings_rad,
    resolve_side,
    resolve_side_through_crossings,
)
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult, correlation_inflation, solve_tma
from sonartrack.tma.verdict import (
    DIVERGED,
    FIXED_CONE,
    FLAT_LIKELIHOOD,
    INCONSISTENT_RESIDUALS,
    SIDE_UNRESOLVED,
    UNOBSERVABLE,
    with_reasons,
)


@dataclass(frozen=True, slots=True)
class Target:
    """A confirmed track's target: side decision, TMA solutions, and the tonal line if any."""

    target_id: int
    track: TrackMeasurements
    side: SideDecision
    #: first time from which the side decision held (NaN if never resolved)
    side_resolved_s: float
    ml: TmaResult
    #: the ML fit of the rejected mirror hypothesis (drawn faint on the tactical picture)
    mirror_ml: TmaResult | None
    sequential: TmaResult
    tonal: TonalTrack | None
    #: the zigs and legs of its side-resolved bearings (systems/passive/target_legs.py); None: not tested
    legs: TargetLegs | None = None


def _tma_settings(method: str, sigma_bearing_rad: float, stages: PassiveStages, tonal: TonalTrack | None
                  ) -> TmaSettings:
    s = stages.settings
    use_f = tonal is not None and method != "ml"
    return TmaSettings(method=method, frequency=use_f, sigma_bearing_deg=float(np.clip(np.rad2deg(sigma_bearing_rad),
                                                                                       1e-3, 30.0)),
                       sigma_freq_hz=max(tonal.sigma_hz, s.sigma_freq_floor_hz) if use_f else 0.1,
                       imm=stages.imm, sequential=stages.sequential, verdict=s.verdict,
                       batch=BatchSettings(correlation_inflation=s.ml_correlation_inflation))


def solve_target(target_id: int, m: TrackMeasurements, tonal: TonalTrack | None, nav: Navigation,
                 stages: PassiveStages, neighbours=(), *, use_frequency_ml: bool = False) -> Target:
    """Side, true bearings and TMA of one track (module docstring).

    Parameters
    ----------
    target_id : int
        The target's number.
    m : TrackMeasurements
        The track's raw peaks.
    tonal : TonalTrack or None
        The track's tonal line.
    nav : Navigation
        The array's position and heading over the recording.
    stages : PassiveStages
        The chain's built settings.
    neighbours : sequence of TrackMeasurements
        The other confirmed tracks: the scans at which one lies within ``stages.min_separation_deg`` of this
        track are left out (:func:`without_neighbour_scans`; reported among the ML's warnings).
    use_frequency_ml : bool
        The ML on bearings + the tonal's frequency (:func:`frequency_ml`) when its frequency is clean enough
        (:func:`line_tonal`): for a target found through its line (a narrowband target), whose bearings alone rarely
        determine the range.

    Returns
    -------
    Target
        Side decision, both sides' ML fits, IMM-MGEKF, each row with its verdict; zigs and legs (:func:`_with_legs`).
    """
    m, left_out = without_neighbour_scans(m, neighbours, stages.min_separation_deg)
    min_log_lr, t = stages.settings.min_side_log_lr, np.asarray(m.time_s, float)
    xy, heading = nav.array_at(t)
    side, cone = _side_of(m, t, heading, xy, min_log_lr)
    since = side_resolved_time(t, cone, heading, xy, side, min_log_lr)
    stbd, port = mirror_bearings_rad(cone, heading)
    chosen, other = (port, stbd) if side.side == "port" else (stbd, port)
    fit, other_fit = (side.port, side.starboard) if side.side == "port" else (side.starboard, side.port)
    sensor = nav.array_track()
    fit, sigma_ml, rel = _noise_law_fit(chosen, t, xy, cone, fit, side.sigma_bearing_rad)
    side_settings = _tma_settings("ml", side.sigma_bearing_rad, stages, None)
    rec, rec_other = BearingRecord(time_s=t, bearing_rad=chosen), BearingRecord(time_s=t, bearing_rad=other)
    ml = determination_checked(solve_tma(rec, sensor, _tma_settings("ml", sigma_ml, stages, None), ml_fit=fit,
                                         unobservable="flag", record_checks=False), rel)
    fixed = fixed_cone_note(ml, cone, rel)  # first: the other checks, and the frequency's Doppler, assume a target
    ml = ml if fixed is None else _undetermined(ml, FIXED_CONE, fixed)
    if fixed is None and use_frequency_ml and line_tonal(tonal, stages) is not None:  # bearings: the side fit's noise
        bf = frequency_ml(replace(ml, settings=side_settings), t, chosen, tonal, stages)
        ml = bf if bf.settings.frequency else replace(ml, warnings=bf.warnings)
    if not ml.settings.frequency:
        ml = jackknife_checked(ml, side, (t, stbd, port, xy), min_log_lr, stages.min_separation_deg)
    ml = axis_checked(ml, side, (t, chosen, other, xy, cone), min_log_lr, stages.min_separation_deg)
    ml = side_checked(ml, side, since, causal=False)
    ml = ml if left_out is None else replace(ml, warnings=ml.warnings + (left_out,))
    ml, legs = _with_legs(ml, side, since, (t, chosen, xy, rel, fit, sigma_ml, other, cone), stages)
    mirror = solve_tma(rec_other, sensor, side_settings, ml_fit=other_fit, unobservable="flag", record_checks=False)
    imm_tonal = _imm_tonal(t, chosen, tonal, stages)
    seq = side_checked(_sequential(t, chosen, imm_tonal, sensor, side.sigma_bearing_rad, stages), side, since,
                       causal=True)
    seq = batch_held(seq, batch_reference(ml, t, chosen, imm_tonal, side.sigma_bearing_rad, stages))
    return Target(target_id, m, side, since, ml, mirror, seq, tonal, legs)


def _with_legs(ml: TmaResult, side: SideDecision, since: float, record, stages: PassiveStages
               ) -> tuple[TmaResult, TargetLegs | None]:
    """(the ML, every row not determined when the record has a zig; the zigs and legs of the side-resolved record,
    systems/passive/target_legs.py; None when the side is not resolved: no true bearings to test). ``record``:
    (times s, chosen side's bearings rad, array centre (n, 2) m, relative sigma, the noise-law CV fit, its sigma_u
    rad, the mirror's bearings rad, the cone angles rad the side was decided on). A zig at a visit of the array's
    axis that a crossing there explains as well is not counted. The legs' rows pass the checks the ML passes
    (:func:`legs_checked`)."""
    if side.side == "unresolved":
        return ml, None
    t, chosen, xy, rel, fit, sigma_u, other, cone = record
    s = stages.settings
    visits = [when for when, _ in crossing_events(t, cone)]
    legs = target_legs(t, chosen, xy, rel, fit, sigma_u, ml, false_alarm_per_hour=s.zig_false_alarm_per_hour,
                       max_range_sd_fraction=s.verdict.max_range_sd_fraction, sigma_floor_rad=SIGMA_U_FLOOR_RAD,
                       other=other, axis_visits_s=visits)
    if legs.result is None:
        return ml, legs
    rows = legs_checked(legs, ml, t[-1], stages.min_separation_deg)
    return with_legs_verdict(ml, legs), replace(legs, result=side_checked(rows, side, since, causal=False))


#: the ML's reasons that hold for the legs' rows too: they are about the side and the source, not the motion
SHARED_REASONS = (SIDE_UNRESOLVED, FIXED_CONE)


def legs_checked(legs: TargetLegs, ml: TmaResult, t_end_s: float, beamwidth_deg: float) -> TmaResult:
    """The legs' rows with the checks the chain's ML passes (:func:`solve_target`): a row whose ML row is not
    determined for the side (:func:`jackknife_checked`'s side test, :func:`axis_checked`, :func:`side_checked`) or a
    cone angle fixed to the array (:data:`SHARED_REASONS`) takes the ML's reason; then the delete-a-block jackknife
    of the legs (systems/passive/target_legs.py :func:`~.target_legs.legs_jackknife`, change times held): a block
    the rest predicts more than a beamwidth and 3 sds away is another source's (reason
    :data:`~sonartrack.tma.verdict.NOT_ONE_TARGET`), a block without which the legs cannot be fitted leaves them
    resting on it (:data:`~sonartrack.tma.verdict.UNOBSERVABLE`), and otherwise the covariance is widened to cover
    the replicates' spread (:func:`_jackknife_widened`)."""
    rows = legs.result
    reasons = ml.solution.reasons()
    shared = np.where(np.isin(reasons, SHARED_REASONS), reasons, "")
    if (shared != "").any():
        rows = replace(rows, solution=with_reasons(rows.solution, shared), warnings=rows.warnings + (
            f"legs: {shared[shared != ''][-1]}, as the constant-velocity ML",))
    if not rows.solution.range_flags().any() or legs.blocks is None:
        return rows
    jk = legs_jackknife(legs.blocks, legs.fit, t_end_s)
    if jk is None:
        return rows
    span = f"of the record's {len(jk.log_lr)} stretches of time"
    if not np.all(np.isfinite(jk.state)):
        j = int(np.flatnonzero(~np.all(np.isfinite(jk.state), axis=1))[0])
        return _undetermined(rows, UNOBSERVABLE, f"without the {ordinal(j + 1)} {span} the legs cannot be fitted: "
                             "they rest on it")
    return _jackknife_verdict(rows, jk, beamwidth_deg, span, "another source's or the mirror's", len(jk.log_lr))


def _side_of(m: TrackMeasurements, t, heading, xy, min_log_lr: float) -> tuple[SideDecision, np.ndarray]:
    """(side decision, cone angles rad) of a track (:func:`solve_target`): through endfire (unfolded cone angles)
    the sides of every segment between axis crossings at once."""
    if m.unfolded_deg is not None:
        side = resolve_side_through_crossings(t, np.deg2rad(m.unfolded_deg), heading, xy, min_log_lr=min_log_lr)
        return side, side.unfolded_rad
    cone = np.deg2rad(np.asarray(m.cone_deg, float))
    return resolve_side(t, cone, heading, xy, min_log_lr=min_log_lr), cone


def _noise_law_fit(chosen, t, xy, cone, fit, sigma_bearing_rad: float):
    """(ML fit, its sigma rad, per-scan relative sigma) for :func:`solve_target`: the scans near endfire (noisy, and
    biased by what shares the wide endfire beam) weigh as the line array's noise law says (:func:`u_weighted_fit`);
    the side decision's equal-weight fit and sigma where that fit fails."""
    law = line_array_relative_sigma(cone)
    weighted = u_weighted_fit(chosen, t, xy, law, fit) if fit is not None and len(t) > 4 else None
    if weighted is None:
        return fit, sigma_bearing_rad, np.ones(len(t))
    (fit, sigma_ml), rel = weighted, law
    return fit, sigma_ml, rel


def _imm_tonal(t, chosen, tonal: TonalTrack | None, stages: PassiveStages) -> TonalTrack | None:
    """The tonal the IMM-MGEKF runs with: a usable one (:func:`usable_tonal`) with a frequency at
    :data:`MIN_FREQUENCY_POINTS` of the bearings at least, else None (bearings only)."""
    tonal = usable_tonal(tonal, stages)
    if tonal is None or len(frequency_record(t, chosen, tonal).time_s) < MIN_FREQUENCY_POINTS:
        return None
    return tonal


def _sequential(t, chosen, tonal: TonalTrack | None, sensor, sigma_bearing_rad: float, stages: PassiveStages
                ) -> TmaResult:
    """The IMM-MGEKF on the chosen bearings, with ``tonal``'s frequency when given (:func:`_imm_tonal`); a filter that
    fails numerically gives a solution of NaN rows, each "diverged", with the failure as a warning."""
    seq_settings = _tma_settings("imm-mgekf", sigma_bearing_rad, stages, tonal)
    record = frequency_record(t, chosen, tonal) if tonal is not None else BearingRecord(time_s=t, bearing_rad=chosen)
    try:
        return solve_tma(record, sensor, seq_settings, record_checks=False)  # the chain's checks follow
    except InputError as failure:  # the filter failed numerically on this track: a diverged answer, not a failed run
        n = len(record.time_s)
        solution = TmaSolution(time_s=np.asarray(record.time_s, float), state=np.full((n, 4), np.nan),
                               covariance=np.full((n, 4, 4), np.nan), method=seq_settings.method,
                               range_determined=np.zeros(n, bool), undetermined_reason=np.full(n, DIVERGED, object))
        return TmaResult(solution=solution, record=record, ownship=sensor, settings=seq_settings,
                         warnings=(str(failure),))


def batch_reference(ml: TmaResult, t, chosen, imm_tonal: TonalTrack | None, sigma_bearing_rad: float,
                    stages: PassiveStages) -> TmaResult:
    """The batch ML that the IMM-MGEKF is held to (:func:`batch_held`): the one of the filter's own record.

    That is the target's ML when the filter runs on bearings only or the ML is already the bearings + frequency one
    (a narrowband target), and otherwise, when the filter runs with the tonal's frequency, the bearings + frequency
    ML of the same bearings and tonal (:func:`frequency_ml`, with all its checks), whose range the frequency fixes
    more tightly than the bearings alone do: held to the bearings-only ML's wide covariance, a filter whose range
    rests on the frequency was never tested (passive-chain study: NEES 99 and 288 on two such rows).

    Parameters
    ----------
    ml : TmaResult
        The target's ML (bearings only, or bearings + frequency for a narrowband target).
    t, chosen : ndarray (n,)
        The bearings' times (s) and the chosen side's true bearings (rad).
    imm_tonal : TonalTrack or None
        The tonal the filter runs with (:func:`_imm_tonal`).
    sigma_bearing_rad : float
        The side fit's bearing noise sd (rad), which the filter and the bearings + frequency ML state.
    stages : PassiveStages
        What :func:`frequency_ml` needs.

    Returns
    -------
    TmaResult
        The reference; ``ml`` itself when its range is not determined (the filter then takes its reason) or the
        bearings + frequency fit fails.
    """
    if imm_tonal is None or ml.settings.frequency or not ml.solution.range_flags()[-1]:
        return ml
    bf = frequency_ml(replace(ml, settings=_tma_settings("ml", sigma_bearing_rad, stages, None)), t, chosen,
                      imm_tonal, stages)
    return bf if bf.settings.frequency else ml


#: fewest bearings with a frequency for the bearings + frequency ML (as for the sequential filter's frequency)
MIN_FREQUENCY_POINTS = 10
#: first-time ranges (m) to which the bearings-only track is scaled about the sensor's first leg to start the
#: bearings + frequency ML (besides the track itself): the bearings alone may leave the scale anywhere along a
#: flat valley (on the default scene the submarine's bearings-only fit lands as far as 1e9 km)
BF_START_RANGES_M = (1_000.0, 2_000.0, 4_000.0, 8_000.0, 16_000.0, 32_000.0)


def frequency_ml(bearings_ml: TmaResult, t, chosen, tonal: TonalTrack, stages: PassiveStages) -> TmaResult:
    """The batch ML on bearings + the tonal's frequency (tma/batch_bf.py; measurement model of paper P2, eq. 3),
    with its own determination check, in place of the bearings-only ML.

    The tonal's received frequency f = f0 (1 - rdot / c) carries the range rate, which fixes the scale of the
    relative track that the bearings leave open (tma/batch_bf.py). Started from the bearings-only solution, as it
    is and scaled about the sensor to each range of :data:`BF_START_RANGES_M`, and the mean frequency; the lowest
    cost wins. Each channel's noise
    is the one it states (bearing: the side fit's residuals; frequency: the tonal's ``sigma_hz``, floored at
    ``sigma_freq_floor_hz``), scaled as in :func:`determination_checked` by the correlation inflation of its
    residuals (``ml_correlation_inflation``) and its measured residual scale, and the fit repeated with those
    noises; beyond :data:`~sonartrack.systems.passive.checks.MAX_RESIDUAL_SCALE` the range is not determined
    ("inconsistent residuals"). Then the range must be determined by the first-order covariance (sd < range) and
    by the profile likelihood with f0 free (:func:`~sonartrack.tma.batch_bf.bf_profile_rise` at twice the range or
    the range + 3 sd; "flat likelihood"), and last by the block jackknife (:func:`bf_jackknife_checked`).

    Parameters
    ----------
    bearings_ml : TmaResult
        The bearings-only ML of the chosen side's bearings (its state starts the search; returned, with a warning,
        when the frequency fit fails).
    t, chosen : ndarray (n,)
        The bearings' times (s) and the chosen side's true bearings (rad).
    tonal : TonalTrack
        The target's line (:func:`line_tonal`).
    stages : PassiveStages
        The sound speed (``sequential.sound_speed_mps``), ``sigma_freq_floor_hz``, ``ml_correlation_inflation``.

    Returns
    -------
    TmaResult
        Method "ml" on the bearings + frequency record (``settings.frequency`` True, ``f0_hz``), rows at its times.
    """
    record = frequency_record(t, chosen, tonal)
    if len(record.time_s) < MIN_FREQUENCY_POINTS:
        return bearings_ml
    s = stages.settings
    sigma = np.array([np.deg2rad(bearings_ml.settings.sigma_bearing_deg), max(tonal.sigma_hz, s.sigma_freq_floor_hz)])
    settings = bearings_ml.settings.model_copy(update={"frequency": True, "sigma_freq_hz": float(sigma[1])})
    try:
        with np.errstate(all="ignore"):
            est = _bf_fit(record, bearings_ml, sigma, stages.sequential.sound_speed_mps, None)
            scale, notes = _bf_noise_scale(record, bearings_ml.ownship, est, sigma, s.ml_correlation_inflation,
                                           stages.sequential.sound_speed_mps)
            if np.any(scale > 1.0):
                est = _bf_fit(record, bearings_ml, sigma * np.sqrt(scale), stages.sequential.sound_speed_mps, est.x0)
    except (InputError, np.linalg.LinAlgError, ValueError) as failure:
        return replace(bearings_ml, warnings=bearings_ml.warnings + (f"bearings + frequency ML failed ({failure}): "
                                                                      "the bearings-only ML is reported",))
    from sonartrack.tma.batch import estimate_to_solution

    result = TmaResult(solution=estimate_to_solution(est.track(), record.time_s), record=record,
                       ownship=bearings_ml.ownship, settings=settings, f0_hz=float(est.x0[4]),
                       f0_std_hz=float(np.sqrt(est.covariance[4, 4])) if est.covariance[4, 4] >= 0 else np.nan,
                       warnings=notes)
    result = _bf_verdict(result, est, sigma * np.sqrt(scale), stages.sequential.sound_speed_mps, float(scale.max()))
    return bf_jackknife_checked(result, est, sigma * np.sqrt(scale), stages.sequential.sound_speed_mps,
                                stages.min_separation_deg)


def _bf_fit(record: BearingRecord, bearings_ml: TmaResult, sigma, c_mps: float, x_init):
    """The bearings + frequency ML estimate of ``record`` with noises ``sigma`` (rad, Hz): from ``x_init``, or from
    the bearings-only solution at the first time as it is and scaled to each of :data:`BF_START_RANGES_M` (the
    lowest cost wins)."""
    from sonartrack.tma.batch_bf import bf_start, ml_bearings_frequency
    from sonartrack.tma.sequential_bf import observer_kinematics

    tf = np.asarray(record.time_s, float)
    own, ov = observer_kinematics(bearings_ml.ownship, tf)
    f = np.asarray(record.frequency_hz, float)
    if x_init is not None:
        starts = [np.asarray(x_init, float)]
    else:
        ts, state = np.asarray(bearings_ml.solution.time_s, float), np.asarray(bearings_ml.solution.state, float)
        x4 = np.array([np.interp(tf[0], ts, state[:, k]) for k in range(4)])
        require(bool(np.all(np.isfinite(x4))), "the bearings-only solution is not finite")
        r0 = float(np.hypot(*(x4[:2] - own[0])))
        starts = [bf_start(x4, f, own[0], ov[0], scale=k) for k in (1.0, *(np.array(BF_START_RANGES_M) / r0))]
    fits = [ml_bearings_frequency(record.bearing_rad, f, tf, own, ov, sigma[0], sigma[1], x, c_mps=c_mps)
            for x in starts]
    fits = [e for e in fits if np.isfinite(e.objective) and np.all(np.isfinite(e.x0))]
    require(len(fits) > 0, "no start converged to a finite solution")
    return min(fits, key=lambda e: e.objective)


def _bf_noise_scale(record: BearingRecord, ownship, est, sigma, inflate: bool, c_mps: float):
    """Per channel (bearing, frequency) the variance factor kappa s2 its residuals measure beyond the stated noise
    (as :func:`determination_checked` does for the bearings), and the notes of the ones inflated."""
    from sonartrack.tma.batch_bf import bf_model
    from sonartrack.tma.sequential_bf import observer_kinematics

    tf = np.asarray(record.time_s, float)
    own, ov = observer_kinematics(ownship, tf)
    h_b, h_f, _, _ = bf_model(est.x0, tf - tf[0], own, ov, c_mps)
    residuals = (wrap_angle(np.asarray(record.bearing_rad) - h_b), np.asarray(record.frequency_hz) - h_f)
    scale, notes = np.ones(2), []
    for k, (e, name) in enumerate(zip(residuals, ("bearing", "frequency"), strict=True)):
        kappa = correlation_inflation(e) if inflate else 1.0
        check = residual_check(tf, e, float(sigma[k]), inflation=kappa, n_params=5)
        scale[k] = kappa * (1.0 if check.consistent else residual_scale(check))
        if scale[k] > 1.0:
            notes.append(f"bearings + frequency ML: {name} noise variance scaled by {scale[k]:.3g} (correlation "
                         f"{kappa:.3g} x residual scale {scale[k] / kappa:.3g})")
    return scale, tuple(notes)


def _bf_verdict(result: TmaResult, est, sigma, c_mps: float, max_scale: float) -> TmaResult:
    """The bearings + frequency ML's rows with their verdict: residuals no noise, covariance not finite, range sd
    at least the range, or a likelihood flat towards twice the range (:func:`frequency_ml`)."""
    from sonartrack.tma.batch_bf import bf_profile_rise
    from sonartrack.tma.sequential_bf import observer_kinematics
    from sonartrack.tma.verdict import UNOBSERVABLE

    if max_scale > MAX_RESIDUAL_SCALE:
        return _undetermined(result, INCONSISTENT_RESIDUALS, f"bearings + frequency residuals {max_scale:.3g} times "
                             f"the stated noise (more than {MAX_RESIDUAL_SCALE:g} times)")
    P = np.asarray(result.solution.covariance, float)
    if not np.all(np.isfinite(P)) or not np.all(np.isfinite(est.covariance)):
        return _undetermined(result, DIVERGED, "bearings + frequency ML covariance not finite")
    if not np.all(np.linalg.eigvalsh(0.5 * (est.covariance + est.covariance.T)) > 0):
        return _undetermined(result, DIVERGED, "bearings + frequency ML covariance not positive definite (the "
                             "information matrix is singular at the solution)")
    cols = solution_columns(result.solution, result.ownship)
    r, sd = float(cols["range_m"][-1]), float(cols["range_std_m"][-1])
    if not sd < r:
        return _undetermined(result, UNOBSERVABLE, f"bearings + frequency ML range {r / 1e3:.2f} ± {sd / 1e3:.2f} km")
    tf = np.asarray(result.record.time_s, float)
    own, ov = observer_kinematics(result.ownship, tf)
    end = np.concatenate([result.solution.state[-1], [est.x0[4]]])
    far = max(PROFILE_FAR_FACTOR * r, r + PROFILE_SIGMAS * sd)
    rise = bf_profile_rise(tf, result.record.bearing_rad, result.record.frequency_hz, own, ov, float(sigma[0]),
                           float(sigma[1]), end, far, c_mps)
    if rise >= PROFILE_MIN_RISE:
        return result
    return _undetermined(result, FLAT_LIKELIHOOD, f"bearings + frequencies fit a target at {far / 1e3:.1f} km almost "
                         f"as well as at {r / 1e3:.2f} km (likelihood rise {rise:.1f} < {PROFILE_MIN_RISE:g}, the 95 % "
                         f"point of chi-square(1)): the record does not support ± {sd / 1e3:.2f} km")


def bf_jackknife_checked(result: TmaResult, est, sigma, c_mps: float, beamwidth_deg: float) -> TmaResult:
    """A determined bearings + frequency ML solution checked by the delete-a-block jackknife of its final state
    (tma/batch_bf.py :func:`~sonartrack.tma.batch_bf.bf_jackknife`: the ten stretches of time of
    :func:`jackknife_checked`, each left out in turn and the bearings + frequency ML refitted).

    As :func:`jackknife_checked` without the side, but a solution the jackknife cannot check is not determined:
    its five-parameter fit's white-noise covariance is optimistic under errors correlated in time (Kunsch 1989,
    sec. 1; Shao & Tu, The Jackknife and Bootstrap, 1995, sec. 5.2), and a narrowband target's record is often
    short. The range is not determined when a replicate's fit fails or keeps fewer than the fit's 6 measurements
    (reason "diverged": the solution rests on that block, e.g. a record of two pieces), or when the rest of the
    record predicts one block's bearings more than a beamwidth (rms) and more than 3 of the prediction's sds away
    (reason :data:`~sonartrack.tma.verdict.NOT_ONE_TARGET`). Otherwise the covariance is widened to the jackknife's when
    larger at the 1e-3 level, and the range is not determined when its sd then reaches the range
    (:func:`_jackknife_widened`). Known limit: a bias over much of the record (a frequency step at mid-record) moves
    no single replicate, and is seen only by the residual checks of :func:`frequency_ml`.

    Parameters
    ----------
    result : TmaResult
        The bearings + frequency ML solution (:func:`frequency_ml`).
    est : BfEstimate
        Its fit (X0 = [x0, y0, vx, vy, f0] at the first time).
    sigma : ndarray (2,)
        The bearing (rad) and frequency (Hz) noise the fit was made with.
    c_mps : float
        Speed of sound (m/s).
    beamwidth_deg : float
        The array's broadside beamwidth (deg).

    Returns
    -------
    TmaResult
        ``result`` unchanged when undetermined already or consistent with its jackknife; else with the covariance
        widened (and a warning), or every row undetermined with the reason.
    """
    from sonartrack.tma.batch_bf import bf_jackknife
    from sonartrack.tma.sequential_bf import observer_kinematics

    if not result.solution.range_flags().any():
        return result
    rec = result.record
    t = np.asarray(rec.time_s, float)
    own, ov = observer_kinematics(result.ownship, t)
    jk = bf_jackknife(t, rec.bearing_rad, rec.frequency_hz, own, ov, float(sigma[0]), float(sigma[1]), est,
                      c_mps=c_mps)
    span = f"of the record's {len(jk.state)} stretches of time"
    failed = np.flatnonzero(~np.all(np.isfinite(jk.state), axis=1))
    if failed.size:
        return _undetermined(result, DIVERGED, f"without the {ordinal(int(failed[0]) + 1)} {span} the bearings + "
                             "frequency ML fails or has fewer than 6 measurements: the solution rests on it")
    return _jackknife_verdict(result, jk, beamwidth_deg, span, "another source's", len(jk.state))
