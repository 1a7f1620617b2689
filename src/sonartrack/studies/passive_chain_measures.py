"""What a passive-chain trial measures against the scene's truth: crossings kept, identities, solutions' errors.

The measures of the passive-chain study (studies/passive_chain.py), each a function of the chain's output and the
truth: per window the levels and true cone angles; per crossing of two ships (:func:`crossing_events`) and per
crossing of the array's axis (:func:`axis_crossings`) what the tracks did (:data:`OUTCOMES`); per target its
solution's errors, normalised errors and the correlated-error Cramer-Rao bound, and whether it diverged.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.scene import PassiveSceneSettings

#: the family's ships, in scene order (per-ship outputs are in this order)
FAMILY_SHIPS = ("pair-near", "pair-far", "crosser", "loner")

#: windows of the running median of a ship's level at its cone angle (its SNR in the detector, :func:`window_truth`)
SNR_MEDIAN_WINDOWS = 11
#: a target follows a ship over a span when at least this many of its peaks lie within match_deg of it
MIN_FOLLOW_SCANS = 5
#: a printed solution has diverged when its range is beyond this many times the true range, or its speed beyond
#: the fastest ship a scene may hold, or it is not finite
DIVERGED_RANGE_FACTOR = 5.0
DIVERGED_SPEED_MPS = 60.0 * KNOT_MPS


def running_median(x, width: int) -> np.ndarray:
    """Centred running median along the last axis (edges: the nearest full window)."""
    from numpy.lib.stride_tricks import sliding_window_view

    x = np.asarray(x, float)
    if x.shape[-1] < width:
        return np.median(x, axis=-1, keepdims=True) * np.ones_like(x)
    med = np.median(sliding_window_view(x, width, axis=-1), axis=-1)
    pad = (width // 2, width - 1 - width // 2)
    return np.pad(med, [(0, 0)] * (x.ndim - 1) + [pad], mode="edge")


def window_levels(scene: PassiveSceneSettings, result):
    """Per ship and window: the geometry, the true cone angle (deg) and the front end's normalised level at it
    (linear between beams, running median over ``SNR_MEDIAN_WINDOWS`` windows: the ship's level, not a noise peak
    that happens to fall on its cone angle)."""
    from sonartrack.sim.passive_scene import scene_geometry

    rec = result.record
    tw = np.asarray(rec.time_s, float)
    g = scene_geometry(scene, tw)
    cone = np.rad2deg(g.cone_rad)
    level = np.asarray(rec.level, float)
    at_ship = np.array([[np.interp(cone[s, k], rec.cone_deg, level[k]) for k in range(len(tw))]
                        for s in range(cone.shape[0])]).reshape(cone.shape)
    return g, cone, running_median(at_ship, SNR_MEDIAN_WINDOWS)


def window_truth(scene: PassiveSceneSettings, result):
    """Per ship and window: the true cone angle (deg), and whether the ship is above the detection threshold.

    Its SNR as the detector sees it is the front end's level at its true cone angle (:func:`window_levels`); it
    counts when that level reaches the threshold and no other ship lies within one beam (direction-cosine separation
    below the broadside beamwidth ``PassiveStages.min_separation_deg`` in rad, :func:`direction_separation`), where
    the level would be the other ship's. A noise-limited formula (z = N SNR sqrt(bins)) would overrate a weak ship
    next to loud ones: their sidelobes, not the noise, set the background spread of the normaliser. Returns
    (geometry, cone (S, T), detectable (S, T))."""
    g, cone, at_ship = window_levels(scene, result)
    sep = direction_separation(cone[:, None, :], cone[None, :, :])
    sep[np.arange(len(cone)), np.arange(len(cone))] = np.inf
    alone = sep.min(axis=1) >= np.deg2rad(result.stages.min_separation_deg) if len(cone) > 1 \
        else np.ones_like(at_ship, bool)
    return g, cone, (at_ship >= result.settings.threshold) & alone


def direction_separation(cone_a_deg, cone_b_deg) -> np.ndarray:
    """|cos(a) - cos(b)|: two cone angles' separation in the direction cosine u = cos(theta), in which a line array's
    beam has one width everywhere (about lambda / L; Van Trees 2002, sec. 2.4): two ships are resolved when this
    reaches the broadside beamwidth in radians. In cone angle the beam widens as 1 / sin(theta) towards endfire,
    so two ships 3 deg apart at 175 deg lie in one beam of an array that resolves 3 deg at broadside.

    Parameters
    ----------
    cone_a_deg, cone_b_deg : array_like
        Cone angles (deg), broadcast together.

    Returns
    -------
    ndarray
        The separation in u (dimensionless; compare with a beamwidth in rad).
    """
    return np.abs(np.cos(np.deg2rad(cone_a_deg)) - np.cos(np.deg2rad(cone_b_deg)))


def crossing_events(cone_deg: np.ndarray, beamwidth_deg: float) -> list[tuple[int, int, int, int]]:
    """Crossings: each maximal run of windows in which two ships lie within one beam of the array: their
    direction-cosine separation (:func:`direction_separation`) below the broadside beamwidth, so that the run lasts
    as long as the array cannot tell the two apart (longer near endfire, where the beam is wider in cone angle).

    Parameters
    ----------
    cone_deg : ndarray (S, T)
        True cone angles (deg).
    beamwidth_deg : float
        One beamwidth at broadside (deg).

    Returns
    -------
    list of (a, b, k0, k1)
        The two ships (a < b) and the first and last window of the run (inclusive).
    """
    out = []
    for a in range(cone_deg.shape[0]):
        for b in range(a + 1, cone_deg.shape[0]):
            close = direction_separation(cone_deg[a], cone_deg[b]) < np.deg2rad(beamwidth_deg)
            edges = np.diff(np.concatenate([[0], close.astype(int), [0]]))
            out += [(a, b, int(k0), int(k1) - 1) for k0, k1 in zip(np.nonzero(edges == 1)[0],
                                                                  np.nonzero(edges == -1)[0], strict=True)]
    return out


def axis_crossings(bearing_rad: np.ndarray, array_heading_rad: np.ndarray) -> list[tuple[int, int]]:
    """Axis crossings: wherever a ship's true side (the sign of sin(bearing - array heading)) changes between
    consecutive windows.

    Parameters
    ----------
    bearing_rad : ndarray (S, T)
        True bearings (rad, clockwise from north).
    array_heading_rad : ndarray (T,)
        The array's axis heading (rad).

    Returns
    -------
    list of (int, int)
        (ship, first window on the new side).
    """
    side = np.sin(np.asarray(bearing_rad) - np.asarray(array_heading_rad)[None]) >= 0.0
    return [(int(s), int(k) + 1) for s, k in zip(*np.nonzero(side[:, 1:] != side[:, :-1]), strict=True)]


def held_by_track(tracks, tw, cone_true_deg, match_deg: float) -> np.ndarray:
    """(S, T) True where a confirmed track (of ``tracks``, a :class:`~sonartrack.tracking.run.BearingTracks`) lies
    within ``match_deg`` of the ship's cone angle at window t."""
    conf = np.asarray(tracks.confirmed).astype(bool)
    k = np.searchsorted(tw, np.asarray(tracks.time_s, float)[conf])
    cone = np.asarray(tracks.bearing_deg, float)[conf]
    held = np.zeros(cone_true_deg.shape, bool)
    for s in range(cone_true_deg.shape[0]):
        near = np.abs(cone - cone_true_deg[s, np.clip(k, 0, len(tw) - 1)]) < match_deg
        held[s, k[near & (k < len(tw))]] = True
    return held


