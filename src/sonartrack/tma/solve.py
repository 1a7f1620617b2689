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
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution, check_coverage
from sonartrack.tma.settings import BATCH_METHODS, SEQUENTIAL_METHODS, TmaSettings


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

    def summary(self) -> str:
        """One line: the record, and the target's range, bearing, course and speed at the last time."""
        from sonartrack.tma.solution_table import solution_columns

        cols = solution_columns(self.solution, self.ownship)
        i, s, t = len(cols["time_s"]) - 1, self.settings, self.record.time_s
        what = "bearings + frequencies" if s.frequency else "bearings"
        line = f"tma {s.method}: {len(t)} {what} over {t[0]:g}..{t[-1]:g} s; at {cols['time_s'][i]:g} s the target "
        if not cols["range_determined"][i]:
            return line + (f"is at bearing {cols['bearing_deg'][i]:.1f} ± {cols['bearing_std_deg'][i]:.1f} deg; "
                           "range, course and speed NOT DETERMINED by this record (see the warning)")
        line += (f"is at range {cols['range_m'][i] / 1e3:.2f} ± {cols['range_std_m'][i] / 1e3:.2f} km, bearing "
                 f"{cols['bearing_deg'][i]:.1f} ± {cols['bearing_std_deg'][i]:.1f} deg, course "
                 f"{cols['course_deg'][i]:.0f} ± {cols['course_std_deg'][i]:.0f} deg, speed {cols['speed_kn'][i]:.1f} "
                 f"± {cols['speed_std_kn'][i]:.1f} kn")
        if self.f0_hz is not None:
            line += f", f0 {self.f0_hz:.2f} ± {self.f0_std_hz:.2f} Hz"
        if self.mode_probabilities is not None:
            line += ", mode probabilities " + "/".join(f"{m:.2f}" for m in self.mode_probabilities)
        if not s.is_sequential and s.batch.window_s is not None:
            line += f", batch on the first {s.batch.window_s:g} s then a sequential EKF"
        return line


def check_settings(settings: TmaSettings) -> None:
    """Refuse settings that belong to the other family of methods (a sign of a mistaken method)."""
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
    out: dict = {"solution": solution}
    if settings.frequency:
        out["f0_hz"] = float(track.rel_state[-1, 4])
        out["f0_std_hz"] = float(np.sqrt(track.rel_cov[-1, 4, 4]))
    if settings.method.startswith("imm"):
        out["mode_probabilities"] = tuple(float(m) for m in track.mode_prob[-1])
    return out


def flag_unresolved_range(solution: TmaSolution, record, ownship, sigma_bearing_rad: float) -> TmaSolution:
    """Bearings-only ML: flag the rows whose range lies beyond what the record can resolve
    (:func:`~sonartrack.tma.batch_ml.observable_range_limit_m`), whose range standard deviation exceeds the range
    itself (the one-sigma interval reaches the ownship), or whose covariance is not finite, and warn.
    The numbers stay in the table (the bearing is still good); the flag column says the range is not."""
    from dataclasses import replace

    from sonartrack.tma.batch_ml import observable_range_limit_m
    from sonartrack.tma.solution_table import solution_columns

    t = np.asarray(record.time_s, float)
    limit_m = observable_range_limit_m(t - t[0], ownship.position_at(t), sigma_bearing_rad)
    cols = solution_columns(solution, ownship)
    range_m, range_std_m = cols["range_m"], cols["range_std_m"]
    P = np.asarray(solution.covariance, float)
    bad_cov = ~np.all(np.isfinite(P), axis=(1, 2)) | (np.einsum("nii->n", P[:, :2, :2]) <= 0)
    with np.errstate(invalid="ignore"):
        ok = (range_m <= limit_m) & (range_std_m < range_m) & ~bad_cov
    if not ok.all():
        from sonartrack.tma.batch import UnobservableWarning

        i = int(np.argmin(ok))
        warnings.warn(f"range not determined: the bearings-only solution puts the target at {range_m[i] / 1e3:.3g} "
                      f"± {range_std_m[i] / 1e3:.3g} km at {cols['time_s'][i]:g} s, and this record's ownship maneuver "
                      f"resolves range only to {limit_m / 1e3:.3g} km; trust the bearing, not the range (flag column "
                      "range_determined), or use a record with a larger maneuver or em-map with SNR",
                      UnobservableWarning, stacklevel=2)
    return replace(solution, range_determined=solution.range_flags() & ok)


def _solve_batch(record, ownship, settings: TmaSettings, environment, tl_store) -> dict:
    from sonartrack.tma.batch import solve_batch, solve_batch_then_ekf

    kw = dict(sigma_bearing_rad=float(np.deg2rad(settings.sigma_bearing_deg)), batch=settings.batch,
              em_map=settings.em_map, environment=environment, tl_store=tl_store)
    if settings.batch.window_s is None:
        solution = solve_batch(record, ownship, settings.method, **kw)
    else:
        solution = solve_batch_then_ekf(record, ownship, settings.method, window_s=settings.batch.window_s, **kw)
    if settings.method == "ml":  # em-map resolves range from the SNR, not from the maneuver
        solution = flag_unresolved_range(solution, record, ownship, kw["sigma_bearing_rad"])
    return {"solution": solution}


def solve_tma(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings | None = None, *,
              environment=None, tl_store=None) -> TmaResult:
    """Solve a bearings (+ frequency, SNR) record for the target's track (module docstring).

    ``ownship`` must cover the record (no extrapolation, gaps up to ``settings.inputs.max_nav_gap_s``).
    For em-map, ``environment`` (an :class:`~sonartrack.acoustics.environment.Environment`) overrides
    ``settings.batch.env`` (a shipped environment's name), and ``tl_store`` caches the TL fields. Solver
    warnings are collected in ``result.warnings``. Mistakes raise :class:`~sonartrack.core.errors.InputError`.
    """
    settings = TmaSettings() if settings is None else settings
    check_settings(settings)
    check_coverage(record, ownship, settings.inputs.max_nav_gap_s)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if settings.is_sequential:
            parts = _solve_sequential(record, ownship, settings)
        else:
            parts = _solve_batch(record, ownship, settings, environment, tl_store)
    return TmaResult(record=record, ownship=ownship, settings=settings,
                     warnings=tuple(str(w.message) for w in caught), **parts)
