"""One entry point for every TMA method: a bearings record and an ownship track in, a target solution out.

:func:`solve_tma` is what ``sonartrack tma`` calls, and what a notebook calls with arrays::

    from sonartrack.tma import BearingRecord, OwnshipTrack, TmaSettings, solve_tma
    result = solve_tma(BearingRecord(time_s=t, bearing_rad=b), OwnshipTrack(time_s=tn, x_m=x, y_m=y),
                       TmaSettings(method="mgekf"))
    result.solution.state  # (n, 4): x, y, vx, vy of the target (m, m/s)

Methods (``settings.method``): the sequential filters of tma/sequential_bf.py (``ekf``, ``mgekf``,
``imm-ekf``, ``imm-mgekf``; paper P2), on bearings or, with ``settings.frequency``, bearings + frequency;
the batch estimators of tma/batch.py (``ml``, ``em-map``; paper P3), over the whole record or over a first
window (``settings.batch.window_s``) with a sequential EKF after it.

A system that runs ``ml`` on its own measurements can hand in what it knows (the passive chain does):
``ml_fit``, an ML estimate of the same record found by a wider search (the multi-start fits of the side
decision, tma/sides.py), taken as the solution instead of the single-start Gauss-Newton fit;
``settings.batch.correlation_inflation``, the covariance scaled for residuals correlated from one bearing to
the next (:func:`correlation_inflation`); and ``unobservable="flag"``, a record whose ownship did not maneuver
returned with every row flagged ``range_determined = False`` and the reason as a warning, instead of an error
(the bearing is still a measurement; only the range is unknown).

Every solution carries its verdict row by row (``range_determined`` and ``undetermined_reason``, tma/verdict.py):
the ML's from the maneuver (:func:`flag_unresolved_range`), the sequential filters' from their own output
(:func:`sequential_verdict`: diverged, inconsistent innovations, unobservable), em-map's from its SNR residuals
(:func:`em_map_verdict`); the summary prints "range NOT DETERMINED (reason)", never the number, for an
undetermined last row.
"""

from __future__ import annotations

import warnings
from contextlib import nullcontext
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.tma.record_checks import BearingSd
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution, check_bearing_sds, check_coverage
from sonartrack.tma.settings import BATCH_METHODS, SEQUENTIAL_METHODS, TmaSettings

if TYPE_CHECKING:
    from sonartrack.tma.advice import ObserverAdvice
    from sonartrack.tma.leg_solution import LegSolution


