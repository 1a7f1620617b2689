"""Every TMA method's answer judged against its record: is the target's constant-velocity motion what the bearings
say, and what is their noise? (what :func:`~sonartrack.tma.solve.solve_tma` adds for ``sonartrack tma``).

Every method of tma/ (the sequential filters through their tuned process noise too) reports a target that keeps
its course and speed, so the record is first fitted by the bearings-only constant-velocity ML
(:func:`judge_record`, tma/batch_ml.py) and its residuals tested (tma/record_checks.py):

* the motion model: independent bearings leave white residuals about the right model; a target that changed course
  or speed leaves runs of one sign (:func:`~sonartrack.tma.record_checks.whiteness_check`, at ``verdict.alpha``).
  For bearing errors declared correlated (``batch.correlation_inflation``) the passive chain's block test is used
  instead, the block means' chi-square against the stated (or estimated) noise with the lag-1 correlation inflation
  (:func:`~sonartrack.tma.record_checks.residual_check`, blocks of at least three bearings). A rejected record
  leaves every row of every method undetermined, reason ``target manoeuvred: residuals reject constant velocity,
  largest A-B s`` (:data:`~sonartrack.tma.verdict.MANOEUVRED`; the span from
  :func:`~sonartrack.tma.record_checks.residual_span`);
* the noise: its sd measured from the residuals with its 95 % chi-square interval
  (:func:`~sonartrack.tma.record_checks.bearing_sd_estimate`); used as the methods' bearing sd when none is given
  (``sigma_bearing_deg`` unset), and when one is given and lies outside the interval, reported. A rejected fit's
  residuals hold the manoeuvre's misfit as well as the noise (on turning records of 1 deg noise they measured
  1.4-5.4 deg, up to 30), so there the sd is measured from the bearings alone, by their differences of order
  :data:`~sonartrack.tma.record_checks.DIFFERENCE_ORDER` on the uneven times with a MAD screen and Satterthwaite's
  interval (:func:`~sonartrack.tma.record_checks.difference_sd_estimate`): used when none is given, and a given sd
  outside its interval reported;
* the misfit against a given noise: with ``sigma_bearing_deg`` given, the residuals' chi-square
  S / sigma^2 ~ chi-square(n - 4) under the model (Bar-Shalom, Li & Kirubarajan 2001, sec. 3.7.4: the fit's
  normalised sum of squares) above its 1 - ``verdict.alpha`` point rejects the fit as well (reason ``residuals
  exceed the stated noise``): either the target manoeuvred in a way that leaves no runs (small zigs under wide
  noise) or the stated sd is too small; the answer is not printed as determined either way, and leaving the sd
  out (estimated) is the fix for the second. Only the upper tail: a given sd larger than the residuals is
  reported, not rejected.

Then, where the record keeps the model (:func:`record_verdict`): the ML is checked as the passive chain checks it
(tma/record_verdict.py :func:`~sonartrack.tma.record_verdict.determination_checked`: residual scale against the
stated noise, profile likelihood of the final range), and a sequential filter on bearings is held to that checked
ML of the same record (:func:`~sonartrack.tma.record_verdict.batch_held`). Why the ML rather than the filter's own
residuals: a filter's process noise lets it follow a turn, so its innovations can pass while its range is wrong
(bearings-only, a target's manoeuvre can mimic a range change); the ML has no process noise, so its residuals carry
the whole misfit, and its covariance is the one the record's checks have tested.
"""

from __future__ import annotations

import contextlib
import warnings
from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.tma.record_checks import (
    DIFFERENCE_ORDER,
    RESIDUAL_BLOCK_S,
    BearingSd,
    ResidualCheck,
    WhitenessCheck,
    bearing_sd_estimate,
    difference_sd_estimate,
    residual_check,
    residual_span,
    whiteness_check,
)
from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.settings import TmaSettings
from sonartrack.tma.verdict import EXCEEDS_STATED_NOISE, MANOEUVRED

#: the bearings' resolution (deg): residual structure far below it is not judged a manoeuvre
#: (:func:`~sonartrack.tma.record_checks.whiteness_check`'s floor), and an estimated sd is at least this. Bearing
#: files give degrees to 0.01 at best, and an ownship interpolated between fixes on a turn errs by about 0.001 deg
#: (a 5 kn ship turning 2.25 deg/s, fixes 10 s apart, a target at 10 km: 0.0013 deg rms, 0.009 deg at most)
SIGMA_FLOOR_DEG = 0.01
#: ... and at most this (the settings' limit)
SIGMA_CEILING_DEG = 30.0