def follower(measurements, tw, cone_true_deg, t_lo: float, t_hi: float, match_deg: float) -> int | None:
    """The target following a ship over [t_lo, t_hi]: the one with the most peaks within ``match_deg`` of the
    ship's true cone angle there, if at least ``MIN_FOLLOW_SCANS``.

    Parameters
    ----------
    measurements : list of (time_s, cone_deg) arrays
        Each target's peaks.
    tw, cone_true_deg : ndarray (T,)
        The windows' times (s) and the ship's true cone angle (deg) there.
    t_lo, t_hi : float
        The span (s).
    match_deg : float
        The match distance (deg).

    Returns
    -------
    int or None
        Index into ``measurements``.
    """
    best, hits_best = None, MIN_FOLLOW_SCANS - 1
    for i, (t, cone) in enumerate(measurements):
        t, cone = np.asarray(t, float), np.asarray(cone, float)
        inside = (t >= t_lo) & (t <= t_hi)
        hits = int(np.sum(np.abs(cone[inside] - np.interp(t[inside], tw, cone_true_deg)) < match_deg))
        if hits > hits_best:
            best, hits_best = i, hits
    return best


#: what became of two ships' targets through a crossing (:func:`crossing_outcome`)
OUTCOMES = {1: "kept", 2: "swapped", 3: "jumped", 4: "lost", 5: "new target"}