@dataclass(frozen=True, slots=True)
class TmaResult:
    """A solved record: the target solution, what it was solved from, and what the method adds."""

    solution: TmaSolution
    record: BearingRecord
    ownship: OwnshipTrack
    settings: TmaSettings
    #: estimated emitted frequency and its standard deviation (Hz) at the last time (frequency methods)
    f0_hz: float | None = None
    f0_std_hz: float | None = None
    #: IMM mode probabilities at the last time (imm-* methods)
    mode_probabilities: tuple[float, ...] | None = None
    #: warnings of the solver (e.g. range unobservable from bearings alone), one line each
    warnings: tuple[str, ...] = ()
    #: what the method found about its own answer (em-map: whether the propagation model explains the SNR; the
    #: bearing sd estimated or contradicted, tma/motion_verdict.py), printed at the end of the summary
    notes: tuple[str, ...] = ()
    #: the bearing noise sd the record's constant-velocity residuals measure, with its interval (record checks)
    bearing_sd: BearingSd | None = None
    #: the record's zigs and legs (tma/leg_solution.py; set by systems/tma/run.py ``run_tma(..., legs=True)``)
    legs: LegSolution | None = None
    #: the next ownship leg advised from the current leg's solution (tma/advice.py; None: not determined)
    advice: ObserverAdvice | None = None

    def summary(self) -> str:
        """One line: the record, and the target's range, bearing, course and speed at the last time.

        Returns
        -------
        str
            Method, number of measurements and their span (s); at the last time range (km), bearing (deg), course
            (deg), speed (kn) with one-sigma values (or the bearing and "range NOT DETERMINED (reason)" when the
            range is not determined: no number), f0 (Hz) and mode probabilities when present, and the method's notes.
        """
        from sonartrack.tma.solution_table import solution_columns
        from sonartrack.tma.verdict import bearing_text, not_determined_text

        cols = solution_columns(self.solution, self.ownship)
        i, s, t = len(cols["time_s"]) - 1, self.settings, self.record.time_s
        what = "bearings + frequencies" if s.frequency else "bearings"
        line = f"tma {s.method}: {len(t)} {what} over {t[0]:g}..{t[-1]:g} s; at {cols['time_s'][i]:g} s the target "
        if not cols["range_determined"][i]:
            bearing = "is at " + bearing_text(cols["bearing_deg"][i], cols["bearing_std_deg"][i])
            line += (f"{bearing}; {not_determined_text(cols['undetermined_reason'][i])} by this record, nor its "
                     "course and speed")
        else:
            line += (f"is at range {cols['range_m'][i] / 1e3:.2f} ± {cols['range_std_m'][i] / 1e3:.2f} km, bearing "
                     f"{cols['bearing_deg'][i]:.1f} ± {cols['bearing_std_deg'][i]:.1f} deg, course "
                     f"{cols['course_deg'][i]:.0f} ± {cols['course_std_deg'][i]:.0f} deg, speed "
                     f"{cols['speed_kn'][i]:.1f} ± {cols['speed_std_kn'][i]:.1f} kn")
            if self.f0_hz is not None:
                line += f", f0 {self.f0_hz:.2f} ± {self.f0_std_hz:.2f} Hz"
        if self.mode_probabilities is not None:
            line += ", mode probabilities " + "/".join(f"{m:.2f}" for m in self.mode_probabilities)
        if not s.is_sequential and s.batch.window_s is not None:
            line += f", batch on the first {s.batch.window_s:g} s then a sequential EKF"
        return line + "".join(f"; {n}" for n in self.notes)

    def leg_lines(self) -> list[str]:
        """The zigs and legs (tma/leg_solution.py), the current leg's answer when the method's last row is not
        determined and the current leg is, and the advice: lines printed after :meth:`summary` (none without legs).

        Returns
        -------
        list of str
            The lines.
        """
        if self.legs is None:
            return []
        out = self.legs.lines()
        leg = self.legs.current
        if leg is not None and not self.solution.range_flags()[-1] and len(self.legs.legs) > 1:
            out.append(current_leg_text(leg, self.ownship, float(self.record.time_s[-1])))
        if self.advice is not None:
            out.append(self.advice.line())
        return out


def current_leg_text(leg, ownship: OwnshipTrack, time_s: float) -> str:
    """The current leg's answer in a phrase: range and bearing at the last time, course and speed, with sds.

    Parameters
    ----------
    leg : Leg
        The current (last) leg (tma/legs.py), state at ``time_s``.
    ownship : OwnshipTrack
        The sensor's track (m).
    time_s : float
        The last bearing's time (s).

    Returns
    -------
    str
        "current leg (leg-wise ML): at T s the target is at range R ± S km, bearing ..., course ..., speed ...".
    """
    d = leg.state[:2] - ownship.position_at(time_s)
    r = float(np.hypot(*d))
    u = np.array([d[1], -d[0]]) / max(r * r, 1e-300)  # d bearing / d position (rad / m)
    with np.errstate(invalid="ignore"):
        b_sd = float(np.degrees(np.sqrt(u @ leg.state_cov[:2, :2] @ u)))
    return (f"current leg (leg-wise ML, since {leg.start_s:.0f} s): at {time_s:g} s the target is at range "
            f"{leg.range_m / 1e3:.2f} ± {leg.range_sd_m / 1e3:.2f} km, bearing "
            f"{np.degrees(np.arctan2(d[0], d[1])) % 360:.1f} ± {b_sd:.1f} deg, course {leg.course_deg:.0f} ± "
            f"{leg.course_sd_deg:.0f} deg, speed {leg.speed_kn:.1f} ± {leg.speed_sd_kn:.1f} kn")


