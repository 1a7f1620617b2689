"""Ownship legs from a navigation record: the spans of steady course and speed, and the turns between them.

Model: on a leg the ownship moves at constant velocity, so each position coordinate is a straight line in time,
x(t) = x0 + vx t, y(t) = y0 + vy t (and, when a heading column is given, the heading is constant); the fixes carry
white noise of sd sigma (GPS noise, quantisation). The record is cut into segments by optimal partitioning
(Jackson et al. 2005, IEEE Signal Processing Letters 12(2):105-108) with the PELT pruning rule (Killick, Fearnhead &
Eckley 2012, JASA 107(500):1590-1598), minimising

    sum over segments of  [ RSS_x / sigma^2 + RSS_y / sigma^2 + RSS_h / sigma_h^2 ]  +  beta * (number of segments)

with the BIC penalty beta = (p + 1) ln n per segment, p its parameters (4, or 5 with headings) plus its change time
(Schwarz's criterion for change points: Yao 1988, Statistics & Probability Letters 6(3):181-189). Each RSS is the
residual sum of squares of the segment's least-squares line (constant, for the heading), from cumulative sums, so a
segment's cost is O(1). sigma is estimated from the record itself: the residual of each fix from the straight line
through its two neighbours, e_k = x_k - (w x_k-1 + (1 - w) x_k+1), has variance sigma^2 (1 + w^2 + (1 - w)^2) on a
leg; its median absolute value (MAD / 0.6745) is robust to the few fixes in turns. sigma_h likewise from heading
differences. Floors keep a noise-free or quantised record from giving sigma = 0. Then the scatter of the fixes
about the legs found is measured; where it exceeds the first estimate by more than 20 % (GPS noise correlated from
fix to fix, which the neighbour residuals do not see; a heading quantised to 1 deg) the record is cut again with it.

A turn is chopped into short chords (its curvature does not fit one line), so segments shorter than
``min_leg_s`` are turn pieces, not legs; a turn is the interval between two consecutive legs. A leg's velocity is
the slope of its lines, with sd sigma / sqrt(sum (t - mean t)^2) per axis: course = atan2(vx, vy) clockwise from
north, sd = sd_v / speed (rad); speed sd = sd_v.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.units import KNOT_MPS

#: segments shorter than this (s) are pieces of a turn, not legs
MIN_LEG_S = 120.0
#: smallest position noise sd taken (m): a noise-free record must still have a finite cost per misfit metre
MIN_POSITION_SD_M = 0.3
#: smallest heading noise sd taken (deg): a heading quantised to 1 deg has sd 1 / sqrt(12) = 0.29 deg on a leg
MIN_HEADING_SD_DEG = 0.3
#: median absolute deviation of a standard normal variable
MAD_NORMAL = 0.6744897501960817


@dataclass(frozen=True, slots=True)
class OwnshipLegs:
    """The ownship's legs (steady course and speed) and the turns between them.

    Legs, one entry each: ``start_s``, ``end_s`` (first and last fix on the leg, s), ``course_deg`` (0..360,
    clockwise from north) and ``course_sd_deg``, ``speed_kn`` and ``speed_sd_kn``, ``velocity_mps`` (n, 2: vx
    east, vy north). Turns, one fewer: ``turn_start_s`` (last fix of the leg before), ``turn_end_s`` (first fix of
    the leg after) and ``turn_deg`` (course change, signed, positive to starboard, -180..180). ``position_sd_m`` and
    ``heading_sd_deg`` are the noise levels estimated from the record (NaN: no heading given).
    """

    start_s: np.ndarray
    end_s: np.ndarray
    course_deg: np.ndarray
    course_sd_deg: np.ndarray
    speed_kn: np.ndarray
    speed_sd_kn: np.ndarray
    velocity_mps: np.ndarray
    turn_start_s: np.ndarray
    turn_end_s: np.ndarray
    turn_deg: np.ndarray
    position_sd_m: float
    heading_sd_deg: float

    def leg_at(self, t_s: float) -> int | None:
        """Index (int) of the leg that holds time ``t_s`` (s); None in a turn or outside the legs."""
        inside = np.flatnonzero((self.start_s <= t_s) & (t_s <= self.end_s))
        return int(inside[0]) if len(inside) else None


def three_point_sd(time_s, values) -> float:
    """Noise sd of ``values`` about a locally straight line: MAD of each fix's residual from the line through its
    two neighbours, each scaled by its own variance factor sqrt(1 + w^2 + (1 - w)^2) (module doc).

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        Strictly increasing times (s), n >= 3.
    values : ndarray, shape (n,) or (n, m)
        The samples (columns pooled).

    Returns
    -------
    float
        The robust sd (same unit as ``values``).
    """
    t = np.asarray(time_s, float)
    v = np.asarray(values, float).reshape(len(t), -1)
    w = ((t[2:] - t[1:-1]) / (t[2:] - t[:-2]))[:, None]
    e = (v[1:-1] - (w * v[:-2] + (1.0 - w) * v[2:])) / np.sqrt(1.0 + w**2 + (1.0 - w) ** 2)
    return float(np.median(np.abs(e)) / MAD_NORMAL)


def _cumulative(t, columns) -> np.ndarray:
    """Cumulative sums (with a leading zero row) of 1, t, t^2 and, per column u, u, t u, u^2: shape (n + 1, 3 + 3m)."""
    parts = [np.ones_like(t), t, t * t]
    for u in columns:
        parts += [u, t * u, u * u]
    S = np.zeros((len(t) + 1, len(parts)))
    S[1:] = np.cumsum(np.column_stack(parts), axis=0)
    return S


def _segment_costs(S, starts, ends, n_line: int, weights) -> np.ndarray:
    """Normalised RSS of the segments [starts, ends) (fix indices into the cumulative sums ``S``): straight lines in t
    for the first ``n_line`` columns, a constant for the rest, each divided by its noise variance (``weights`` =
    1 / sigma^2 per column)."""
    d = S[ends] - S[starts]
    n, st, stt = d[..., 0], d[..., 1], d[..., 2]
    sxx = np.maximum(stt - st * st / n, 1e-300)
    cost = np.zeros(np.shape(n))
    for c, wgt in enumerate(weights):
        su, stu, suu = d[..., 3 + 3 * c], d[..., 4 + 3 * c], d[..., 5 + 3 * c]
        rss = suu - su * su / n
        if c < n_line:
            sxu = stu - st * su / n
            rss = rss - sxu * sxu / sxx
        cost += wgt * np.maximum(rss, 0.0)
    return cost


def _partition(S, grid, n_line: int, weights, penalty: float) -> np.ndarray:
    """Optimal partitioning with PELT pruning over the candidate boundaries ``grid`` (fix indices, from 0 to n):
    the boundaries chosen, as fix indices."""
    m = len(grid) - 1
    F = np.full(m + 1, np.inf)
    F[0] = -penalty
    last = np.zeros(m + 1, int)
    active = np.zeros(0, int)
    for end in range(1, m + 1):
        active = np.append(active, end - 1)
        total = F[active] + _segment_costs(S, grid[active], grid[end], n_line, weights) + penalty
        k = int(np.argmin(total))
        F[end], last[end] = total[k], active[k]
        # PELT: a start whose cost already exceeds the optimum by the penalty can never be best again
        active = active[total <= F[end] + penalty]
    bounds = [m]
    while bounds[-1] > 0:
        bounds.append(int(last[bounds[-1]]))
    return grid[np.array(bounds[::-1])]


def _refine(S, bounds, reach: int, n_line: int, weights, min_size: int) -> np.ndarray:
    """Each inner boundary moved, within ``reach`` fixes, to where its two segments cost least (the others held)."""
    b = bounds.copy()
    for k in range(1, len(b) - 1):
        cand = np.arange(max(b[k] - reach, b[k - 1] + min_size), min(b[k] + reach, b[k + 1] - min_size) + 1)
        if len(cand):
            cost = (_segment_costs(S, np.full(len(cand), b[k - 1]), cand, n_line, weights)
                    + _segment_costs(S, cand, np.full(len(cand), b[k + 1]), n_line, weights))
            b[k] = cand[int(np.argmin(cost))]
    return b


def change_points(time_s, columns, n_line: int, weights, penalty: float, min_size: int = 2,
                  max_blocks: int = 800) -> np.ndarray:
    """Optimal partition of the record into segments (module doc: optimal partitioning with PELT pruning).

    A long record is partitioned first on blocks of b = ceil(n / max_blocks) fixes (the sums are exact at block
    ends, so only the boundaries are coarse), then each boundary is moved within b fixes to its best place: PELT
    prunes little on a record without changes (its cost grows as n^2), and this keeps it near n.

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        Times (s).
    columns : list of ndarray, each shape (n,)
        The signals: the first ``n_line`` fitted by lines in t, the rest by constants.
    n_line : int
        How many columns are lines.
    weights : sequence of float
        1 / sigma^2 of each column.
    penalty : float
        Cost of one more segment.
    min_size : int
        Fewest fixes in a segment (and in a block).
    max_blocks : int
        Most blocks of the first pass.

    Returns
    -------
    ndarray of int
        Segment boundaries [0, b1, ..., n]: segment k is fixes b_k .. b_k+1 - 1.
    """
    t = np.asarray(time_s, float)
    n = len(t)
    S = _cumulative(t - t.mean(), [np.asarray(c, float) - np.mean(c) for c in columns])
    block = max(min_size, int(np.ceil(n / max_blocks)))
    grid = np.unique(np.r_[np.arange(0, n - block + 1, block), n])
    bounds = _partition(S, grid, n_line, weights, penalty)
    return _refine(S, bounds, block, n_line, weights, min_size) if block > 1 else bounds


def _line_velocity(t, x, y):
    """Least-squares slopes (vx, vy) (m/s) of x(t), y(t) and sum (t - mean t)^2 (s^2)."""
    tc = t - t.mean()
    sxx = float(tc @ tc)
    return float(tc @ (x - x.mean()) / sxx), float(tc @ (y - y.mean()) / sxx), sxx


def ownship_legs(time_s, x_m, y_m, heading_deg=None, *, min_leg_s: float = MIN_LEG_S,
                 position_sd_m: float | None = None) -> OwnshipLegs:
    """The ownship's legs and turns in a navigation record (module doc).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Fix times (s), strictly increasing, n >= 3.
    x_m, y_m : array_like, shape (n,)
        Positions (m; x east, y north).
    heading_deg : array_like, shape (n,), optional
        Headings (deg, clockwise from north; unwrapped here), a second witness of the turns.
    min_leg_s : float
        Shortest leg (s); shorter segments are turn pieces.
    position_sd_m : float, optional
        Position noise sd (m); by default estimated from the record (:func:`three_point_sd`).

    Returns
    -------
    OwnshipLegs
        Legs with courses and speeds (and their sds), turns, and the noise levels used.
    """
    t, x, y = (np.asarray(a, float) for a in (time_s, x_m, y_m))
    require(t.ndim == 1 and len(t) == len(x) == len(y), "navigation times and positions must have the same length")
    require(len(t) >= 3, f"ownship legs need at least 3 fixes, got {len(t)}")
    require(bool(np.all(np.isfinite(t)) and np.all(np.isfinite(x)) and np.all(np.isfinite(y))),
            "navigation times and positions must be finite numbers")
    require(bool(np.all(np.diff(t) > 0)), "navigation times must increase strictly: sort the record, drop duplicates")
    sigma = position_sd_m if position_sd_m is not None else three_point_sd(t, np.column_stack([x, y]))
    sigmas = [max(float(sigma), MIN_POSITION_SD_M)]
    columns = [x, y]
    if heading_deg is not None:
        h = np.unwrap(np.asarray(heading_deg, float), period=360.0)
        require(len(h) == len(t) and bool(np.all(np.isfinite(h))), "headings must be finite, one per fix")
        sigmas.append(max(float(np.median(np.abs(np.diff(h))) / MAD_NORMAL / np.sqrt(2.0)), MIN_HEADING_SD_DEG))
        columns.append(h)
    penalty = (2 * 2 + len(sigmas) - 1 + 1) * np.log(len(t))
    for _ in range(2):
        weights = [sigmas[0] ** -2, sigmas[0] ** -2] + [sd**-2 for sd in sigmas[1:]]
        bounds = change_points(t, columns, 2, weights, penalty)
        # the fixes' scatter about the legs found: larger than the neighbour-based estimate when the noise is
        # correlated from fix to fix (GPS) or the heading quantised, and then the one to cut with
        on_legs = _leg_residual_sds(t, columns, bounds, min_leg_s)
        if position_sd_m is not None:
            on_legs[0] = sigmas[0]
        if all(r <= 1.2 * sd for r, sd in zip(on_legs, sigmas, strict=True)):
            break
        sigmas = [max(r, sd) for r, sd in zip(on_legs, sigmas, strict=True)]
    return _legs_from_bounds(t, x, y, bounds, min_leg_s, sigmas[0], sigmas[1] if len(sigmas) > 1 else float("nan"))


def _leg_residual_sds(t, columns, bounds, min_leg_s: float) -> list[float]:
    """Residual sds about the segments at least ``min_leg_s`` long: position (x and y lines pooled), then heading
    (constant); 0 where no segment is that long."""
    rss, dof = np.zeros(len(columns)), np.zeros(len(columns))
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if t[b - 1] - t[a] < min_leg_s or b - a < 3:
            continue
        A = np.column_stack([np.ones(b - a), t[a:b] - t[a]])
        for c, u in enumerate(columns):
            fit = A @ np.linalg.lstsq(A, u[a:b], rcond=None)[0] if c < 2 else np.mean(u[a:b])
            rss[c] += float(np.sum((u[a:b] - fit) ** 2))
            dof[c] += b - a - (2 if c < 2 else 1)
    sd = np.sqrt(rss / np.maximum(dof, 1))
    return [float(np.sqrt((rss[0] + rss[1]) / max(dof[0] + dof[1], 1)))] + [float(v) for v in sd[2:]]


def _legs_from_bounds(t, x, y, bounds, min_leg_s: float, sigma: float, sigma_h: float) -> OwnshipLegs:
    """The segments at least ``min_leg_s`` long as legs (velocity by least squares), the gaps between them as turns."""
    rows = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if t[b - 1] - t[a] >= min_leg_s:
            vx, vy, sxx = _line_velocity(t[a:b], x[a:b], y[a:b])
            rows.append((t[a], t[b - 1], vx, vy, sigma / np.sqrt(sxx)))
    arr = np.array(rows, float).reshape(-1, 5)
    start, end, v, sd_v = arr[:, 0], arr[:, 1], arr[:, 2:4], arr[:, 4]
    speed = np.hypot(v[:, 0], v[:, 1])
    course = np.degrees(np.arctan2(v[:, 0], v[:, 1])) % 360.0
    with np.errstate(divide="ignore", invalid="ignore"):
        course_sd = np.minimum(np.degrees(sd_v / speed), 180.0)
    turn = (np.diff(course) + 180.0) % 360.0 - 180.0
    return OwnshipLegs(start_s=start, end_s=end, course_deg=course, course_sd_deg=np.nan_to_num(course_sd, nan=180.0),
                       speed_kn=speed / KNOT_MPS, speed_sd_kn=sd_v / KNOT_MPS, velocity_mps=v,
                       turn_start_s=end[:-1], turn_end_s=start[1:], turn_deg=turn, position_sd_m=sigma,
                       heading_sd_deg=sigma_h)