@dataclass(frozen=True, slots=True)
class RecordJudgement:
    """What the constant-velocity ML says of a record (:func:`judge_record`): its residual scale, the stated sd
    (None: estimated), the motion test and the span its residuals point at. ``why_untested`` when no fit was
    possible (a record too short or degenerate)."""

    noise: BearingSd | None
    given_rad: float | None
    whiteness: WhitenessCheck | None = None
    block: ResidualCheck | None = None
    span: tuple[float, float] | None = None
    why_untested: str | None = None
    #: the residuals' chi-square against the given sd and its 1 - alpha point (None without a given sd)
    misfit: tuple[float, float] | None = None
    #: the record gave each bearing's sd: ``given_rad`` is their reference (tma/records.py
    #: :meth:`~sonartrack.tma.records.BearingRecord.reference_sd_rad`) and ``noise`` the residual scale in its units
    per_bearing: bool = False
    #: the sd from the bearings' differences, no motion model (:func:`~sonartrack.tma.record_checks.
    #: difference_sd_estimate`), measured where the record rejects the fit (None elsewhere or too few bearings)
    differences: BearingSd | None = None

    @property
    def runs(self) -> bool:
        """Whether the residuals' runs (or correlated blocks) reject constant velocity."""
        if self.whiteness is not None:
            return not self.whiteness.white
        return self.block is not None and self.block.block_chi2 > self.block.block_limit

    @property
    def excess(self) -> bool:
        """Whether the residuals exceed the given noise (chi-square above its 1 - alpha point)."""
        return self.misfit is not None and self.misfit[0] > self.misfit[1]

    @property
    def rejected(self) -> bool:
        """Whether the record rejects the constant-velocity fit: runs in its residuals, or more misfit than the
        given noise allows."""
        return self.runs or self.excess

    def reason(self) -> str:
        """The rows' reason for a rejected record, with the span.

        Returns
        -------
        str
            "target manoeuvred: residuals reject constant velocity, largest A-B s".
        """
        where = f", largest {self.span[0]:.0f}-{self.span[1]:.0f} s" if self.span is not None else ""
        if self.runs:
            return f"{MANOEUVRED}: residuals reject constant velocity{where}"
        if self.per_bearing:
            return (f"{EXCEEDS_STATED_NOISE}: residuals {self.noise.sd_rad / self.given_rad:.3g} times the stated "
                    f"bearing sds (target manoeuvred{where}, or the sds too small: leave them out to estimate one)")
        return (f"{EXCEEDS_STATED_NOISE}: rms {np.rad2deg(self.noise.sd_rad):.3g} deg against the stated "
                f"{np.rad2deg(self.given_rad):.3g} deg (target manoeuvred{where}, or the sd too small: leave it out "
                "to estimate it)")

    def test_note(self) -> str:
        """The motion test's statistic in a phrase.

        Returns
        -------
        str
            The whiteness or block test's line.
        """
        if self.excess and not self.runs:
            return (f"residual chi-square {self.misfit[0]:.1f} against the stated sd > {self.misfit[1]:.1f} "
                    "(its 1 - alpha point)")
        if self.whiteness is not None:
            return self.whiteness.note()
        return self.block.note() if self.block is not None else ""

    def notes(self) -> tuple[str, ...]:
        """What the summary says of the noise: the estimate, a stated sd the residuals contradict, or why no
        test was made.

        Returns
        -------
        tuple of str
            Zero or one phrase.
        """
        if self.why_untested is not None:
            return (f"motion model not tested: {self.why_untested}",)
        if self.rejected and self.differences is not None:
            return self._difference_notes()
        if self.runs:
            return (f"bearing sd not estimated: the constant-velocity fit is rejected (its residual scale "
                    f"{np.rad2deg(self.noise.sd_rad):.3g} deg bounds it)",)
        if self.given_rad is None:
            floored = np.rad2deg(self.noise.sd_rad) < SIGMA_FLOOR_DEG
            used = f"; used {SIGMA_FLOOR_DEG:g} deg, the bearings' resolution" if floored else ""
            return (f"bearing sd estimated from the record: {self.noise.text()}{used}",)
        if self.per_bearing and self.noise.excludes(self.given_rad):
            return (f"the given bearing sds are contradicted by the record: its residuals are "
                    f"{self.noise.sd_rad / self.given_rad:.3g} [{self.noise.lo_rad / self.given_rad:.3g}, "
                    f"{self.noise.hi_rad / self.given_rad:.3g}] times them",)
        if self.noise.excludes(self.given_rad):
            return (f"the given bearing sd {np.rad2deg(self.given_rad):.3g} deg is contradicted by the record: its "
                    f"residuals measure {self.noise.text()}",)
        return ()

    def _difference_notes(self) -> tuple[str, ...]:
        """:meth:`notes` of a rejected record: the sd its bearings' differences measure, and a given sd they
        contradict."""
        d, scale = self.differences, np.rad2deg(self.noise.sd_rad)
        what = (f"from the bearings' differences (order {DIFFERENCE_ORDER}, no motion model; the constant-velocity "
                f"fit is rejected, its residual scale {scale:.3g} deg)")
        if self.given_rad is None:
            floored = np.rad2deg(d.sd_rad) < SIGMA_FLOOR_DEG
            used = f"; used {SIGMA_FLOOR_DEG:g} deg, the bearings' resolution" if floored else ""
            return (f"bearing sd estimated {what}: {d.text()}{used}",)
        if self.per_bearing:
            verdict = "which contradicts them" if d.excludes(self.given_rad) else "consistent with them"
            return (f"bearing sds measured {what}: {d.sd_rad / self.given_rad:.3g} [{d.lo_rad / self.given_rad:.3g}, "
                    f"{d.hi_rad / self.given_rad:.3g}] times the given ones, {verdict}",)
        if d.excludes(self.given_rad):
            return (f"the given bearing sd {np.rad2deg(self.given_rad):.3g} deg is contradicted by the record: "
                    f"measured {what}: {d.text()}",)
        return (f"bearing sd measured {what}: {d.text()}, consistent with the given "
                f"{np.rad2deg(self.given_rad):.3g} deg",)

    def sigma_deg(self, settings: TmaSettings) -> float:
        """The bearing sd the methods use (deg): the given one, else the estimate within the bounds.

        Parameters
        ----------
        settings : TmaSettings
            ``sigma_bearing_deg`` (None: estimated).

        Returns
        -------
        float
            The sd (deg).
        """
        if settings.sigma_bearing_deg is not None:
            return float(settings.sigma_bearing_deg)
        if self.noise is None:
            raise InputError(f"the bearing sd cannot be estimated from this record ({self.why_untested}): give it "
                             "with --sigma-bearing-deg (sigma_bearing_deg)")
        sd = self.differences if self.rejected and self.differences is not None else self.noise
        return float(np.clip(np.rad2deg(sd.sd_rad), SIGMA_FLOOR_DEG, SIGMA_CEILING_DEG))


