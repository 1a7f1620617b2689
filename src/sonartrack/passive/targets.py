"""From a confirmed bearing track to a target: array side, true bearings, and the two TMA solutions.

Per track (its raw peaks, passive/measurements.py):

1. Side. A line array measures the cone angle theta; the target lies on either side of the array axis,
   at true bearing  heading_array + theta  (starboard) or  heading_array - theta  (port). Both mirror
   hypotheses are fitted by a constant-velocity bearings-only ML (tma/sides.py); before the array turns,
   both explain the bearings equally (ln LR ~ 0, unresolved); after the turn only the true side does.
   The decision is re-taken on the growing record every ``SIDE_CHECK_S`` seconds, so the time it was
   resolved is known.
2. TMA on the chosen side's bearings, sensor = the array centre: batch ML with the observability check
   (paper P3; :func:`~sonartrack.tma.solve.solve_tma` method ``ml``), and the sequential IMM-MGEKF
   (paper P2), on bearings + the tonal's frequency when the track carries a tonal line.
   Bearing noise: the standard deviation measured from the better side's ML residuals (tma/sides.py),
   so that the solution's uncertainty reflects this recording, not a nominal value; the ML covariance is
   inflated for the residuals' correlation from window to window (:func:`correlation_inflation`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.tma.records import BearingRecord
from sonartrack.tma.settings import TmaSettings
from sonartrack.tma.sides import SideDecision, mirror_bearings_rad, resolve_side
from sonartrack.tma.solve import TmaResult, solve_tma

#: interval at which the side decision is re-taken on the growing record
SIDE_CHECK_S = 60.0


@dataclass(frozen=True, slots=True)
class Target:
    """A confirmed track's target: side decision, TMA solutions, and the tonal line if any."""

    target_id: int
    track: object  # TrackMeasurements
    side: SideDecision
    #: first time from which the side decision held (NaN if never resolved)
    side_resolved_s: float
    ml: TmaResult
    #: the ML fit of the rejected mirror hypothesis (drawn faint on the tactical picture)
    mirror_ml: TmaResult | None
    sequential: TmaResult
    tonal: object | None  # TonalTrack


def side_resolved_time(t, cone_rad, heading_rad, xy, final: SideDecision, min_log_lr: float) -> float:
    """First checkpoint from which every later decision on the growing record agrees with ``final``."""
    if final.side == "unresolved":
        return float("nan")
    checkpoints = np.arange(t[0] + SIDE_CHECK_S, t[-1], SIDE_CHECK_S)
    since = float(t[-1])
    for c in checkpoints[::-1]:
        n = int(np.searchsorted(t, c, side="right"))
        d = resolve_side(t[:n], cone_rad[:n], heading_rad[:n], xy[:n], min_log_lr=min_log_lr)
        if d.side != final.side:
            break
        since = float(c)
    return since


def _tma_settings(method: str, sigma_bearing_rad: float, settings, tonal) -> TmaSettings:
    use_f = tonal is not None and method != "ml"
    return TmaSettings(method=method, frequency=use_f, sigma_bearing_deg=float(np.clip(np.rad2deg(sigma_bearing_rad),
                                                                                       1e-3, 30.0)),
                       sigma_freq_hz=max(tonal.sigma_hz, settings.sigma_freq_floor_hz) if use_f else 0.1,
                       imm=settings.imm, sequential=settings.sequential)