def check_settings(settings: TmaSettings) -> None:
    """Refuse settings that belong to the other family of methods (a sign of a mistaken method).

    Parameters
    ----------
    settings : TmaSettings
        The settings; raises :class:`InputError` when a sequential method has ``batch.env``/``batch.sl_db`` or a
        batch method asks for ``frequency``.
    """
    if settings.is_sequential:
        require(settings.batch.env is None and settings.batch.sl_db is None,
                f"--env and --sl (batch.env, batch.sl_db) apply to the batch methods ({', '.join(BATCH_METHODS)}), "
                f"not to '{settings.method}'")
    else:
        require(not settings.frequency, f"--frequency applies to the sequential methods "
                                        f"({', '.join(SEQUENTIAL_METHODS)}), not to '{settings.method}'")


def _solve_sequential(record, ownship, settings: TmaSettings) -> dict:
    from sonartrack.tma.sequential_bf import solve_sequential

    solution, track = solve_sequential(record, ownship, settings.method,
                                       sigma_bearing_rad=float(np.deg2rad(settings.sigma_bearing_deg)),
                                       sigma_freq_hz=settings.sigma_freq_hz, use_frequency=settings.frequency,
                                       imm=settings.imm, sequential=settings.sequential)
    out: dict = {"solution": sequential_verdict(solution, track, record, ownship, settings)}
    if settings.frequency:
        out["f0_hz"] = float(track.rel_state[-1, 4])
        out["f0_std_hz"] = float(np.sqrt(track.rel_cov[-1, 4, 4]))
    if settings.method.startswith("imm"):
        out["mode_probabilities"] = tuple(float(m) for m in track.mode_prob[-1])
    return out


def sequential_verdict(solution: TmaSolution, track, record: BearingRecord, ownship: OwnshipTrack,
                       settings: TmaSettings) -> TmaSolution:
    """A sequential filter's solution with its verdict row by row (tma/verdict.py: diverged, unobservable,
    inconsistent innovations), from the filter's own output.

    Parameters
    ----------
    solution : TmaSolution
        The filter's absolute solution.
    track : SequentialTrack
        Its relative states, covariances and mode probabilities (tma/sequential_bf.py).
    record : BearingRecord
        The bearings (rad) and frequencies (Hz) it was run on.
    ownship : OwnshipTrack
        The sensor's track (m).
    settings : TmaSettings
        The method, noises, modes, the prior's range sd (``sequential.sigma_range_m``) and ``verdict``.

    Returns
    -------
    TmaSolution
        ``solution`` with ``range_determined`` and ``undetermined_reason`` set.
    """
    from sonartrack.models.relative_motion import observer_inputs
    from sonartrack.tma.imm_mgekf import combined_nis
    from sonartrack.tma.sequential_bf import filter_model, observer_kinematics
    from sonartrack.tma.verdict import sequential_reasons, with_reasons

    model = filter_model(settings.method, sigma_bearing_rad=float(np.deg2rad(settings.sigma_bearing_deg)),
                         sigma_freq_hz=settings.sigma_freq_hz, imm=settings.imm, sequential=settings.sequential)
    t = np.asarray(record.time_s, float)
    pos, vel = observer_kinematics(ownship, t)
    freq = np.asarray(record.frequency_hz, float) if settings.frequency else None
    with np.errstate(all="ignore"):
        nis, dof = combined_nis(t, record.bearing_rad, freq, observer_inputs(t, pos, vel), track.rel_state,
                                track.rel_cov, track.mode_prob, model)
    reasons = sequential_reasons(solution, ownship, nis, dof, settings.sequential.sigma_range_m, settings.verdict)
    return with_reasons(solution, reasons)