def cv_residuals(record: BearingRecord, ownship: OwnshipTrack) -> np.ndarray:
    """The residuals (rad) of the bearings-only constant-velocity ML of the whole record: the lowest-cost fit from
    the pseudo-linear start (tma/batch_ml.py) and from the passive chain's multi-start tracks (tma/sides.py
    :func:`~sonartrack.tma.sides.fit_cv_target`), the ownship's maneuver not required. One start is not enough
    for a test of the model: without an ownship maneuver the cost is flat along range, and a single Gauss-Newton
    start may stop in a far local minimum whose residuals run in arcs (measured: a one-leg ownship, 151 bearings of
    0.5 deg, read back from a CSV file: residual sd 6.5 deg, lag-1 correlation 0.97, against 0.44 deg and -0.02 for
    the best of the starts).

    Parameters
    ----------
    record : BearingRecord
        Bearings (rad) at times (s).
    ownship : OwnshipTrack
        The sensor's track (m).

    Returns
    -------
    ndarray (n,)
        Measured minus fitted bearings (rad, wrapped; the fit weighs each bearing by its own sd when the record
        gives them). Raises InputError, LinAlgError or FloatingPointError when no fit is possible.
    """
    from sonartrack.tma.batch_ml import bearing_model, ml_bearings_only
    from sonartrack.tma.sides import fit_cv_target

    t = np.asarray(record.time_s, float)
    z = wrap_angle(np.asarray(record.bearing_rad, float))
    own = ownship.position_at(t)
    rel = record.relative_sd()  # each bearing weighed by its own sd when the record gives them
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        fits = [fit_cv_target(z, t, own, relative_sigma=rel)]
        with contextlib.suppress(InputError, np.linalg.LinAlgError, FloatingPointError):
            fits.append(ml_bearings_only(z, t, own, rel, check=False))
        fits = [f for f in fits if f is not None and np.isfinite(f.objective) and np.all(np.isfinite(f.x0))]
        if not fits:
            raise FloatingPointError("no start converges")
        best = min(fits, key=lambda f: f.objective)
        h, _, _ = bearing_model(best.x0, t - t[0], own)
    e = wrap_angle(z - h)
    if not np.all(np.isfinite(e)):
        raise FloatingPointError("the constant-velocity fit is not finite")
    return e