def frequency_record(t, bearing_rad, tonal) -> BearingRecord:
    """Bearings with the tonal's frequency at the same times (only the times that have both)."""
    f = np.interp(t, tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
    on = np.isin(t, tonal.time_s)
    f = np.where(on, f, np.nan)
    keep = np.isfinite(f)
    return BearingRecord(time_s=t[keep], bearing_rad=bearing_rad[keep], frequency_hz=f[keep])


def usable_tonal(tonal, settings):
    """The tonal if it is clean enough for bearing + frequency TMA, else None (the record is then bearings only)."""
    if tonal is None or tonal.sigma_hz > settings.max_sigma_freq_hz or tonal.line_snr_db < settings.min_line_snr_db:
        return None
    return tonal


def correlation_inflation(residuals_rad) -> float:
    """Variance factor (1 + rho) / (1 - rho) >= 1 for residuals with lag-1 autocorrelation rho > 0.

    The chain's bearing errors are not white: from window to window a neighbouring ship's sidelobes and the
    background normaliser move slowly, so consecutive peaks err alike. The white-noise ML covariance
    (inverse Fisher information) then claims n independent bearings where there are fewer, about
    n (1 - rho) / (1 + rho) for an AR(1) error (its effective sample size, e.g. Bretherton et al. 1999);
    the covariance is inflated by the inverse ratio so that the reported uncertainty covers the error."""
    r = np.asarray(residuals_rad, float)
    r = r - r.mean()
    den = float(np.dot(r, r))
    if len(r) < 3 or den <= 0:
        return 1.0
    rho = float(np.clip(np.dot(r[:-1], r[1:]) / den, 0.0, 0.95))
    return (1.0 + rho) / (1.0 - rho)


def inflated_fit(fit, record: BearingRecord, sensor):
    """``fit`` with its covariance scaled by :func:`correlation_inflation` of its own residuals (None passes)."""
    from dataclasses import replace

    from sonartrack.core.angles import wrap_angle
    from sonartrack.tma.batch_ml import bearing_model

    if fit is None:
        return None
    t = np.asarray(record.time_s, float)
    h, _, _ = bearing_model(fit.x0, t - fit.t0_s, sensor.position_at(t))
    factor = correlation_inflation(wrap_angle(np.asarray(record.bearing_rad) - h))
    return replace(fit, covariance=np.asarray(fit.covariance) * factor)


def batch_ml(record: BearingRecord, sensor, settings: TmaSettings, fit=None) -> TmaResult:
    """Batch ML of a track's true bearings (paper P3), as ``solve_tma`` method ``ml`` gives it, but from the
    side decision's multi-start fit ``fit`` when there is one (the single pseudo-linear start of the plain ML
    can settle in a far local minimum). When the array did not maneuver during the track (range unobservable,
    paper P3 sec. 2) every row is flagged ``range_determined = False`` with the reason as its warning, instead
    of an error: the track still has a bearing, only its range is unknown. Otherwise rows beyond the range
    the record resolves are flagged (tma/solve.py :func:`flag_unresolved_range`)."""
    from dataclasses import replace

    from sonartrack.tma.batch import estimate_to_solution
    from sonartrack.tma.batch_ml import check_observability, ml_bearings_only
    from sonartrack.tma.solve import flag_unresolved_range

    t = np.asarray(record.time_s, float)
    own = sensor.position_at(t)
    sigma = float(np.deg2rad(settings.sigma_bearing_deg))
    why = check_observability(t - t[0], own)
    with np.errstate(invalid="ignore", over="ignore"):  # a covariance may be singular where range is unknown
        est = fit if fit is not None else ml_bearings_only(record.bearing_rad, t, own, sigma, check=False)
        solution = estimate_to_solution(est, t)
        if why is not None:
            solution = replace(solution, range_determined=np.zeros(len(t), bool))
            return TmaResult(solution=solution, record=record, ownship=sensor, settings=settings, warnings=(why,))
        import warnings

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            solution = flag_unresolved_range(solution, record, sensor, sigma)
    return TmaResult(solution=solution, record=record, ownship=sensor, settings=settings,
                     warnings=tuple(str(w.message) for w in caught))


def solve_target(target_id: int, m, tonal, nav, settings) -> Target:
    """Side, true bearings and TMA of one track's measurements ``m`` (module docstring)."""
    t = np.asarray(m.time_s, float)
    cone = np.deg2rad(np.asarray(m.cone_deg, float))
    xy, heading = nav.array_at(t)
    side = resolve_side(t, cone, heading, xy, min_log_lr=settings.min_side_log_lr)
    since = side_resolved_time(t, cone, heading, xy, side, settings.min_side_log_lr)
    stbd, port = mirror_bearings_rad(cone, heading)
    chosen, other = (port, stbd) if side.side == "port" else (stbd, port)
    fit, other_fit = (side.port, side.starboard) if side.side == "port" else (side.starboard, side.port)
    sensor = nav.array_track()
    ml_settings = _tma_settings("ml", side.sigma_bearing_rad, settings, None)
    rec, rec_other = BearingRecord(time_s=t, bearing_rad=chosen), BearingRecord(time_s=t, bearing_rad=other)
    ml = batch_ml(rec, sensor, ml_settings, inflated_fit(fit, rec, sensor))
    mirror = batch_ml(rec_other, sensor, ml_settings, inflated_fit(other_fit, rec_other, sensor))
    seq_settings = _tma_settings("imm-mgekf", side.sigma_bearing_rad, settings, usable_tonal(tonal, settings))
    record = frequency_record(t, chosen, tonal) if seq_settings.frequency else BearingRecord(time_s=t,
                                                                                              bearing_rad=chosen)
    if seq_settings.frequency and len(record.time_s) < 10:
        seq_settings = _tma_settings("imm-mgekf", side.sigma_bearing_rad, settings, None)
        record = BearingRecord(time_s=t, bearing_rad=chosen)
    seq = solve_tma(record, sensor, seq_settings)
    return Target(target_id, m, side, since, ml, mirror, seq, tonal)