def flag_unresolved_range(solution: TmaSolution, record, ownship, sigma_bearing_rad: float) -> TmaSolution:
    """Bearings-only ML: flag the rows whose range lies beyond what the record can resolve
    (:func:`~sonartrack.tma.batch_ml.observable_range_limit_m`), whose range standard deviation exceeds the range
    itself (the one-sigma interval reaches the ownship), or whose covariance is not finite, and warn.
    The numbers stay in the table (the bearing is still good); the flag column says the range is not.

    Parameters
    ----------
    solution : TmaSolution
        The batch solution.
    record : BearingRecord
        Its bearings (times in s).
    ownship : OwnshipTrack
        Ownship positions (m).
    sigma_bearing_rad : float or ndarray (n,)
        Bearing noise standard deviation (rad), one or each bearing's (then the limit uses the sd of equal
        information, :meth:`~sonartrack.tma.records.BearingRecord.reference_sd_rad`).

    Returns
    -------
    TmaSolution
        ``solution`` with ``range_determined`` false on the flagged rows, reason "diverged" (covariance not
        finite) or "unobservable" (an :class:`UnobservableWarning` is issued when any is).
    """
    from sonartrack.tma.batch_ml import observable_range_limit_m
    from sonartrack.tma.solution_table import solution_columns
    from sonartrack.tma.verdict import DIVERGED, UNOBSERVABLE, with_reasons

    t = np.asarray(record.time_s, float)
    sd = np.broadcast_to(np.asarray(sigma_bearing_rad, float), t.shape)
    sigma_ref = float(1.0 / np.sqrt(np.mean(1.0 / np.square(sd))))  # the same information in one sd
    limit_m = observable_range_limit_m(t - t[0], ownship.position_at(t), sigma_ref)
    cols = solution_columns(solution, ownship)
    range_m, range_std_m = cols["range_m"], cols["range_std_m"]
    P = np.asarray(solution.covariance, float)
    bad_cov = ~np.all(np.isfinite(P), axis=(1, 2)) | (np.einsum("nii->n", P[:, :2, :2]) <= 0)
    with np.errstate(invalid="ignore"):
        ok = (range_m <= limit_m) & (range_std_m < range_m) & ~bad_cov
    reasons = np.where(bad_cov, DIVERGED, np.where(ok, "", UNOBSERVABLE)).astype(object)
    if not ok.all():
        from sonartrack.tma.batch import UnobservableWarning

        i = int(np.argmin(ok))
        warnings.warn(f"range not determined: the bearings-only solution puts the target at {range_m[i] / 1e3:.3g} "
                      f"± {range_std_m[i] / 1e3:.3g} km at {cols['time_s'][i]:g} s, and this record's ownship maneuver "
                      f"resolves range only to {limit_m / 1e3:.3g} km; trust the bearing, not the range (flag column "
                      "range_determined), or use a record with a larger maneuver or em-map with SNR",
                      UnobservableWarning, stacklevel=2)
    return with_reasons(solution, reasons)


def correlation_inflation(residuals_rad) -> float:
    """Variance factor (1 + rho) / (1 - rho) >= 1 for residuals with lag-1 autocorrelation rho > 0.

    Measured bearing errors need not be white: in the passive chain a neighbouring ship's sidelobes and the
    background normaliser move slowly from window to window, so consecutive bearings err alike. The white-noise
    ML covariance (inverse Fisher information) then claims n independent bearings where there are fewer, about
    n_eff = n (1 - rho) / (1 + rho) for an AR(1) error (its effective sample size; Bretherton et al. 1999,
    J. Climate 12, 1990-2009); the covariance is inflated by n / n_eff so that the reported uncertainty covers
    the error. rho is the sample lag-1 autocorrelation of the de-meaned residuals, clipped to 0..0.95.

    Parameters
    ----------
    residuals_rad : array_like (n,)
        The fit's bearing residuals in time order (rad).

    Returns
    -------
    float
        The factor (1 + rho) / (1 - rho) (1 for fewer than 3 residuals or zero spread).
    """
    rho = lag1_correlation(residuals_rad)
    return (1.0 + rho) / (1.0 - rho)


def lag1_correlation(residuals) -> float:
    """The sample lag-1 autocorrelation of de-meaned residuals in time order, clipped to 0..0.95 (0 for fewer than 3
    residuals or zero spread): the rho of :func:`correlation_inflation`.

    Parameters
    ----------
    residuals : array_like (n,)
        Residuals in time order.

    Returns
    -------
    float
        rho.
    """
    r = np.asarray(residuals, float)
    r = r - r.mean()
    den = float(np.dot(r, r))
    if len(r) < 3 or den <= 0:
        return 0.0
    return float(np.clip(np.dot(r[:-1], r[1:]) / den, 0.0, 0.95))