def judge_record(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings) -> RecordJudgement:
    """The constant-velocity ML's judgement of a record (module docstring).

    Parameters
    ----------
    record, ownship
        The bearings and the sensor's track, as :func:`cv_residuals`.
    settings : TmaSettings
        ``sigma_bearing_deg`` (None: estimated), ``verdict.alpha``, ``batch.correlation_inflation``. A record that
        gives each bearing's sd (``record.bearing_sd_rad``) is judged with those: its residuals are whitened by
        them (in units of their reference sd), and the noise estimate is their scale.

    Returns
    -------
    RecordJudgement
        The residual scale, the motion test and the span (``why_untested`` set when no fit is possible).
    """
    from sonartrack.tma.solve import correlation_inflation

    per_bearing = record.bearing_sd_rad is not None
    given = (record.reference_sd_rad() if per_bearing else
             None if settings.sigma_bearing_deg is None else float(np.deg2rad(settings.sigma_bearing_deg)))
    try:
        e = cv_residuals(record, ownship)
    except (InputError, np.linalg.LinAlgError, FloatingPointError) as failure:
        return RecordJudgement(None, given, why_untested=f"no constant-velocity fit of the bearings ({failure})",
                               per_bearing=per_bearing)
    t = np.asarray(record.time_s, float)
    e = e / record.relative_sd()  # in units of the reference sd: each bearing weighed by its own
    noise = bearing_sd_estimate(e)
    sigma = given if given is not None else max(noise.sd_rad, float(np.deg2rad(SIGMA_FLOOR_DEG)))
    if settings.batch.correlation_inflation:
        block_s = max(RESIDUAL_BLOCK_S, 3.0 * float(np.median(np.diff(t))))
        block = residual_check(t, e, sigma, inflation=correlation_inflation(e), block_s=block_s)
        judgement = RecordJudgement(noise, given, block=block, per_bearing=per_bearing)
    else:
        judgement = RecordJudgement(noise, given, whiteness=whiteness_check(
            e, settings.verdict.alpha, float(np.deg2rad(SIGMA_FLOOR_DEG))), per_bearing=per_bearing)
    if given is not None and e.size > 4:
        misfit = float(np.sum((np.asarray(e, float) / given) ** 2))
        judgement = replace(judgement, misfit=(misfit, float(chi2_quantile(1.0 - settings.verdict.alpha, e.size - 4))))
    if judgement.rejected:
        judgement = replace(judgement, span=residual_span(t, e, sigma), differences=_differences(record))
    return judgement


def _differences(record: BearingRecord) -> BearingSd | None:
    """The record's bearing sd from its differences (module doc), None when it has too few bearings for them."""
    if len(record.time_s) < DIFFERENCE_ORDER + 8:
        return None
    return difference_sd_estimate(record.time_s, record.bearing_rad, record.relative_sd())


def record_verdict(result, judgement: RecordJudgement):
    """``result`` judged by its record (module docstring): every row undetermined when the record rejects constant
    velocity; else the whole-record ML checked (residual scale, profile likelihood) and a sequential filter on
    bearings held to that checked ML; the noise's note added either way.

    Parameters
    ----------
    result : TmaResult
        A method's answer (tma/solve.py).
    judgement : RecordJudgement
        :func:`judge_record` of its record.

    Returns
    -------
    TmaResult
        ``result`` with its verdict, ``bearing_sd`` and notes.
    """
    from sonartrack.tma.record_verdict import determination_checked, undetermined

    result = replace(result, bearing_sd=judgement.noise, notes=result.notes + judgement.notes())
    s = result.settings
    if judgement.rejected:  # before any reason the CV fit gave (unobservable...): the model itself is rejected
        n = len(result.solution.time_s)
        result = replace(result, solution=replace(result.solution, range_determined=np.ones(n, bool),
                                                  undetermined_reason=np.full(n, "", dtype=object)))
        return undetermined(result, judgement.reason(), f"{judgement.test_note()}: the target did not keep one "
                            "course and speed over the record (solve its legs apart)")
    if judgement.why_untested is not None:
        return result
    if s.method == "ml" and s.batch.window_s is None:
        return determination_checked(result, result.record.relative_sd())
    if s.is_sequential and not s.frequency:
        return _held_to_ml(result)
    return result


def _held_to_ml(result):
    """A sequential filter on bearings held to the checked bearings-only ML of its record (module docstring)."""
    from sonartrack.tma.record_verdict import batch_held, determination_checked
    from sonartrack.tma.solve import solve_tma

    ml_settings = result.settings.model_copy(update={"method": "ml", "frequency": False})
    try:
        ml = solve_tma(result.record, result.ownship, ml_settings, unobservable="flag", record_checks=False)
    except (InputError, np.linalg.LinAlgError):
        return result
    return batch_held(result, determination_checked(ml, result.record.relative_sd()))