def crossing_outcome(measurements, tw, cone_a, cone_b, t0: float, t1: float, window_s: float,
                     match_deg: float) -> float:
    """What became of the two targets following ships a and b over ``window_s`` before a crossing [t0, t1], seen
    over ``window_s`` after it (codes of ``OUTCOMES``): 1 kept (each ship followed by its own target), 2 swapped
    (each followed by the other's), 3 jumped (one target follows the other ship, the rest not swapped: one record
    joining two ships), 4 lost (a ship followed by no target), 5 a new target on a ship; NaN if the two ships are
    not followed by two targets before it."""
    before = [follower(measurements, tw, c, t0 - window_s, t0, match_deg) for c in (cone_a, cone_b)]
    if None in before or before[0] == before[1]:
        return float("nan")
    after = [follower(measurements, tw, c, t1, t1 + window_s, match_deg) for c in (cone_a, cone_b)]
    if after == before:
        return 1.0
    if after == before[::-1]:
        return 2.0
    if after[0] == before[1] or after[1] == before[0]:
        return 3.0
    return 4.0 if None in after else 5.0


def identity_through(measurements, tw, cone_a, cone_b, t0: float, t1: float, window_s: float,
                     match_deg: float) -> float:
    """1 if the two targets following ships a and b over ``window_s`` before a crossing [t0, t1] follow the same
    ships over ``window_s`` after it, 0 if not (swapped, merged, lost or a new target), NaN if the two ships are
    not followed by two targets before it (:func:`crossing_outcome`)."""
    code = crossing_outcome(measurements, tw, cone_a, cone_b, t0, t1, window_s, match_deg)
    return code if np.isnan(code) else float(code == 1.0)


def bearing_error_after(record_t, record_bearing_rad, truth_t, truth_bearing_rad, t_lo: float, t_hi: float) -> float:
    """Median |true bearing - truth| of a record's bearings over [t_lo, t_hi].

    Parameters
    ----------
    record_t, record_bearing_rad : ndarray (n,)
        The record's times (s) and true bearings (rad).
    truth_t, truth_bearing_rad : ndarray (T,)
        The truth's times (s) and bearings (rad), interpolated (unwrapped) to the record's times.
    t_lo, t_hi : float
        The span (s).

    Returns
    -------
    float
        The median error (deg); NaN without a bearing in the span.
    """
    from sonartrack.core.angles import wrap_angle

    t = np.asarray(record_t, float)
    inside = (t >= t_lo) & (t <= t_hi)
    if not inside.any():
        return float("nan")
    truth = np.interp(t[inside], truth_t, np.unwrap(truth_bearing_rad))
    return float(np.rad2deg(np.median(np.abs(wrap_angle(np.asarray(record_bearing_rad)[inside] - truth)))))


def diverged(state, covariance, array_xy, true_range_m: float) -> bool:
    """Whether a solution's final row has gone away: not finite, a range beyond ``DIVERGED_RANGE_FACTOR`` x the
    true range, or a speed beyond ``DIVERGED_SPEED_MPS``.

    Parameters
    ----------
    state : array (4,)
        [x, y, vx, vy] (m, m/s).
    covariance : array (4, 4)
        Its covariance.
    array_xy : array (2,)
        The array centre at the same time (m).
    true_range_m : float
        The true range (m).

    Returns
    -------
    bool
        True when diverged.
    """
    x, P = np.asarray(state, float), np.asarray(covariance, float)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(P))):
        return True
    r = float(np.hypot(*(x[:2] - np.asarray(array_xy, float))))
    return bool(r > DIVERGED_RANGE_FACTOR * true_range_m or np.hypot(x[2], x[3]) > DIVERGED_SPEED_MPS)


def normalised_errors(state, covariance, truth_state) -> tuple[float, float]:
    """NEES e^T P^-1 e of the 4-state (e = estimate - truth) and the Mahalanobis distance of the position error in
    its own 2 x 2 covariance.

    Parameters
    ----------
    state, truth_state : array (4,)
        Estimate and truth [x, y, vx, vy] (m, m/s).
    covariance : array (4, 4)
        The estimate's covariance.

    Returns
    -------
    (float, float)
        NEES (chi-square(4) for a consistent estimator) and the position error in sds; NaN for a singular P.
    """
    e = np.asarray(state, float) - np.asarray(truth_state, float)
    P = np.asarray(covariance, float)
    try:
        nees = float(e @ np.linalg.solve(P, e))
        pos = float(np.sqrt(max(e[:2] @ np.linalg.solve(P[:2, :2], e[:2]), 0.0)))
    except np.linalg.LinAlgError:
        return float("nan"), float("nan")
    return nees, pos


def match_targets(result, scene, match_deg: float) -> dict[int, int]:
    """target index -> ship index (the ship whose cone angle the target's peaks follow, median offset below
    ``match_deg``); targets following no ship are absent (false targets)."""
    from sonartrack.sim.passive_scene import scene_geometry

    out = {}
    for i, tg in enumerate(result.targets):
        cone = np.rad2deg(scene_geometry(scene, tg.track.time_s).cone_rad)  # (S, n)
        if cone.shape[0] == 0:
            continue
        off = np.median(np.abs(cone - np.asarray(tg.track.cone_deg)[None]), axis=1)
        if off.min() < match_deg:
            out[i] = int(np.argmin(off))
    return out