def _inflated(est, record: BearingRecord, own_xy):
    """``est`` with its covariance scaled by :func:`correlation_inflation` of its own residuals on ``record``."""
    from sonartrack.core.angles import wrap_angle
    from sonartrack.tma.batch_ml import bearing_model

    t = np.asarray(record.time_s, float)
    h, _, _ = bearing_model(est.x0, t - est.t0_s, own_xy)
    factor = correlation_inflation(wrap_angle(np.asarray(record.bearing_rad) - h) / record.relative_sd())
    return replace(est, covariance=np.asarray(est.covariance) * factor)


def _ml_estimate(record: BearingRecord, t, own, sigma_rad: float, ml_fit, unobservable: str):
    """The ML estimate: ``ml_fit`` when given (checked to be of this record), else Gauss-Newton from the
    pseudo-linear start; an unobservable record raises unless ``unobservable`` is "flag"."""
    from sonartrack.tma.batch_ml import check_observability, ml_bearings_only

    if ml_fit is None:
        return ml_bearings_only(record.bearing_rad, t, own, sigma_rad, check=unobservable == "raise")
    require(ml_fit.t0_s == t[0] and np.shape(ml_fit.x0) == (4,),
            f"ml_fit must be an ML estimate of this record (reference time {t[0]:g} s), got one at {ml_fit.t0_s:g} s")
    why = check_observability(t - t[0], own) if unobservable == "raise" else None
    if why is not None:
        raise InputError(why)
    return ml_fit


def _solve_ml(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings, ml_fit, unobservable: str) -> dict:
    """Bearings-only batch ML over the whole record (module docstring: ``ml_fit``, the inflation, ``unobservable``)."""
    from sonartrack.tma.batch import UnobservableWarning, estimate_to_solution
    from sonartrack.tma.batch_ml import check_observability
    from sonartrack.tma.verdict import UNOBSERVABLE, with_reasons

    t = np.asarray(record.time_s, float)
    own = ownship.position_at(t)
    sigma = (float(np.deg2rad(settings.sigma_bearing_deg)) if record.bearing_sd_rad is None
             else np.asarray(record.bearing_sd_rad, float))
    why = check_observability(t - t[0], own) if unobservable == "flag" else None
    # a record taken as it is may leave the covariance singular (range unknown): no warnings for its infinities
    quiet = np.errstate(invalid="ignore", over="ignore") if unobservable == "flag" else nullcontext()
    with quiet:
        est = _ml_estimate(record, t, own, sigma, ml_fit, unobservable)
        if settings.batch.correlation_inflation:
            est = _inflated(est, record, own)
        solution = estimate_to_solution(est, t)
    if why is not None:
        warnings.warn(why, UnobservableWarning, stacklevel=2)
        return {"solution": with_reasons(solution, np.full(len(t), UNOBSERVABLE, dtype=object))}
    return {"solution": flag_unresolved_range(solution, record, ownship, sigma)}


class _MemoryStore:
    """TL fields kept for the length of one solve (em-map's fit and its SNR check share one field)."""

    def __init__(self):
        self.fields: dict = {}

    def load(self, key: str):
        return self.fields.get(key)

    def save(self, key: str, ranges_m, depths_m, tl_db) -> None:
        self.fields[key] = (ranges_m, depths_m, tl_db)


def _solve_batch(record, ownship, settings: TmaSettings, environment, tl_store) -> dict:
    from sonartrack.tma.batch import solve_batch, solve_batch_then_ekf

    if settings.method == "em-map" and tl_store is None:
        tl_store = _MemoryStore()
    kw = dict(sigma_bearing_rad=float(np.deg2rad(settings.sigma_bearing_deg)), batch=settings.batch,
              em_map=settings.em_map, environment=environment, tl_store=tl_store)
    if settings.batch.window_s is None:
        solution = solve_batch(record, ownship, settings.method, **kw)
    else:
        solution = solve_batch_then_ekf(record, ownship, settings.method, window_s=settings.batch.window_s, **kw)
    if settings.method == "ml":  # em-map resolves range from the SNR, not from the maneuver
        return {"solution": flag_unresolved_range(solution, record, ownship, kw["sigma_bearing_rad"])}
    return em_map_verdict(solution, record, ownship, settings, environment=environment, tl_store=tl_store)


