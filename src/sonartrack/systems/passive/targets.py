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
   Bearing noise: the standard deviation measured from the better side's ML residuals (tma/sides.py),
   so that the solution's uncertainty reflects this recording, not a nominal value; the ML covariance is
   inflated for the residuals' correlation from window to window (tma/solve.py
   :func:`~sonartrack.tma.solve.correlation_inflation`; setting ``ml_correlation_inflation``).
   A determined ML range whose residuals disagree with that stated noise, or whose likelihood is flatter than
   its stated covariance claims, is reported as not determined (:func:`determination_checked`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.core.angles import wrap_angle
from sonartrack.io.navigation import Navigation
from sonartrack.systems.passive.checks import (
    PROFILE_FAR_FACTOR,
    PROFILE_MIN_RISE,
    PROFILE_SIGMAS,
    range_profile_rise,
    residual_check,
)
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveStages
from sonartrack.tma.records import BearingRecord
from sonartrack.tma.settings import BatchSettings, TmaSettings
from sonartrack.tma.sides import SideDecision, mirror_bearings_rad, resolve_side, resolve_side_through_crossings
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult, correlation_inflation, solve_tma

#: how the warning of a range the record does not support begins (:func:`determination_checked`)
UNSUPPORTED_RANGE = "range not supported by the record:"
#: interval at which the side decision is re-taken on the growing record
SIDE_CHECK_S = 60.0


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


def side_resolved_time(t, cone_rad, heading_rad, xy, final: SideDecision, min_log_lr: float) -> float:
    """First checkpoint from which every later decision on the growing record agrees with ``final``.

    Parameters
    ----------
    t, cone_rad, heading_rad : ndarray (n,)
        The track's times (s), cone angles (rad) and the array's heading (rad) at those times.
    xy : ndarray (n, 2)
        The array centre (m).
    final : SideDecision
        The decision on the whole record.
    min_log_lr : float
        The decision threshold on |ln LR|.

    Returns
    -------
    float
        The time (s), checked every ``SIDE_CHECK_S``; NaN when the side was never resolved.
    """
    if final.side == "unresolved":
        return float("nan")
    checkpoints = np.arange(t[0] + SIDE_CHECK_S, t[-1], SIDE_CHECK_S)
    since = float(t[-1])
    for c in checkpoints[::-1]:
        n = int(np.searchsorted(t, c, side="right"))
        d = resolve_side(t[:n], cone_rad[:n], heading_rad[:n], xy[:n], min_log_lr=min_log_lr,
                         unfolded=final.unfolded_rad is not None)
        if d.side != final.side:
            break
        since = float(c)
    return since


def _tma_settings(method: str, sigma_bearing_rad: float, stages: PassiveStages, tonal: TonalTrack | None
                  ) -> TmaSettings:
    s = stages.settings
    use_f = tonal is not None and method != "ml"
    return TmaSettings(method=method, frequency=use_f, sigma_bearing_deg=float(np.clip(np.rad2deg(sigma_bearing_rad),
                                                                                       1e-3, 30.0)),
                       sigma_freq_hz=max(tonal.sigma_hz, s.sigma_freq_floor_hz) if use_f else 0.1,
                       imm=stages.imm, sequential=stages.sequential,
                       batch=BatchSettings(correlation_inflation=s.ml_correlation_inflation))


def frequency_record(t, bearing_rad, tonal: TonalTrack) -> BearingRecord:
    """Bearings with the tonal's frequency at the same times.

    Parameters
    ----------
    t, bearing_rad : ndarray (n,)
        The bearings' times (s) and true bearings (rad).
    tonal : TonalTrack
        The track's tonal line.

    Returns
    -------
    BearingRecord
        The times that have both a bearing and a tonal frequency (Hz).
    """
    f = np.interp(t, tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
    on = np.isin(t, tonal.time_s)
    f = np.where(on, f, np.nan)
    keep = np.isfinite(f)
    return BearingRecord(time_s=t[keep], bearing_rad=bearing_rad[keep], frequency_hz=f[keep])


def usable_tonal(tonal: TonalTrack | None, stages: PassiveStages) -> TonalTrack | None:
    """The tonal if it is clean enough for bearing + frequency TMA.

    Parameters
    ----------
    tonal : TonalTrack or None
        The track's tonal line.
    stages : PassiveStages
        Its settings' ``max_sigma_freq_hz`` and ``tma_min_tonal_snr_db``.

    Returns
    -------
    TonalTrack or None
        ``tonal``, or None when it is too noisy or too weak (the record is then bearings only).
    """
    s = stages.settings
    if tonal is None or tonal.sigma_hz > s.max_sigma_freq_hz or tonal.line_snr_db < s.tma_min_tonal_snr_db:
        return None
    return tonal


def _undetermined_because(result: TmaResult) -> str | None:
    """Why a determined ML range is not what its record supports (:func:`determination_checked`), or None."""
    t = np.asarray(result.record.time_s, float)
    z = np.asarray(result.record.bearing_rad, float)
    ts, state = np.asarray(result.solution.time_s, float), np.asarray(result.solution.state, float)
    own = result.ownship.position_at(t)
    at_t = np.stack([np.interp(t, ts, state[:, k]) for k in range(4)], axis=1)
    e = wrap_angle(z - np.arctan2(at_t[:, 0] - own[:, 0], at_t[:, 1] - own[:, 1]))
    kappa = correlation_inflation(e) if result.settings.batch.correlation_inflation else 1.0
    sigma = float(np.deg2rad(result.settings.sigma_bearing_deg))
    check = residual_check(t, e, sigma, inflation=kappa)
    if not check.consistent:
        return check.note()
    cols = solution_columns(result.solution, result.ownship)
    r, sd = float(cols["range_m"][-1]), float(cols["range_std_m"][-1])
    far = max(PROFILE_FAR_FACTOR * r, r + PROFILE_SIGMAS * sd)
    rise = range_profile_rise(t, z, own, sigma, at_t[-1], far) / kappa
    if rise >= PROFILE_MIN_RISE:
        return None
    return (f"the bearings fit a target at {far / 1e3:.1f} km almost as well as at {r / 1e3:.2f} km (likelihood "
            f"rise {rise:.1f} < {PROFILE_MIN_RISE:g}, the 95 % point of chi-square(1)): the record does not support "
            f"± {sd / 1e3:.2f} km")


def determination_checked(result: TmaResult) -> TmaResult:
    """An ML range that its record does not support is reported as not determined.

    Two tests (systems/passive/checks.py), on the solution's own bearings and the noise it states: the residuals
    must agree with that noise (:func:`~sonartrack.systems.passive.checks.residual_check`: chi-square of the
    residuals and of their 30 s block means, 99.9 % limits), and the likelihood must fall off as the stated
    covariance would have it: held at twice the range (or at the stated range + 3 sd, if farther), the best fit
    must be worse by at least the 95 % point of chi-square(1)
    (:func:`~sonartrack.systems.passive.checks.range_profile_rise`, in units of the stated covariance). A far
    target seen through a small maneuver has a likelihood flat towards long ranges, so its first-order covariance
    at a near estimate claims a narrow interval the data do not give (on the default scene's first 300 s: the
    tanker at 13.9 km estimated 2.44 +- 0.87 km, its likelihood at 5.0 km only 2.2 worse).

    Parameters
    ----------
    result : TmaResult
        The batch ML solution.

    Returns
    -------
    TmaResult
        ``result``, or, when its range was determined and a test fails, a copy with every row's
        ``range_determined`` False and the reason as a warning.
    """
    if not result.solution.range_flags().any():
        return result
    reason = _undetermined_because(result)
    if reason is None:
        return result
    solution = replace(result.solution, range_determined=np.zeros(len(result.solution.time_s), bool))
    return replace(result, solution=solution, warnings=result.warnings + (f"{UNSUPPORTED_RANGE} {reason}",))


def solve_target(target_id: int, m: TrackMeasurements, tonal: TonalTrack | None, nav: Navigation,
                 stages: PassiveStages) -> Target:
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

    Returns
    -------
    Target
        The side decision, the ML fits of both sides, and the IMM-MGEKF solution.
    """
    min_log_lr = stages.settings.min_side_log_lr
    t = np.asarray(m.time_s, float)
    xy, heading = nav.array_at(t)
    if m.unfolded_deg is not None:  # through endfire: the sides of every segment between axis crossings at once
        side = resolve_side_through_crossings(t, np.deg2rad(m.unfolded_deg), heading, xy, min_log_lr=min_log_lr)
        cone = side.unfolded_rad
    else:
        cone = np.deg2rad(np.asarray(m.cone_deg, float))
        side = resolve_side(t, cone, heading, xy, min_log_lr=min_log_lr)
    since = side_resolved_time(t, cone, heading, xy, side, min_log_lr)
    stbd, port = mirror_bearings_rad(cone, heading)
    chosen, other = (port, stbd) if side.side == "port" else (stbd, port)
    fit, other_fit = (side.port, side.starboard) if side.side == "port" else (side.starboard, side.port)
    sensor = nav.array_track()
    ml_settings = _tma_settings("ml", side.sigma_bearing_rad, stages, None)
    rec, rec_other = BearingRecord(time_s=t, bearing_rad=chosen), BearingRecord(time_s=t, bearing_rad=other)
    ml = determination_checked(solve_tma(rec, sensor, ml_settings, ml_fit=fit, unobservable="flag"))
    mirror = solve_tma(rec_other, sensor, ml_settings, ml_fit=other_fit, unobservable="flag")
    seq_settings = _tma_settings("imm-mgekf", side.sigma_bearing_rad, stages, usable_tonal(tonal, stages))
    record = frequency_record(t, chosen, tonal) if seq_settings.frequency else BearingRecord(time_s=t,
                                                                                              bearing_rad=chosen)
    if seq_settings.frequency and len(record.time_s) < 10:
        seq_settings = _tma_settings("imm-mgekf", side.sigma_bearing_rad, stages, None)
        record = BearingRecord(time_s=t, bearing_rad=chosen)
    seq = solve_tma(record, sensor, seq_settings)
    return Target(target_id, m, side, since, ml, mirror, seq, tonal)
