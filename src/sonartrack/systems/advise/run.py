"""The advise system's run function: the targets now and the ownship's navigation in, the next leg out.

:func:`run_advice` finds the ownship's legs in its navigation (tma/observer_legs.py), takes its position now and
its velocity (the current leg's, or the last minute's when it is turning), brings every target to the same time by
constant-velocity prediction (X <- F X, P <- F P F^T), and asks tma/advice.py for the leg of least predicted
range sd at the horizon. A target from a bearings file is the constant-velocity batch ML of tma/batch_ml.py
(:func:`target_from_bearings`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.models.motion import cv_transition
from sonartrack.tma.advice import ObserverAdvice, advise
from sonartrack.tma.observer_legs import OwnshipLegs, ownship_legs
from sonartrack.tma.records import BearingRecord, OwnshipTrack, check_coverage

from .settings import AdviceSettings

#: when the ownship is not on a leg now, its velocity is the straight-line fit over this last span (s)
TURNING_VELOCITY_SPAN_S = 60.0


@dataclass(frozen=True, slots=True)
class TargetNow:
    """One target's solution at one time: state [x, y, vx, vy] (m, m/s) and covariance, and where it came from."""

    name: str
    time_s: float
    state: np.ndarray
    covariance: np.ndarray

    def at(self, time_s: float) -> TargetNow:
        """The solution predicted to ``time_s`` at constant velocity (X <- F X, P <- F P F^T).

        Parameters
        ----------
        time_s : float
            Time (s).

        Returns
        -------
        TargetNow
            The predicted solution.
        """
        F = cv_transition(float(time_s) - self.time_s)
        return TargetNow(self.name, float(time_s), F @ self.state, F @ self.covariance @ F.T)


@dataclass(frozen=True, slots=True)
class AdviceResult:
    """What :func:`run_advice` returns: the advice, the ownship's legs and track, the targets at the advice's time,
    and warnings (one line each)."""

    advice: ObserverAdvice
    legs: OwnshipLegs
    ownship: OwnshipTrack
    targets: tuple[TargetNow, ...]
    warnings: tuple[str, ...]


def target_from_bearings(record: BearingRecord, ownship: OwnshipTrack, sigma_rad: float, name: str) -> TargetNow:
    """The constant-velocity batch ML solution of a bearings record at its last bearing (tma/batch_ml.py).

    Parameters
    ----------
    record : BearingRecord
        Bearings (rad) and times (s).
    ownship : OwnshipTrack
        The sensor's positions covering the record.
    sigma_rad : float
        Bearing sd (rad).
    name : str
        The target's name (the file), for messages.

    Returns
    -------
    TargetNow
        State and covariance at the last bearing time. Raises InputError when the range is not determined.
    """
    from sonartrack.tma.batch_ml import ml_bearings_only

    check_coverage(record, ownship)
    t = np.asarray(record.time_s, float)
    try:
        est = ml_bearings_only(record.bearing_rad, t, ownship.position_at(t), sigma_rad)
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None
    X, P = est.state_at(t[-1])
    determined = bool(np.all(np.isfinite(P[0]))) and float(np.linalg.eigvalsh(0.5 * (P[0] + P[0].T))[0]) > 0.0
    require(est.converged and determined,
            f"{name}: the constant-velocity batch ML did not converge to a determined range: no advice can rest on "
            "it; give a solution file (--solution) of sonartrack tma instead")
    return TargetNow(name, float(t[-1]), X[0], P[0])


def ownship_now(ownship: OwnshipTrack, legs: OwnshipLegs, time_s: float) -> tuple[np.ndarray, np.ndarray, str | None]:
    """The ownship's position (interpolated) and velocity at ``time_s``: its leg's, or when it is turning (on no leg)
    the straight-line fit over the last :data:`TURNING_VELOCITY_SPAN_S`, with a warning.

    Parameters
    ----------
    ownship : OwnshipTrack
        Navigation (s, m).
    legs : OwnshipLegs
        Its legs.
    time_s : float
        Now (s), within the navigation's span.

    Returns
    -------
    xy : ndarray (2,)
        Position (m).
    velocity : ndarray (2,)
        Velocity (m/s).
    warning : str or None
        Set when the velocity is the last minute's.
    """
    t = np.asarray(ownship.time_s, float)
    require(t[0] <= time_s <= t[-1], f"the ownship file spans {t[0]:g}..{t[-1]:g} s but the targets' time is "
                                     f"{time_s:g} s: give navigation up to the targets' last time")
    xy = ownship.position_at(time_s)
    leg = legs.leg_at(time_s)
    if leg is not None:
        return xy, np.asarray(legs.velocity_mps[leg], float), None
    k = int(np.searchsorted(t, time_s, side="right"))  # fixes at or before now
    idx = np.flatnonzero((t <= time_s) & (t >= time_s - TURNING_VELOCITY_SPAN_S))
    if len(idx) < 2:
        idx = np.arange(max(k - 2, 0), max(k, 2))
    tt = t[idx] - t[idx].mean()
    v = np.array([tt @ np.asarray(ownship.x_m)[idx], tt @ np.asarray(ownship.y_m)[idx]]) / (tt @ tt)
    return xy, v, (f"the ownship is not on a steady leg at t = {time_s:g} s (turning): its velocity is taken from the "
                   f"last {t[idx[-1]] - t[idx[0]]:.0f} s of navigation")


def run_advice(targets: list[TargetNow], ownship: OwnshipTrack, settings: AdviceSettings | None = None, *,
               interval_s: float | None = None) -> AdviceResult:
    """Advise the next ownship leg for ``targets`` (module doc).

    Parameters
    ----------
    targets : list of TargetNow
        The targets' solutions (any times; brought to the latest).
    ownship : OwnshipTrack
        The ownship's navigation up to at least that time.
    settings : AdviceSettings, optional
        Candidate grid, bearing sd and interval, objective, shortest leg.
    interval_s : float, optional
        The bearing interval when the settings give none (e.g. the bearings files'); default 30 s.

    Returns
    -------
    AdviceResult
        The advice, the ownship's legs, the targets at the advice's time, warnings.
    """
    s = AdviceSettings() if settings is None else settings
    require(len(targets) >= 1, "give at least one target: --solution FILE or --bearings FILE")
    now = max(tg.time_s for tg in targets)
    targets = tuple(tg.at(now) for tg in targets)
    legs = ownship_legs(ownship.time_s, ownship.x_m, ownship.y_m, min_leg_s=s.min_leg_s)
    xy, v, note = ownship_now(ownship, legs, now)
    require(np.hypot(*v) > 0.1, f"the ownship is (nearly) stopped at t = {now:g} s ({np.hypot(*v):.2f} m/s): the "
                                "candidate legs keep its speed, so none would move it; advise needs a moving ownship")
    dt = s.interval_s if s.interval_s is not None else (interval_s if interval_s is not None else 30.0)
    require(dt < s.horizon_s, f"the bearing interval {dt:g} s is not shorter than the horizon {s.horizon_s:g} s")
    require(max(s.turn_delays_s) < s.horizon_s, f"every turn time must come before the horizon ({s.horizon_s:g} s)")
    adv = advise(np.array([tg.state for tg in targets]), np.array([tg.covariance for tg in targets]), xy, v,
                 np.radians(s.sigma_bearing_deg), dt, time_s=now, horizon_s=s.horizon_s,
                 turn_delays_s=s.turn_delays_s, course_step_deg=s.course_step_deg, objective=s.objective)
    return AdviceResult(adv, legs, ownship, targets, tuple(w for w in (note,) if w))