def em_map_verdict(solution: TmaSolution, record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings, *,
                   environment=None, tl_store=None) -> dict:
    """em-map's solution judged by its SNR residuals (tma/em_snr_check.py
    :func:`~sonartrack.tma.em_snr_check.snr_residual_check`).

    When the propagation model explains the SNRs along the solution's track the solution stands. When it does
    not, the SNR's range is not to be trusted: over the whole record with bearings that determine the range
    alone (an ownship maneuver; :func:`flag_unresolved_range`), the solution becomes the bearings-only ML's;
    otherwise every row is undetermined (reason :data:`~sonartrack.tma.verdict.SNR_NOT_EXPLAINED`). Either way
    the test's line is a note of the result (printed in its summary).

    Parameters
    ----------
    solution : TmaSolution
        The em-map solution (m, m/s) at the record's times.
    record : BearingRecord
        Bearings (rad), times (s) and SNRs (dB).
    ownship : OwnshipTrack
        The sensor's track (m).
    settings : TmaSettings
        The model (``batch``: environment, SL, frequency, depth, NL, DI, sigma_SNR; ``em_map``), the bearing noise
        and ``verdict.alpha``.
    environment : Environment, optional
        Overrides ``settings.batch.env``.
    tl_store : FieldStore, optional
        Cache of TL fields (the one the solve used).

    Returns
    -------
    dict
        "solution" and "notes" of the :class:`TmaResult`.
    """
    from sonartrack.tma.batch import snr_model
    from sonartrack.tma.em_snr_check import snr_residual_check
    from sonartrack.tma.verdict import SNR_NOT_EXPLAINED, with_reasons

    b, em = settings.batch, settings.em_map
    xi_bar, _, _ = snr_model(environment if environment is not None else b.env, b.sl_db, b.freq_hz, b.depth_m,
                             em.r_max_m * 1.05, b.nl_db, b.di_db, tl_store=tl_store, window_m=em.tl_average_m)
    t = np.asarray(solution.time_s, float)
    r = np.hypot(*(np.asarray(solution.state, float)[:, :2] - ownship.position_at(t)).T)
    check = snr_residual_check(record.snr_db, xi_bar(r), r, b.sigma_snr_db, alpha=settings.verdict.alpha)
    if check.explained:
        return {"solution": solution, "notes": (check.note(),)}
    if b.window_s is None:
        ml = _bearings_alone(record, ownship, settings)
        if ml is not None:
            return {"solution": ml, "notes": (f"{check.note()}: range from the bearings alone (ML)",)}
    undetermined = with_reasons(solution, np.full(len(t), SNR_NOT_EXPLAINED, dtype=object))
    return {"solution": undetermined, "notes": (f"{check.note()}, and the bearings alone do not determine the range",)}


