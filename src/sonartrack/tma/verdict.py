"""Whether a solution's range is determined, row by row, and why not: the verdict every TMA method carries.

A range is printed only when its row is determined; otherwise the row says why (column
``undetermined_reason`` of the solution table, tma/solution_table.py). A sequential filter's reasons, in the
order they are checked (the first that applies is given; :func:`sequential_reasons`):

* :data:`DIVERGED` -- the estimate is not a target: not finite, a covariance that is not positive definite, a
  range or speed beyond a physical bound (``verdict.max_range_m``, ``verdict.max_speed_mps``), or a range
  standard deviation above ``verdict.max_range_sd_fraction`` of the range;
* :data:`INCONSISTENT` -- the filter's normalised innovations are larger than its stated covariances allow: the
  running sum of the last ``verdict.nis_window`` NIS values (tma/imm_mgekf.py :func:`combined_nis`) above the
  upper limit of its chi-square interval at ``verdict.alpha`` (Bar-Shalom, Li & Kirubarajan 2001, sec. 5.4.2:
  the time-average NIS test, a window instead of the whole record so that a filter that diverges later is
  caught from then on). Only the upper tail: a sum below the lower limit says the stated noise is larger than
  the errors (noise-free bearings with a nominal 1 deg), which leaves the estimate right and its interval wider
  than need be, not a range to withhold. Checked before observability, which is judged from the covariance an
  inconsistent filter gets wrong;
* :data:`UNOBSERVABLE` -- a sequential filter whose range standard deviation has not fallen below
  ``verdict.prior_shrink`` times the prior's: without an ownship maneuver the bearings do not observe range
  (Nardone & Aidala, IEEE Trans. AES 17(2), 1981), and the filter's range is its initial guess.

A line array's target whose side of the array is not decided (its bearings may be the mirror ones) adds
:data:`SIDE_UNRESOLVED` to the rows that have no reason yet (systems/passive/targets.py). The batch methods give their
own: the ML (tma/solve.py :func:`~sonartrack.tma.solve.flag_unresolved_range`) :data:`DIVERGED` (a covariance that is
not finite) and :data:`UNOBSERVABLE` (no maneuver, a range beyond what the maneuver resolves, or a range sd above the
range), the passive chain's check of it (systems/passive/targets.py) :data:`INCONSISTENT_RESIDUALS`,
:data:`FLAT_LIKELIHOOD`, :data:`NOT_ONE_TARGET` (a stretch of the record that the rest of it places more than a
beamwidth away: another ship's bearings, or the mirror's) and :data:`FIXED_CONE` (bearings that one cone angle fixed
in the array's frame explains as well as the CV target does); em-map :data:`SNR_NOT_EXPLAINED` (tma/em_snr_check.py
:func:`~sonartrack.tma.em_snr_check.snr_residual_check`). The passive chain holds its sequential filter to the batch
ML of the same record (systems/passive/targets.py :func:`batch_held`): the ML's reason where the ML is not determined,
else :data:`DISAGREES_WITH_BATCH` when the two final positions differ beyond what their covariances allow.
``sonartrack tma`` (tma/solve.py :func:`~sonartrack.tma.solve.solve_tma`) judges every method's answer by its record
(tma/motion_verdict.py): :data:`MANOEUVRED` on every row when the bearings reject constant velocity, else the ML's
residual and profile-likelihood checks and, for a sequential filter on bearings, the batch ML's hold, as in the
passive chain.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.core.gaussian import chi2_quantile
from sonartrack.tma.records import OwnshipTrack, TmaSolution
from sonartrack.tma.settings import VerdictSettings

DIVERGED = "diverged"
SIDE_UNRESOLVED = "side unresolved"
UNOBSERVABLE = "unobservable"
INCONSISTENT = "inconsistent innovations"
SNR_NOT_EXPLAINED = "SNR not explained by the propagation model"
INCONSISTENT_RESIDUALS = "inconsistent residuals"
FLAT_LIKELIHOOD = "flat likelihood"
NOT_ONE_TARGET = "bearings of more than one target"
DISAGREES_WITH_BATCH = "disagrees with the batch ML"
FIXED_CONE = "cone angle fixed to the array: own-ship or array noise, range unobservable"
#: the record rejects the constant-velocity motion every method assumes (tma/motion_verdict.py); the reason goes on
#: with the test and the span its residuals point at: "target manoeuvred: residuals reject constant velocity,
#: largest 300-720 s"
MANOEUVRED = "target manoeuvred"
EXCEEDS_STATED_NOISE = "residuals exceed the stated noise"


def with_reasons(solution: TmaSolution, reasons) -> TmaSolution:
    """``solution`` with the rows that have a reason made undetermined; a row already undetermined keeps its own.

    Parameters
    ----------
    solution : TmaSolution
        A solution (rows possibly already undetermined).
    reasons : array_like of str (n,)
        A reason per row, "" where this check finds nothing.

    Returns
    -------
    TmaSolution
        ``range_determined`` False and ``undetermined_reason`` set where a reason is given.
    """
    new = np.asarray(reasons, dtype=object)
    old = solution.reasons()
    merged = np.where(old != "", old, new).astype(object)
    return replace(solution, range_determined=merged == "", undetermined_reason=merged)


def diverged_rows(solution: TmaSolution, ownship: OwnshipTrack, verdict: VerdictSettings) -> np.ndarray:
    """Rows whose estimate is not a target (module docstring, :data:`DIVERGED`).

    Parameters
    ----------
    solution : TmaSolution
        States [x, y, vx, vy] (m, m/s) and 4 x 4 covariances.
    ownship : OwnshipTrack
        The sensor's track (m).
    verdict : VerdictSettings
        The bounds.

    Returns
    -------
    ndarray of bool (n,)
        True where the row diverged.
    """
    X, P = np.asarray(solution.state, float), np.asarray(solution.covariance, float)
    finite = np.all(np.isfinite(X), axis=1) & np.all(np.isfinite(P), axis=(1, 2))
    d = X[:, :2] - ownship.position_at(solution.time_s)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        r = np.hypot(d[:, 0], d[:, 1])
        speed = np.hypot(X[:, 2], X[:, 3])
        u = d / np.where(r > 0, r, np.nan)[:, None]
        range_sd = np.sqrt(np.einsum("ni,nij,nj->n", u, P[:, :2, :2], u))
        sym = 0.5 * (P + np.swapaxes(P, 1, 2))
        pd = np.zeros(len(X), bool)
        pd[finite] = np.linalg.eigvalsh(sym[finite])[:, 0] > 0
        ok = finite & pd & (r <= verdict.max_range_m) & (speed <= verdict.max_speed_mps) & \
            (range_sd <= verdict.max_range_sd_fraction * r)
    return ~ok


def range_sd_m(solution: TmaSolution, ownship: OwnshipTrack) -> np.ndarray:
    """The range standard deviation sqrt(u^T P_pos u), u the unit vector from the ownship to the estimate.

    Parameters
    ----------
    solution, ownship : TmaSolution, OwnshipTrack
        The states [x, y, vx, vy] (m, m/s) with 4 x 4 covariances, and the sensor's track (m).

    Returns
    -------
    ndarray (n,)
        The first-order range standard deviation of each row (m; NaN where the estimate is not finite).
    """
    X, P = np.asarray(solution.state, float), np.asarray(solution.covariance, float)
    d = X[:, :2] - ownship.position_at(solution.time_s)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        u = d / np.hypot(d[:, 0], d[:, 1])[:, None]
        return np.sqrt(np.abs(np.einsum("ni,nij,nj->n", u, P[:, :2, :2], u)))


def running_nis_outside(nis, dof, window: int, alpha: float) -> np.ndarray:
    """Rows whose running NIS lies above its chi-square interval (module docstring, :data:`INCONSISTENT`).

    With eps_i the NIS and m_i its degrees of freedom, the sum over the last ``window`` measurements up to row k,
    sum eps_i, is chi-square with sum m_i degrees of freedom for a consistent filter; the row is inconsistent
    when the sum lies above the 1 - alpha / 2 quantile (the upper end of the two-sided interval).

    Parameters
    ----------
    nis : array_like (n,)
        NIS per row (NaN: none).
    dof : array_like of int (n,)
        Its degrees of freedom (0: none).
    window : int
        Measurements in the running sum.
    alpha : float
        Two-sided significance.

    Returns
    -------
    ndarray of bool (n,)
        True where the running sum is above the interval (False where no innovation has been seen yet).
    """

    e = np.nan_to_num(np.asarray(nis, float), nan=0.0)
    m = np.asarray(dof, int)
    ce, cm = np.concatenate([[0.0], np.cumsum(e)]), np.concatenate([[0], np.cumsum(m)])
    k = np.arange(1, len(e) + 1)
    lo_i = np.maximum(k - window, 0)
    s, n_dof = ce[k] - ce[lo_i], cm[k] - cm[lo_i]
    out = np.zeros(len(e), bool)
    has = n_dof > 0
    out[has] = s[has] > chi2_quantile(1 - alpha / 2, n_dof[has])
    return out


def sequential_reasons(solution: TmaSolution, ownship: OwnshipTrack, nis, dof, prior_range_sd_m: float,
                       verdict: VerdictSettings) -> np.ndarray:
    """The verdict of a sequential filter's rows (module docstring): the first reason that applies, or "".

    Parameters
    ----------
    solution : TmaSolution
        The filter's absolute solution.
    ownship : OwnshipTrack
        The sensor's track (m).
    nis, dof : array_like (n,)
        The filter's NIS and their degrees of freedom (tma/imm_mgekf.py :func:`combined_nis`).
    prior_range_sd_m : float
        The standard deviation of the initial range guess (m).
    verdict : VerdictSettings
        The thresholds.

    Returns
    -------
    ndarray of str (n,)
        :data:`DIVERGED`, :data:`INCONSISTENT`, :data:`UNOBSERVABLE` or "" per row.
    """
    diverged = diverged_rows(solution, ownship, verdict)
    with np.errstate(invalid="ignore"):
        unobserved = ~(range_sd_m(solution, ownship) < verdict.prior_shrink * prior_range_sd_m)
    inconsistent = running_nis_outside(nis, dof, verdict.nis_window, verdict.alpha)
    return np.select([diverged, inconsistent, unobserved], [DIVERGED, INCONSISTENT, UNOBSERVABLE], "").astype(object)


def not_determined_text(reason: str) -> str:
    """What is printed instead of a range: "range NOT DETERMINED (reason)", from the row's ``reason`` (str)."""
    return f"range NOT DETERMINED ({reason or 'not determined'})"


#: a bearing whose standard deviation reaches this (deg) says nothing of the direction: a uniform bearing has sd
#: 180 / sqrt(3) = 104 deg, so at 90 deg the 1-sigma interval already spans half the circle
MAX_BEARING_SD_DEG = 90.0


def bearing_text(bearing_deg: float, bearing_sd_deg: float) -> str:
    """What is printed for a bearing: "bearing B ± S deg", or "bearing NOT DETERMINED" when the estimate or its
    sd is not finite or the sd reaches :data:`MAX_BEARING_SD_DEG` (a number there would be confident noise);
    ``bearing_deg`` and ``bearing_sd_deg`` are the bearing and its standard deviation (deg).
    """
    if not (np.isfinite(bearing_deg) and np.isfinite(bearing_sd_deg)) or bearing_sd_deg >= MAX_BEARING_SD_DEG:
        return "bearing NOT DETERMINED"
    return f"bearing {bearing_deg:.1f} ± {bearing_sd_deg:.1f} deg"
