"""Left/right (port/starboard) ambiguity of a line array: cone angle -> the two mirror true bearings, and the
side decided by which of them a constant-velocity target explains (the passive chain's side decision).

A line array measures only the cone angle theta in [0, pi] between its forward axis and the arrival
direction; the true bearing (clockwise from north) is one of the two mirror images about the axis

    b_starboard = h + theta,    b_port = h - theta        (h: the array's axis heading)

(the convention of sim/passive_scene.py: side = starboard where sin(b - h) >= 0).

While the array moves straight along its own axis the two hypotheses explain the cone angles equally
well: the reflection of a constant-velocity (CV) target about the array's straight track is again a CV
target, with the mirrored bearings. After a turn of the array the reflection axis has changed, so only
the true side's bearings stay consistent with one CV track. We fit a CV target to each hypothesis by the
bearings-only maximum likelihood of tma/batch_ml.py (Gauss-Newton / Levenberg-Marquardt, paper P3
eqs. 15-18) and compare the maximised Gaussian likelihoods (a generalised likelihood ratio; both
hypotheses have the same 4 parameters, so no dimension penalty):

    J_side = min over X0 of sum_n wrap(b_side,n - h_n(X0))^2         (rad^2)
    ln LR  = ln L_starboard - ln L_port = -(J_starboard - J_port) / (2 sigma^2)

sigma (the bearing noise) is given, or measured from the better fit's residuals, the unbiased estimate
of a 4-parameter least-squares fit, sigma^2 = min(J_s, J_p) / (n - 4), floored at ``sigma_floor_rad``
(a floor keeps noise-free or quantised bearings from giving an infinite ratio out of model mismatch).
The side is decided when |ln LR| >= ``min_log_lr`` (default ln 100, a 100:1 likelihood ratio).

The ML cost of the wrong side after a turn is not convex and the right side's cost is flat in range
before the turn, so each side is fitted from several starts (the pseudo-linear estimate and, for each
of a few initial ranges R, the track from range R on the first bearing to range R on the last bearing),
keeping the lowest cost.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.angles import heading_unit, wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, ml_bearings_only

#: fewest bearings for a side decision: 4 CV parameters plus at least 2 degrees of freedom for sigma
MIN_BEARINGS = 6
#: initial ranges (m) of the multi-start CV fits (module doc)
INITIAL_RANGES_M = (2_000.0, 5_000.0, 10_000.0, 20_000.0)
#: smallest bearing noise (rad) the measured sigma may take (0.1 deg, module doc)
SIGMA_FLOOR_RAD = float(np.deg2rad(0.1))


@dataclass(frozen=True)
class SideDecision:
    """Which side of the array a track's target is on, with the evidence.

    ``side``: "starboard", "port" or "unresolved"; ``log_likelihood_ratio``: ln L_starboard - ln L_port
    at each side's ML CV fit (0 when no decision could be computed); ``sigma_bearing_rad``: the bearing noise
    used (given, or measured from the better fit); ``starboard`` / ``port``: the ML fits (covariances
    scaled by sigma^2), None where a fit failed; ``note``: why the side is unresolved ("" otherwise)."""

    side: str
    log_likelihood_ratio: float
    sigma_bearing_rad: float
    starboard: BatchEstimate | None
    port: BatchEstimate | None
    note: str = ""
    #: times (s) at which the target crossed the array's axis (endfire; the side changes there), in order
    crossings_s: tuple[float, ...] = ()
    #: the unfolded cone angles (rad) the decision was taken on (through the crossings), or None (plain cone angles)
    unfolded_rad: np.ndarray | None = None

    def side_at(self, time_s) -> np.ndarray:
        """The side at each of ``time_s`` (s): ``side`` (the side at the record's start) before the first axis
        crossing, the other side after it, and so on; "unresolved" everywhere when unresolved.

        Parameters
        ----------
        time_s : float or array
            Times (s).

        Returns
        -------
        numpy.ndarray
            Object array of "starboard" / "port" / "unresolved", shaped as ``time_s``.
        """
        t = np.asarray(time_s, float)
        if self.side == "unresolved":
            return np.full(t.shape, "unresolved", dtype=object)
        flips = np.searchsorted(np.asarray(self.crossings_s, float), t, side="right") % 2
        other = "port" if self.side == "starboard" else "starboard"
        return np.where(flips == 0, self.side, other).astype(object)

    @property
    def final_side(self) -> str:
        """The side after the last axis crossing (``side`` when there was none)."""
        if self.side == "unresolved" or len(self.crossings_s) % 2 == 0:
            return self.side
        return "port" if self.side == "starboard" else "starboard"


def mirror_bearings_rad(cone_rad, array_heading_rad) -> tuple[np.ndarray, np.ndarray]:
    """The two true bearings (rad, clockwise from north, wrapped to (-pi, pi]) of cone angles ``cone_rad``
    (0..pi from the array's forward axis) for an array whose axis heads ``array_heading_rad``:
    (starboard = h + theta, port = h - theta).

    Parameters
    ----------
    cone_rad : float or array (n,)
        Cone angles theta from the array's forward axis (rad, 0 = ahead).
    array_heading_rad : float or array (n,)
        Heading h of the array's forward axis (rad, clockwise from north).

    Returns
    -------
    starboard, port : numpy.ndarray
        (n,) true bearings (rad, clockwise from north, in (-pi, pi]).
    """
    theta = np.asarray(cone_rad, dtype=float)
    h = np.asarray(array_heading_rad, dtype=float)
    return wrap_angle(h + theta), wrap_angle(h - theta)


def _starts(z_rad, time_s, sensor_xy, initial_ranges_m) -> list[np.ndarray | None]:
    """Initial X0s: None (the pseudo-linear estimate) and, per range R, the CV track from range R on the first
    bearing line to range R on the last one."""
    u = heading_unit(np.array([z_rad[0], z_rad[-1]]))
    span_s = float(time_s[-1] - time_s[0])
    starts: list[np.ndarray | None] = [None]
    for r in initial_ranges_m:
        p0, p1 = sensor_xy[0] + r * u[0], sensor_xy[-1] + r * u[1]
        starts.append(np.concatenate([p0, (p1 - p0) / span_s]))
    return starts


def fit_cv_target(z_rad, time_s, sensor_xy, initial_ranges_m=INITIAL_RANGES_M, relative_sigma=1.0
                  ) -> BatchEstimate | None:
    """The lowest-cost bearings-only ML CV fit over the starts of :func:`_starts` (objective = sum of squared
    wrapped residuals, rad^2; covariance for unit noise), or None if every start fails.

    Parameters
    ----------
    z_rad : array (n,)
        True bearings (rad, clockwise from north).
    time_s : array (n,)
        Times (s), increasing.
    sensor_xy : array (n, 2)
        Sensor positions [x east, y north] (m).
    initial_ranges_m : sequence of float
        Ranges (m) of the multi-start tracks (module doc).
    relative_sigma : float or array (n,)
        Each bearing's noise relative to the others (1: equal weights).

    Returns
    -------
    BatchEstimate or None
        The best fit (state [x, y, vx, vy] at the first time, m and m/s), or None.
    """
    best = None
    for x_init in _starts(z_rad, time_s, sensor_xy, initial_ranges_m):
        try:
            est = ml_bearings_only(z_rad, time_s, sensor_xy, relative_sigma, x_init=x_init, check=False)
        except (InputError, np.linalg.LinAlgError, FloatingPointError):
            continue
        if np.isfinite(est.objective) and np.all(np.isfinite(est.x0)) and (
                best is None or est.objective < best.objective):
            best = est
    return best


def _check_inputs(time_s, cone_rad, array_heading_rad, sensor_xy_m, unfolded: bool = False):
    """Arrays as float, or InputError naming the problem (NaNs, shapes, unsorted times, cone outside 0..pi)."""
    t, cone = np.asarray(time_s, dtype=float), np.asarray(cone_rad, dtype=float)
    head, xy = np.asarray(array_heading_rad, dtype=float), np.asarray(sensor_xy_m, dtype=float)
    n = len(t)
    require(t.ndim == 1 and cone.shape == (n,) and head.shape == (n,) and xy.shape == (n, 2),
            f"resolve_side: time_s, cone_rad, array_heading_rad must be (n,) and sensor_xy_m (n, 2), got "
            f"{t.shape}, {cone.shape}, {head.shape}, {xy.shape}")
    for name, a in (("time_s", t), ("cone_rad", cone), ("array_heading_rad", head), ("sensor_xy_m", xy)):
        require(bool(np.all(np.isfinite(a))), f"resolve_side: {name} holds NaN or infinite values: drop those rows")
    require(bool(np.all(np.diff(t) > 0)), "resolve_side: times must increase strictly: sort and drop duplicates")
    require(unfolded or bool(np.all((cone >= 0) & (cone <= np.pi))),
            "resolve_side: cone angles must lie in 0..pi rad from the array's forward axis")
    return t, cone, head, xy


def resolve_side(time_s, cone_rad, array_heading_rad, sensor_xy_m, *, sigma_bearing_rad: float | None = None,
                 min_log_lr: float = float(np.log(100.0)), sigma_floor_rad: float = SIGMA_FLOOR_RAD,
                 initial_ranges_m=INITIAL_RANGES_M, unfolded: bool = False) -> SideDecision:
    """The side of the array a cone-angle track's target is on (module doc for the equations).

    Unresolved (ln LR 0, a ``note``) with fewer than 6 bearings or when a side's fit fails.

    Parameters
    ----------
    time_s : array (n,)
        Times (s), strictly increasing.
    cone_rad : array (n,)
        Cone angles (rad, 0..pi from the array's forward axis); with ``unfolded``, unfolded angles phi through
        axis crossings (:func:`resolve_side_through_crossings`), any real values.
    array_heading_rad : array (n,)
        Heading of the array's axis (rad, clockwise from north).
    sensor_xy_m : array (n, 2)
        The array centre [x east, y north] (m).
    sigma_bearing_rad : float, optional
        The bearing noise (rad) if known, else measured from the better fit.
    min_log_lr, sigma_floor_rad : float
        |ln LR| needed for a decision, and the floor of a measured sigma (rad).
    initial_ranges_m : sequence of float
        Ranges (m) of the multi-start fits.
    unfolded : bool
        Whether ``cone_rad`` holds unfolded angles.

    Returns
    -------
    SideDecision
        The side, ln LR, the sigma used and both fits; NaN inputs raise :class:`InputError`.
    """
    t, cone, head, xy = _check_inputs(time_s, cone_rad, array_heading_rad, sensor_xy_m, unfolded)
    require(sigma_bearing_rad is None or (np.isfinite(sigma_bearing_rad) and sigma_bearing_rad > 0),
            f"resolve_side: sigma_bearing_rad must be a positive number, got {sigma_bearing_rad}")
    nan = float("nan") if sigma_bearing_rad is None else float(sigma_bearing_rad)
    if len(t) < MIN_BEARINGS:
        return SideDecision("unresolved", 0.0, nan, None, None,
                            f"too few bearings ({len(t)} < {MIN_BEARINGS}) for a constant-velocity fit")
    z_s, z_p = mirror_bearings_rad(cone, head)
    fit_s = fit_cv_target(z_s, t, xy, initial_ranges_m)
    fit_p = fit_cv_target(z_p, t, xy, initial_ranges_m)
    failed = [name for name, f in (("starboard", fit_s), ("port", fit_p)) if f is None]
    if failed:
        return SideDecision("unresolved", 0.0, nan, fit_s, fit_p,
                            f"constant-velocity fit failed on the {' and '.join(failed)} side")
    j_s, j_p = fit_s.objective, fit_p.objective
    if sigma_bearing_rad is None:
        sigma = max(float(np.sqrt(min(j_s, j_p) / (len(t) - 4))), sigma_floor_rad)
    else:
        sigma = float(sigma_bearing_rad)
    log_lr = -(j_s - j_p) / (2.0 * sigma**2)
    side = "unresolved" if abs(log_lr) < min_log_lr else ("starboard" if log_lr > 0 else "port")
    note = "" if side != "unresolved" else f"|ln LR| = {abs(log_lr):.3g} < {min_log_lr:.3g}: the array has not " \
                                           "turned enough to tell the mirror images apart"
    return SideDecision(side, float(log_lr), sigma, replace(fit_s, covariance=fit_s.covariance * sigma**2),
                        replace(fit_p, covariance=fit_p.covariance * sigma**2), note)


#: most axis crossings whose alternative (the target turned back before the axis) is tried: 2^k hypotheses
MAX_CROSSING_ALTERNATIVES = 3


def axis_crossings(time_s, phi_rad) -> np.ndarray:
    """Times (s) at which an unfolded cone angle phi passes a multiple of pi (the array's axis, endfire): the
    midpoints between the samples where floor(phi / pi) changes.

    Parameters
    ----------
    time_s : array (n,)
        Times (s).
    phi_rad : array (n,)
        Unfolded cone angles (rad).

    Returns
    -------
    numpy.ndarray
        (k,) crossing times (s), in order.
    """
    t, k = np.asarray(time_s, float), np.floor(np.asarray(phi_rad, float) / np.pi)
    i = np.nonzero(np.diff(k) != 0)[0]
    return 0.5 * (t[i] + t[i + 1])


#: a track that comes this close to the array's axis and turns back may have crossed it (the beams are widest at
#: endfire and the peaks there are clipped at the grid's end): its crossing is tried as an alternative (rad)
NEAR_AXIS_RAD = float(np.deg2rad(3.0))
#: axis events (passes and approaches) at one axis closer than this in time are one visit of the axis
#: (:func:`crossing_events`; the tracker's jitter about endfire, not the target's motion, makes them)
VISIT_GAP_S = 60.0


def _reflect_after(phi, time_s, event_s: float, axis_rad: float) -> np.ndarray:
    """phi reflected about ``axis_rad`` after ``event_s``: a crossing undone, or a turning back made a crossing."""
    out = phi.copy()
    after = np.asarray(time_s) > event_s
    out[after] = 2.0 * axis_rad - phi[after]
    return out


def crossing_events(time_s, phi_rad) -> list[tuple[float, float]]:
    """(time s, axis rad) of each visit of phi to the array's axis: each pass of phi through a multiple of pi, and
    each approach to within ``NEAR_AXIS_RAD`` of one that turns back without passing it (a crossing the tracker may
    have reflected), the events at one axis less than :data:`VISIT_GAP_S` apart taken as one visit (its time the
    midpoint of its first and last event).

    Near endfire the beams are widest and the peaks clipped at the grid's end, so the tracker's phi jitters about
    the axis: one true crossing can give a dozen passes and approaches within a minute (the shipped ``zigzag`` scene,
    seed 5: 30 events in 7 visits at three true crossings). Each event's alternative flips the side after it, so a
    jittered visit would spend the :data:`MAX_CROSSING_ALTERNATIVES` on one crossing and leave the next unexamined
    (there: the merchant placed on the wrong side for its last 450 s, and two false zigs); what the record can decide
    is the side after each visit.

    Parameters
    ----------
    time_s, phi_rad : array (n,)
        As :func:`axis_crossings`: times (s) and unfolded cone angles (rad).

    Returns
    -------
    list of (float, float)
        Visit time (s) and the axis angle (rad, a multiple of pi), sorted by time.
    """
    t, phi = np.asarray(time_s, float), np.asarray(phi_rad, float)
    k = np.floor(phi / np.pi)
    events = [(0.5 * (t[i] + t[i + 1]), np.pi * max(k[i], k[i + 1])) for i in np.nonzero(np.diff(k) != 0)[0]]
    axis = np.pi * np.round(phi / np.pi)
    near = np.abs(phi - axis) < NEAR_AXIS_RAD
    edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(int), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if len(np.unique(k[max(a - 1, 0):min(b + 1, len(k))])) == 1 and a > 0 and b < len(k):
            j = a + int(np.argmin(np.abs(phi[a:b] - axis[a:b])))
            events.append((float(t[j]), float(axis[j])))
    visits: list[list[float]] = []  # [first s, last s, axis rad]
    for when, ax in sorted(events):
        if visits and visits[-1][2] == ax and when - visits[-1][1] < VISIT_GAP_S:
            visits[-1][1] = when
        else:
            visits.append([when, when, ax])
    return [(0.5 * (first + last), ax) for first, last, ax in visits]


def resolve_side_through_crossings(time_s, phi_rad, array_heading_rad, sensor_xy_m, **options) -> SideDecision:
    """The side decision of a track that may cross the array's axis (endfire), on its unfolded cone angles.

    The tracker follows phi through endfire (tracking/measurements.py ``fold_cone_deg``); the true bearing on the
    starboard hypothesis is b = h + phi and on the port one b = h - phi, continuous through the crossings (each
    pass of phi through a multiple of pi changes the side). Both mirror hypotheses are carried through every
    crossing; in addition, each event's alternative (:func:`crossing_events`: a crossing undone -- the target
    turned back before the axis -- or a turning back within ``NEAR_AXIS_RAD`` of the axis made a crossing; phi
    reflected about the axis after it) is fitted (the first ``MAX_CROSSING_ALTERNATIVES`` events, 2^k
    patterns), and the pattern
    whose better side has the lowest constant-velocity ML cost wins: the motion that follows the crossing decides
    it. ``side`` is the side at the record's start; :meth:`SideDecision.side_at` and ``final_side`` follow the
    crossings.

    Parameters
    ----------
    time_s : ndarray (n,)
        Times (s), increasing.
    phi_rad : ndarray (n,)
        Unfolded cone angles (rad).
    array_heading_rad : ndarray (n,)
        The array's heading (rad, clockwise from north).
    sensor_xy_m : ndarray (n, 2)
        The array centre (m).
    **options
        Passed to :func:`resolve_side` (``min_log_lr``, ``sigma_bearing_rad`` ...).

    Returns
    -------
    SideDecision
        The decision with ``crossings_s`` and ``unfolded_rad`` of the winning pattern.
    """
    phi = np.asarray(phi_rad, float)
    if len(phi) and int(np.floor(phi[0] / np.pi)) % 2:  # started on the mirrored half: the same bearings as -phi
        phi = -phi
    phi = phi - 2.0 * np.pi * np.floor(phi[0] / (2.0 * np.pi)) if len(phi) else phi  # so that phi[0] in [0, pi]
    patterns = [phi]
    for when, axis in crossing_events(time_s, phi)[:MAX_CROSSING_ALTERNATIVES]:
        patterns += [_reflect_after(p, time_s, when, axis) for p in patterns]
    best, best_cost = None, np.inf
    for p in patterns:
        d = resolve_side(time_s, p, array_heading_rad, sensor_xy_m, unfolded=True, **options)
        costs = [f.objective for f in (d.starboard, d.port) if f is not None]
        cost = min(costs) if costs else np.inf
        if best is None or cost < best_cost:
            best, best_cost = replace(d, crossings_s=tuple(axis_crossings(time_s, p)), unfolded_rad=p), cost
    return best



def axis_end_stretches(cone_rad, near_rad: float) -> list[np.ndarray]:
    """The scans at the record's start and at its end whose cone angle lies within ``near_rad`` of the array's axis
    (0 or pi, also for unfolded angles), as boolean masks (one per end that lies that near; none otherwise).

    Near endfire a line array's beam widens (a beam of half-power width du in u = cos(theta) steered to the axis
    reaches theta = arccos(1 - du / 2) ~ sqrt(du) from it; Van Trees, Optimum Array Processing, 2002, sec. 2.4) and
    the peaks of a ship crossing the axis stop short of it (clipped at the steering grid's end): a track that begins
    or ends within that reach may have crossed the axis there unseen, so the side of those scans is not decided by
    the record (the target's side after the crossing is only known from the motion that follows it, which a track
    ending there does not have).

    Parameters
    ----------
    cone_rad : array (n,)
        Cone angles or unfolded cone angles (rad).
    near_rad : float
        How near the axis a scan must be (rad).

    Returns
    -------
    list of numpy.ndarray
        Boolean masks (n,) of the leading and of the trailing stretch near the axis (each present only if non-empty).
    """
    phi = np.asarray(cone_rad, float)
    near = np.abs(phi - np.pi * np.round(phi / np.pi)) < near_rad
    out = []
    for run in (near, near[::-1]):
        k = len(run) if run.all() else int(np.argmin(run))
        if k:
            mask = np.zeros(len(phi), bool)
            mask[:k] = True
            out.append(mask if run is near else mask[::-1])
    return out


def near_axis_times(time_s, cone_rad, near_rad: float, per_stretch: int = 5) -> np.ndarray:
    """Candidate times of an axis crossing the peaks did not show: in each stretch of scans whose cone angle lies
    within ``near_rad`` of the array's axis (:func:`axis_end_stretches` for why), ``per_stretch`` scans evenly
    spread over it, and the scan nearest the axis.

    Parameters
    ----------
    time_s : array (n,)
        Times (s).
    cone_rad : array (n,)
        Cone angles or unfolded cone angles (rad).
    near_rad : float
        How near the axis a scan must be (rad).
    per_stretch : int
        Evenly spread candidates per stretch.

    Returns
    -------
    numpy.ndarray
        Candidate times (s), sorted; empty when the track never comes that near the axis.
    """
    t, phi = np.asarray(time_s, float), np.asarray(cone_rad, float)
    off = np.abs(phi - np.pi * np.round(phi / np.pi))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (off < near_rad).astype(int), [0]])))
    out = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        idx = np.unique(np.concatenate([np.linspace(a, b - 1, per_stretch).round().astype(int),
                                        [a + int(np.argmin(off[a:b]))]]))
        out += list(t[idx])
    return np.array(sorted(out), float)


@dataclass(frozen=True, slots=True)
class CrossingAlternative:
    """The best-fitting hypothesis that the target crossed the array's axis at ``time_s`` (the side switched there),
    against the decided side: ``log_lr`` = ln L_decided - ln L_alternative (small or negative: the record does not
    reject the crossing); ``fit``: its constant-velocity ML fit, covariance for sigma_u = 1; ``sigma_u``: the noise
    of u = cos(theta) measured from the decided side's weighted fit (:func:`crossing_alternative`)."""

    time_s: float
    log_lr: float
    fit: BatchEstimate
    sigma_u: float


def crossing_alternative(time_s, chosen_rad, other_rad, sensor_xy_m, cone_rad, candidates_s, near_rad: float
                         ) -> CrossingAlternative | None:
    """The likeliest hypothesis that the side switched at one of ``candidates_s``: the decided side's bearings
    before it and the mirror's after, or the mirror's before and the decided side's after, against the decided
    side's bearings throughout; each fitted by the constant-velocity ML (:func:`fit_cv_target`).

    The noise of a line array's cone angle is white in u = cos(theta): sigma_theta = sigma_u / sin(theta) (the
    CRB of a line array's direction in u, Van Trees, Optimum Array Processing, 2002, sec. 8.5; measured on this
    chain's peaks, flat in u from 5 to 90 deg), so each bearing is weighted by sigma_n = sigma_u /
    max(|sin theta_n|, sin(near_rad)): the scans near the axis, where the crossing happens, are the noisiest and
    must not decide it alone. sigma_u^2 = J_decided / (n - 4); ln LR = (J_alt - J_decided) / (2 sigma_u^2), the
    side decision's likelihood ratio (:func:`resolve_side`) with these weights.

    Parameters
    ----------
    time_s : array (n,)
        Times (s).
    chosen_rad, other_rad : array (n,)
        True bearings of the decided side and of its mirror (rad).
    sensor_xy_m : array (n, 2)
        The array centre (m).
    cone_rad : array (n,)
        The cone angles (or unfolded cone angles) the bearings come from (rad).
    candidates_s : array
        Candidate crossing times (s; :func:`near_axis_times`).
    near_rad : float
        The floor of the angle from the axis in the weights (rad; about the endfire beam's reach).

    Returns
    -------
    CrossingAlternative or None
        The alternative of lowest cost; None without candidates inside the record or when the fits fail.
    """
    t, xy = np.asarray(time_s, float), np.asarray(sensor_xy_m, float)
    zc, zo = np.asarray(chosen_rad, float), np.asarray(other_rad, float)
    rel = 1.0 / np.maximum(np.abs(np.sin(np.asarray(cone_rad, float))), np.sin(near_rad))
    inside = [w for w in np.asarray(candidates_s, float) if t[0] <= w < t[-1]]
    decided = fit_cv_target(zc, t, xy, relative_sigma=rel) if inside and len(t) > 4 else None
    if decided is None:
        return None
    var_u = max(decided.objective / (len(t) - 4), SIGMA_FLOOR_RAD**2)
    best = None
    for when in inside:
        after = t > when
        for z in (np.where(after, zo, zc), np.where(after, zc, zo)):
            fit = fit_cv_target(z, t, xy, relative_sigma=rel)
            if fit is not None and (best is None or fit.objective < best.fit.objective):
                best = CrossingAlternative(float(when), (fit.objective - decided.objective) / (2.0 * var_u), fit,
                                           float(np.sqrt(var_u)))
    return best


#: the delete-a-block jackknife's names, which moved to tma/side_jackknife.py; still importable from here
_JACKKNIFE_NAMES = ("JACKKNIFE_BLOCKS", "GAP_BLOCK_FRACTION", "SideJackknife", "time_blocks", "side_jackknife")


def __getattr__(name: str):
    """The jackknife's names (:data:`_JACKKNIFE_NAMES`) from tma/side_jackknife.py, imported on first use (that
    module imports this one, so a plain re-export would be circular)."""
    if name in _JACKKNIFE_NAMES:
        from sonartrack.tma import side_jackknife

        return getattr(side_jackknife, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
