"""A record's legs as ``sonartrack tma`` reports them: zigs found, legs fitted, the current leg as the answer.

:func:`solve_legs` runs the zig detector and the joint leg fit (tma/zig.py :func:`~sonartrack.tma.zig.detect_zigs`,
tma/legs.py :func:`~sonartrack.tma.legs.fit_legs`, with the fit's own whiteness verdict) on the bearings of a
record. The bearing sd is the given one; when none is given it is estimated from the leg fit's residuals
(sum e^2 / (n - p), p the fit's parameters, with its chi-square interval) by fixed-point iteration: detect and fit
at an sd, measure the sd about the legs, detect again with it, until it moves by less than 5 % (at most
:data:`MAX_SIGMA_PASSES` passes). The start is not the constant-velocity fit's residual scale, which holds a
manoeuvring target's misfit as well as the noise (measured: 6.3 deg on a three-leg record of 1 deg noise, at
which no zig is found), but the smaller of it and the bearings' own scatter about a locally straight line
(tma/observer_legs.py :func:`~sonartrack.tma.observer_legs.three_point_sd`, a robust estimate that needs no motion
model), floored at the bearings' resolution.

The current (last) leg's state at the last bearing, with its covariance, is the record's answer when the leg is
determined (range sd below the range, residuals white); :func:`current_advice` asks tma/advice.py for the next
ownship leg from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.tma.legs import Leg
from sonartrack.tma.observer_legs import three_point_sd
from sonartrack.tma.record_checks import BearingSd, bearing_sd_estimate
from sonartrack.tma.zig import DEFAULT_FALSE_ALARM_PER_HOUR, ZigReport, detect_zigs

#: passes of the bearing sd's fixed-point estimate (module doc)
MAX_SIGMA_PASSES = 4
#: an estimated sd is at least the bearings' resolution (deg; as tma/motion_verdict.py's SIGMA_FLOOR_DEG)
SIGMA_FLOOR_DEG = 0.01
#: ... and the ownship's velocity when it is turning is the straight-line fit over this last span (s)
VELOCITY_SPAN_S = 60.0


@dataclass(frozen=True, slots=True)
class LegSolution:
    """The zigs and legs of a record (``report`` None with ``message`` when none could be fitted), the bearing sd
    they used (rad) and, when it was estimated, the estimate with its interval."""

    report: ZigReport | None
    sigma_rad: float
    sigma_estimate: BearingSd | None = None
    message: str = ""
    #: the record gave each bearing's sd (``sigma_rad`` is then their information-equivalent reference)
    per_bearing: bool = False

    @property
    def legs(self) -> tuple[Leg, ...]:
        """The fitted legs (empty when none)."""
        return () if self.report is None or self.report.legs is None else self.report.legs.legs

    @property
    def current(self) -> Leg | None:
        """The last leg when it is determined (the record's answer), else None."""
        legs = self.legs
        return legs[-1] if legs and legs[-1].determined else None

    def lines(self) -> list[str]:
        """The zigs and legs in lines for the summary: one for the zigs, one per leg.

        Returns
        -------
        list of str
            E.g. "legs: 1 zig, at 1790 s (95 % interval 1720-1850 s); 2 legs (bearing sd 1 deg given)" and
            "  leg 1: 0-1790 s, course 045 ± 3 deg, speed 8.0 ± 0.4 kn, range at its end 10.2 ± 0.8 km".
        """
        if not self.legs:
            return [f"legs: not fitted ({self.message or self.report.message})"]
        zigs = self.report.zigs
        where = ", ".join(f"at {z.time_s:.0f} s (95 % interval {z.interval_s[0]:.0f}-{z.interval_s[1]:.0f} s)"
                          for z in zigs)
        head = f"{len(zigs)} zig{'s' if len(zigs) != 1 else ''}" + (f", {where}" if zigs else "")
        sd = (f"estimated from the legs' residuals: {self.sigma_estimate.text()}" if self.sigma_estimate is not None
              else "each bearing's own given, this their reference" if self.per_bearing else "given")
        out = [f"legs: {head}; {len(self.legs)} leg{'s' if len(self.legs) != 1 else ''} (bearing sd "
               f"{np.degrees(self.sigma_rad):.3g} deg, {sd}; false zigs stated "
               f"{self.report.false_alarm_per_hour:g} per hour)"]
        for k, leg in enumerate(self.legs):
            now = " (current)" if k == len(self.legs) - 1 else ""
            if leg.determined:  # without a range, bearings give no course or speed either: none is printed
                what = (f"course {leg.course_deg:03.0f} ± {leg.course_sd_deg:.0f} deg, speed {leg.speed_kn:.1f} ± "
                        f"{leg.speed_sd_kn:.1f} kn, range at its end {leg.range_m / 1e3:.2f} ± "
                        f"{leg.range_sd_m / 1e3:.2f} km")
            else:
                what = f"range, course and speed not determined ({leg.reason})"
            out.append(f"  leg {k + 1}{now}: {leg.start_s:.0f}-{leg.end_s:.0f} s, {what}")
        return out

    def table(self) -> dict[str, np.ndarray]:
        """One row per leg: ``tma_legs.csv``'s columns (empty when no legs).

        Returns
        -------
        dict of str to ndarray
            leg, start_s, end_s and their sds, the zig interval that starts the leg, course_deg, speed_kn with
            sds, the state at the leg's end (x_m, y_m, vx_mps, vy_mps) with the position sds, range_m, range_sd_m,
            determined, reason, current.
        """
        legs = self.legs
        zigs = self.report.zigs if legs else ()
        lo = np.r_[np.nan, [z.interval_s[0] for z in zigs]][:len(legs)]
        hi = np.r_[np.nan, [z.interval_s[1] for z in zigs]][:len(legs)]
        col = {name: np.array([getattr(leg, name) for leg in legs], float) for name in
               ("start_s", "end_s", "start_sd_s", "end_sd_s", "course_deg", "course_sd_deg", "speed_kn",
                "speed_sd_kn", "range_m", "range_sd_m")}
        state = np.array([leg.state for leg in legs], float).reshape(-1, 4)
        with np.errstate(invalid="ignore"):
            pos_sd = np.sqrt(np.array([np.diag(leg.state_cov)[:2] for leg in legs], float).reshape(-1, 2))
        return {"leg": np.arange(1, len(legs) + 1), "start_s": col["start_s"], "start_sd_s": col["start_sd_s"],
                "zig_lo_s": lo, "zig_hi_s": hi, "end_s": col["end_s"], "end_sd_s": col["end_sd_s"],
                "course_deg": col["course_deg"], "course_sd_deg": col["course_sd_deg"], "speed_kn": col["speed_kn"],
                "speed_sd_kn": col["speed_sd_kn"], "x_m": state[:, 0], "y_m": state[:, 1],
                "x_sd_m": pos_sd[:, 0], "y_sd_m": pos_sd[:, 1], "vx_mps": state[:, 2], "vy_mps": state[:, 3],
                "range_m": col["range_m"], "range_sd_m": col["range_sd_m"],
                "determined": np.array([leg.determined for leg in legs], bool),
                "reason": np.array([leg.reason for leg in legs], dtype=object),
                "current": np.arange(len(legs)) == len(legs) - 1}


def _detect(t, z, own, sigma_rad, false_alarm_per_hour: float) -> ZigReport:
    with np.errstate(all="ignore"):
        return detect_zigs(t, z, own, sigma_rad, false_alarm_per_hour=false_alarm_per_hour)


def solve_legs(record, ownship, sigma_deg: float, *, given: bool,
               false_alarm_per_hour: float = DEFAULT_FALSE_ALARM_PER_HOUR) -> LegSolution:
    """The record's zigs and legs (module doc).

    Parameters
    ----------
    record : BearingRecord
        Bearings (rad) at increasing times (s).
    ownship : OwnshipTrack
        The sensor's track (m).
    sigma_deg : float
        The bearing sd (deg): the given one, or the constant-velocity fit's residual scale (an upper bound of the
        estimate's start). Unused when the record gives each bearing's sd (``record.bearing_sd_rad``): those are
        the detector's and the legs' weights, given.
    given : bool
        The sd was given (else it is estimated from the legs' residuals, module doc).
    false_alarm_per_hour : float
        The zig detector's stated rate.

    Returns
    -------
    LegSolution
        The zigs and legs, or the reason none were fitted.
    """
    t = np.asarray(record.time_s, float)
    z = np.asarray(record.bearing_rad, float)
    own = ownship.position_at(t)
    if record.bearing_sd_rad is not None:  # each bearing's own sd: given, as the detector and fits weigh them
        ref = record.reference_sd_rad()
        try:
            report = _detect(t, z, own, np.asarray(record.bearing_sd_rad, float), false_alarm_per_hour)
        except InputError as err:
            return LegSolution(None, ref, message=str(err), per_bearing=True)
        return LegSolution(report, ref, message=report.message if report.legs is None else "", per_bearing=True)
    floor = float(np.radians(SIGMA_FLOOR_DEG))
    sigma = float(np.radians(sigma_deg))
    if not given and len(t) >= 3:
        sigma = max(min(sigma, three_point_sd(t, np.unwrap(z))), floor)
    try:
        report = _detect(t, z, own, sigma, false_alarm_per_hour)
        for _ in range(0 if given else MAX_SIGMA_PASSES - 1):
            if report.legs is None:
                break
            new = max(_sd_about(report.legs, sigma).sd_rad, floor)
            if abs(new - sigma) < 0.05 * sigma:
                break
            sigma = new
            report = _detect(t, z, own, sigma, false_alarm_per_hour)
    except InputError as err:
        return LegSolution(None, sigma, message=str(err))
    if report.legs is None:
        return LegSolution(report, sigma, message=report.message)
    return LegSolution(report, sigma, None if given else _sd_about(report.legs, sigma))


def _sd_about(fit, sigma_rad: float) -> BearingSd:
    """The bearing sd measured from a leg fit's residuals (its parameters: theta and the change times)."""
    return bearing_sd_estimate(fit.residuals * sigma_rad, n_params=len(fit.params) + len(fit.change_times_s))


def ownship_velocity(ownship, time_s: float) -> np.ndarray:
    """The ownship's velocity (m/s) at ``time_s``: the straight-line fit of its positions over the last
    :data:`VELOCITY_SPAN_S` (at least the last two fixes)."""
    t = np.asarray(ownship.time_s, float)
    idx = np.flatnonzero((t <= time_s) & (t >= time_s - VELOCITY_SPAN_S))
    if len(idx) < 2:
        k = int(np.searchsorted(t, time_s, side="right"))
        idx = np.arange(max(k - 2, 0), max(k, 2))
    tt = t[idx] - t[idx].mean()
    return np.array([tt @ np.asarray(ownship.x_m, float)[idx], tt @ np.asarray(ownship.y_m, float)[idx]]) / (tt @ tt)


def current_advice(legs: LegSolution, record, ownship):
    """tma/advice.py's next ownship leg from the current leg's solution at the last bearing, or None when the
    current leg is not determined (or its covariance admits no advice).

    Parameters
    ----------
    legs : LegSolution
        The record's legs.
    record : BearingRecord
        Its bearings (times in s).
    ownship : OwnshipTrack
        The sensor's track (m).

    Returns
    -------
    ObserverAdvice or None
        The advice.
    """
    from sonartrack.tma.advice import advise

    leg = legs.current
    if leg is None:
        return None
    t = np.asarray(record.time_s, float)
    dt = float(np.median(np.diff(t)))
    try:
        return advise(leg.state, leg.state_cov, ownship.position_at(t[-1]), ownship_velocity(ownship, t[-1]),
                      legs.sigma_rad, dt, time_s=float(t[-1]))
    except (InputError, np.linalg.LinAlgError):
        return None