def _bearings_alone(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings) -> TmaSolution | None:
    """The bearings-only ML solution of the record when it determines the range at the last time, else None."""
    ml_settings = settings.model_copy(update={"method": "ml"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            sol = _solve_ml(record, ownship, ml_settings, None, "flag")["solution"]
        except (InputError, np.linalg.LinAlgError):
            return None
    return sol if sol.range_flags()[-1] else None


def _judged(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings, record_checks: bool):
    """(the record's judgement or None, the settings with the bearing sd filled in when it is to be estimated)
    (tma/motion_verdict.py :func:`~sonartrack.tma.motion_verdict.judge_record`)."""
    if not record_checks and settings.sigma_bearing_deg is not None:
        return None, settings
    from sonartrack.tma.motion_verdict import judge_record

    judgement = judge_record(record, ownship, settings)
    return judgement, settings.model_copy(update={"sigma_bearing_deg": judgement.sigma_deg(settings)})


def with_record_sd(record: BearingRecord, settings: TmaSettings) -> TmaSettings:
    """The settings with ``sigma_bearing_deg`` the reference of the record's per-bearing sds, when it gives them
    (:meth:`~sonartrack.tma.records.BearingRecord.reference_sd_rad`: what the single-sd methods use; the ML and the
    record's checks weigh each bearing by its own). A different ``sigma_bearing_deg`` given as well is refused: one
    of the two would be silently ignored.

    Parameters
    ----------
    record : BearingRecord
        The measurements, ``bearing_sd_rad`` optional.
    settings : TmaSettings
        The settings.

    Returns
    -------
    TmaSettings
        ``settings``, with ``sigma_bearing_deg`` set from the record when it gives each bearing's sd.
    """
    check_bearing_sds(record)
    if record.bearing_sd_rad is None:
        return settings
    from sonartrack.tma.motion_verdict import SIGMA_CEILING_DEG

    ref_deg = float(np.clip(np.rad2deg(record.reference_sd_rad()), 1e-9, SIGMA_CEILING_DEG))
    given = settings.sigma_bearing_deg
    if given is not None and abs(given - ref_deg) > 1e-9 * ref_deg:
        raise InputError(f"the record gives each bearing's sd (reference {ref_deg:.3g} deg) and sigma_bearing_deg "
                         f"(--sigma-bearing-deg) gives {given:g} deg: leave out one of the two")
    return settings.model_copy(update={"sigma_bearing_deg": ref_deg})


def solve_tma(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings | None = None, *,
              environment=None, tl_store=None, ml_fit=None,
              unobservable: Literal["raise", "flag"] = "raise", record_checks: bool = True) -> TmaResult:
    """Solve a bearings (+ frequency, SNR) record for the target's track (module docstring).

    Parameters
    ----------
    record : BearingRecord
        Bearings (rad, clockwise from north) at increasing times (s), with frequencies (Hz) or SNRs (dB) when
        the method uses them, and optionally each bearing's noise sd (``bearing_sd_rad``, rad: the whole-record
        ML and the record's checks weigh each bearing by it, the other methods use :func:`with_record_sd`'s).
    ownship : OwnshipTrack
        The sensor's track; it must cover the record (no extrapolation, gaps up to
        ``settings.inputs.max_nav_gap_s``).
    settings : TmaSettings, optional
        Method and noise; default ``TmaSettings()``.
    environment : Environment, optional
        em-map: the propagation environment, overriding ``settings.batch.env`` (a shipped environment's name).
    tl_store : FieldStore, optional
        em-map: a cache of transmission-loss fields.
    ml_fit : BatchEstimate, optional
        ml over the whole record only: an ML estimate of this record found by a wider search (e.g. tma/sides.py
        :func:`~sonartrack.tma.sides.resolve_side`'s), taken instead of the single-start fit (a far local minimum).
    unobservable : {"raise", "flag"}
        ml over the whole record only: with an ownship that did not maneuver, "raise" refuses the record
        (:class:`~sonartrack.core.errors.InputError`); "flag" returns the solution with every row's
        ``range_determined`` False and the reason in ``warnings``.
    record_checks : bool
        Judge the answer by its record (tma/motion_verdict.py; off in the passive chain, which runs the same checks
        with its line-array weights, side and jackknife). A ``sigma_bearing_deg`` of None is estimated anyway.

    Returns
    -------
    TmaResult
        The solution at the record's times; solver warnings in ``result.warnings``. Mistakes raise
        :class:`~sonartrack.core.errors.InputError`.
    """
    settings = with_record_sd(record, TmaSettings() if settings is None else settings)
    check_settings(settings)
    check_coverage(record, ownship, settings.inputs.max_nav_gap_s)
    whole_ml = settings.method == "ml" and settings.batch.window_s is None
    require(unobservable in ("raise", "flag"), f"unobservable must be 'raise' or 'flag', got {unobservable!r}")
    require(whole_ml or (ml_fit is None and unobservable == "raise"),
            "ml_fit and unobservable='flag' apply to method ml over the whole record (no batch.window_s)")
    judgement, settings = _judged(record, ownship, settings, record_checks)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if settings.is_sequential:
            parts = _solve_sequential(record, ownship, settings)
        elif whole_ml:
            parts = _solve_ml(record, ownship, settings, ml_fit, unobservable)
        else:
            parts = _solve_batch(record, ownship, settings, environment, tl_store)
    result = TmaResult(record=record, ownship=ownship, settings=settings,
                       warnings=tuple(str(w.message) for w in caught), **parts)
    if not record_checks:
        return result
    from sonartrack.tma.motion_verdict import record_verdict

    return record_verdict(result, judgement)