def longest_per_ship(result, matches: dict[int, int], n_ships: int) -> list[int | None]:
    """For each ship, the index of its longest target (None if none follows it)."""
    best: list[int | None] = [None] * n_ships
    for i, s in matches.items():
        if best[s] is None or result.targets[i].track.duration_s > result.targets[best[s]].track.duration_s:
            best[s] = i
    return best


def ml_scans(tg) -> np.ndarray:
    """Which of the target's scans (``tg.track``) its ML solution was fitted to: those its record holds (the
    bearings + frequency ML's record keeps only the scans with a tonal frequency; bool (n,))."""
    return np.isin(np.asarray(tg.track.time_s, float), np.asarray(tg.ml.record.time_s, float))


def _crb_inputs(tg, scene, ship: int, nav):
    """(times s, array positions m, the peaks' offsets from the true cone angle rad, true X0 at the first time, the
    last row's time s) over the scans the target's ML was fitted to (:func:`ml_scans`)."""
    from sonartrack.core.angles import wrap_angle
    from sonartrack.sim.passive_scene import scene_geometry

    on = ml_scans(tg)
    t = np.asarray(tg.track.time_s, float)[on]
    g = scene_geometry(scene, t)
    offsets = wrap_angle(np.deg2rad(np.asarray(tg.track.cone_deg, float)[on]) - g.cone_rad[ship])
    x0 = np.concatenate([g.ship_xy[ship, 0], g.ship_velocity[ship, 0]])
    xy, _ = nav.array_at(t)
    return t, xy, offsets, x0, float(tg.ml.solution.time_s[-1])


def target_errors(tg, scene, ship: int, nav) -> tuple[float, float, float, float]:
    """(final ML position error m, CRB position sd m at the same time, measured bearing sd deg, range determined)
    of one target, judged on the data the ML was given: the scans of its record (:func:`ml_scans`) and the time of
    its last row. The CRB (tma/batch_ml.py :func:`~sonartrack.tma.batch_ml.crb_position_sd_m`) is that of the
    true constant-velocity track over those scans, with the bearing noise of the target's own peaks there (the sd
    of their offsets from the true cone angle: the sensor's noise, whichever side the chain took), carried to the
    last row's time; the error is the last row's position against the ship's at that time."""
    from sonartrack.sim.passive_scene import scene_geometry
    from sonartrack.tma.batch_ml import crb_position_sd_m

    t, xy, offsets, x0, t_end = _crb_inputs(tg, scene, ship, nav)
    sigma = float(np.std(offsets))
    crb_sd = crb_position_sd_m(x0, t - t[0], xy, max(sigma, 1e-6), t_end - t[0])
    truth_end = scene_geometry(scene, np.array([t_end])).ship_xy[ship, 0]
    err = float(np.hypot(*(np.asarray(tg.ml.solution.state[-1, :2], float) - truth_end)))
    return err, crb_sd, float(np.rad2deg(sigma)), float(tg.ml.solution.range_flags()[-1])


def correlated_crb_sd_m(tg, scene, ship: int, nav) -> float:
    """The CRB position sd of :func:`target_errors` for errors that are AR(1) in scan order with the lag-1
    correlation of the peaks' own offsets from the truth (tma/solve.py
    :func:`~sonartrack.tma.solve.lag1_correlation`; tma/batch_ml.py
    :func:`~sonartrack.tma.batch_ml.fisher_information` with ``rho``). A reading of the ml-near-crb yardstick,
    reported beside it: a second ship in the beam makes the errors slow (lag-1 correlation 0.5-0.95 on the study's
    failures), and the white-noise CRB of the same sd then bounds an error no estimator can reach."""
    from sonartrack.tma.batch_ml import crb_position_sd_m
    from sonartrack.tma.solve import lag1_correlation

    t, xy, offsets, x0, t_end = _crb_inputs(tg, scene, ship, nav)
    return crb_position_sd_m(x0, t - t[0], xy, max(float(np.std(offsets)), 1e-6), t_end - t[0],
                             rho=lag1_correlation(offsets))


def side_correct(side, time_s, truth_side) -> float:
    """1 if a target's side decision (per segment between its axis crossings: ``side.side_at``) matches the true side
    in at least 90 % of its scans, 0 if not, NaN if its side is unresolved."""
    if side.side == "unresolved":
        return float("nan")
    return float(np.mean(side.side_at(time_s) == np.asarray(truth_side, object)) >= 0.9)


def ship_names(config) -> list[str]:
    """The family's ships in scene order (the per-ship outputs' order)."""
    return list(FAMILY_SHIPS)
