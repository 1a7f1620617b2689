"""Narrowband targets: line sources no bearing track explains, joined by one constant-velocity target, to TMA.

Such sources on one frequency (within ``same_line_hz``) are fragments of one line when one constant-velocity target
explains their bearings through the array's motion and turn (:func:`join_statistic`: the predictive test of the
later fragment against the earlier one's target, the bearings b = h +- theta on either side from the navigation, so
a line that broke where the array turned is tied to its continuation by the turn's cone-angle shift on its side).
Fragments are taken in time order, each continuing the target it passes the test with (``max_join_gap_s``), and a
target's cone angles off its constant-velocity fit are left out as outliers (:func:`without_outliers`). A record
that spans ``min_track_s`` with at least 10 periods goes to the same side decision and TMA as a bearing track
(systems/passive/targets.py), its bearings the lines' refined cone angles per period (every detection at least
``min_target_snr_db`` over the background) and its tonal their refined frequencies. Step 3 of the narrowband stage
(systems/passive/narrowband.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.narrowband import NarrowbandLines, SourceRoles, strongest_line, tonal_at
from sonartrack.systems.passive.settings import PassiveStages
from sonartrack.tracking.line_tracks import LineSource, LineTrack

#: fewest measurements of a record that goes to TMA (the chain's rule for bearing tracks)
MIN_TMA_POINTS = 10
#: fewest cone angles of a fragment whose constant-velocity fit (4 parameters) judges outliers and joins
MIN_FIT_POINTS = 6
#: a cone angle farther than this many robust standard deviations from its target's constant-velocity fit is an
#: outlier (a noise cell the line's gate took: default scene, 1200 s, seeds 1-6, 5 % of the submarine's line
#: detections at 1-3 dB over the background lay more than 5 deg off, against a median error of 0.9 deg); 3.5, not 3:
#: a Gaussian record of 50 holds a 3-sigma value in one of seven
OUTLIER_SIGMAS = 3.5
#: refits while leaving out outliers
OUTLIER_PASSES = 3
#: floor of a line's cone-angle standard deviation (deg): the refined cone angles' slow biases
MIN_SD_DEG = 0.5
#: significance of the predictive test that joins fragments (:func:`join_statistic`)
JOIN_ALPHA = 0.01


@dataclass(frozen=True, slots=True)
class _Fragment:
    """One source's line as a piece of a narrowband target: periods (s), refined cone angles (deg), SNR (dB) and
    frequencies (Hz) of its strongest line's kept detections; the ids of the sources in it."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    snr_db: np.ndarray
    frequency_hz: np.ndarray
    source_ids: tuple[int, ...]

    def take(self, keep: np.ndarray) -> _Fragment:
        return _Fragment(self.time_s[keep], self.cone_deg[keep], self.snr_db[keep], self.frequency_hz[keep],
                         self.source_ids)

    def then(self, b: _Fragment) -> _Fragment:
        return _Fragment(*(np.concatenate([getattr(self, a), getattr(b, a)])
                           for a in ("time_s", "cone_deg", "snr_db", "frequency_hz")), self.source_ids + b.source_ids)


def _fragment(src: LineSource, lines: dict[int, LineTrack], min_snr_db: float) -> _Fragment:
    top = strongest_line(src, lines)
    on = top.detected & (np.nan_to_num(top.snr_db, nan=-np.inf) >= min_snr_db)
    return _Fragment(top.time_s[on], top.measured_cone_deg[on], top.snr_db[on], top.measured_frequency_hz[on],
                     (src.source_id,))


def cv_fit_residuals_deg(time_s, cone_deg, nav, fit_on: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """The bearings-only constant-velocity ML fit of a cone-angle history on the better of the two mirror sides
    (tma/sides.py :func:`~sonartrack.tma.sides.fit_cv_target`, b = h +- theta): its cost J (sum of squared residuals,
    rad^2) and the residuals of every measurement (deg).

    Parameters
    ----------
    time_s, cone_deg : ndarray (n,)
        Times (s, increasing) and cone angles (deg).
    nav : Navigation
        The array's position and heading.
    fit_on : ndarray of bool (n,), optional
        The measurements fitted (default all); the residuals are of all.

    Returns
    -------
    cost : float
        J over the fitted measurements (rad^2); inf when no fit.
    residual_deg : ndarray (n,)
        Measured minus fitted bearing (deg); inf when no fit.
    """
    from sonartrack.core.angles import bearing_rad, wrap_angle
    from sonartrack.tma.sides import fit_cv_target, mirror_bearings_rad

    t = np.asarray(time_s, float)
    on = np.ones(len(t), bool) if fit_on is None else np.asarray(fit_on, bool)
    xy, heading = nav.array_at(t)
    best, res = np.inf, np.full(len(t), np.inf)
    for z in mirror_bearings_rad(np.deg2rad(np.asarray(cone_deg, float)), heading):
        f = fit_cv_target(z[on], t[on], xy[on]) if on.sum() > 4 else None
        if f is not None and f.objective < best:
            with np.errstate(invalid="ignore"):  # the covariance of a fit without range is not used here
                pos = f.state_at(t)[0][:, :2] - xy
            best, res = f.objective, np.rad2deg(wrap_angle(z - bearing_rad(pos[:, 0], pos[:, 1])))
    return best, res


def _robust_sd_deg(residual_deg: np.ndarray) -> float:
    """1.4826 median |r| (the standard deviation of Gaussian residuals, unmoved by a few outliers), at least
    ``MIN_SD_DEG``."""
    return max(1.4826 * float(np.median(np.abs(residual_deg))), MIN_SD_DEG)


def without_outliers(fr: _Fragment, nav) -> _Fragment:
    """The fragment without the cone angles farther than ``OUTLIER_SIGMAS`` robust standard deviations (of all its
    residuals) from its constant-velocity fit (refitted without them until none is left out; a fragment too short
    for a fit with residuals, fewer than ``MIN_FIT_POINTS``, is kept whole)."""
    keep = np.ones(len(fr.time_s), bool)
    for _ in range(OUTLIER_PASSES):
        if keep.sum() < MIN_FIT_POINTS:
            return fr
        _, r = cv_fit_residuals_deg(fr.time_s, fr.cone_deg, nav, keep)
        new = np.abs(r) <= OUTLIER_SIGMAS * _robust_sd_deg(r)  # over all: the kept ones' would shrink pass by pass
        if (new == keep).all() or new.sum() < MIN_FIT_POINTS:
            break
        keep = new
    return fr.take(keep)


def join_statistic(a: _Fragment, b: _Fragment, nav) -> tuple[float, float]:
    """Whether fragment b continues target a: the predictive test of one constant-velocity target through both
    (Chow's test for predictive failure: G. C. Chow, "Tests of equality between sets of coefficients in two linear
    regressions", Econometrica 28, 1960, sec. 4), with the array's motion and turn from the navigation in the fit
    (the bearing history b = h +- theta on either side; the side that explains both wins):

        F = ((J_ab - J_a) / n_b) / (J_a / (n_a - 4))   ~   F(n_b, n_a - 4)   when b is a's target

    J the CV fits' costs (b's cone angles farther than ``OUTLIER_SIGMAS`` robust sd of a's residuals from the joint
    fit left out, at most a quarter of them; J_a / (n_a - 4) at least ``MIN_SD_DEG`` squared, and at least b's own
    J_b / (n_b - 4) when b has ``MIN_FIT_POINTS``: DEVIATION from Chow's equal variances, a line's noise grows as it
    fades, and a test on a's variance alone split the submarine of the default scene, seed 2, at F = 3.6 against 2.9).

    Parameters
    ----------
    a, b : _Fragment
        The earlier target (a fragment or fragments already joined) and the later fragment, b after a.
    nav : Navigation
        The array's position and heading.

    Returns
    -------
    (float, float)
        F and its critical value at ``1 - JOIN_ALPHA`` (F > critical: not one target; inf, 0 when a is too short).
    """
    from scipy.special import fdtri  # the F quantile (f.ppf's own formula) without scipy.stats' 0.3 s import

    n_a = len(a.time_s)
    if n_a < MIN_FIT_POINTS or len(b.time_s) < 2:
        return np.inf, 0.0
    j_a, r_a = cv_fit_residuals_deg(a.time_s, a.cone_deg, nav)
    var_a = max(j_a / (n_a - 4), np.deg2rad(MIN_SD_DEG) ** 2)
    if len(b.time_s) >= MIN_FIT_POINTS:  # a line's noise changes with its SNR: b's own, when larger, is the scale
        j_b, _ = cv_fit_residuals_deg(b.time_s, b.cone_deg, nav)
        var_a = max(var_a, j_b / (len(b.time_s) - 4))
    ab = a.then(b)
    _, r = cv_fit_residuals_deg(ab.time_s, ab.cone_deg, nav)
    far = np.abs(r[n_a:]) > OUTLIER_SIGMAS * max(_robust_sd_deg(r_a), np.rad2deg(np.sqrt(var_a)))
    if far.sum() > 0.25 * len(b.time_s):
        return np.inf, 0.0
    keep = np.concatenate([np.ones(n_a, bool), ~far])
    j_ab, _ = cv_fit_residuals_deg(ab.time_s, ab.cone_deg, nav, keep)
    n_b = int((~far).sum())
    return float(max(j_ab - j_a, 0.0) / n_b / var_a), float(fdtri(n_b, n_a - 4, 1.0 - JOIN_ALPHA))


def _after(a: _Fragment, b: _Fragment) -> _Fragment:
    """b's periods after a's last (a line track and its successor overlap where the first coasted)."""
    return b.take(b.time_s > a.time_s[-1])


def joined_fragments(frags: list[_Fragment], nav, max_gap_s: float) -> list[_Fragment]:
    """Fragments of one line joined in time order: each fragment continues the target it passes the predictive
    test with (:func:`join_statistic`, the least F over critical), among those that ended at most ``max_gap_s``
    before it starts, else starts a target of its own; each target's outliers are then left out.

    Parameters
    ----------
    frags : list of _Fragment
        One line's fragments (one frequency).
    nav : Navigation
        The array's position and heading.
    max_gap_s : float
        Largest gap (s) between two fragments of one target.

    Returns
    -------
    list of _Fragment
        The targets, in order of first period.
    """
    out: list[_Fragment] = []
    for b in sorted((f for f in frags if len(f.time_s)), key=lambda f: f.time_s[0]):
        best, ratio = None, 1.0
        for i, a in enumerate(out):
            bb = _after(a, b)
            if not len(bb.time_s) or bb.time_s[0] - a.time_s[-1] > max_gap_s:
                continue
            stat, crit = join_statistic(a, bb, nav)
            if stat <= crit * ratio:
                best, ratio = i, stat / max(crit, 1e-12)
        if best is None:
            out.append(without_outliers(b, nav))
        else:
            out[best] = without_outliers(out[best].then(_after(out[best], b)), nav)
    return out


def _frequency_clusters(sources: list[LineSource], lines: dict[int, LineTrack], tol_hz: float
                        ) -> list[list[LineSource]]:
    """Sources whose strongest lines lie within ``tol_hz`` of the next (single linkage along frequency)."""
    order = sorted(sources, key=lambda s: strongest_line(s, lines).mean_frequency_hz)
    out: list[list[LineSource]] = []
    last = -np.inf
    for src in order:
        f = strongest_line(src, lines).mean_frequency_hz
        if f - last > tol_hz:
            out.append([])
        out[-1].append(src)
        last = f
    return out


def narrowband_records(nb: NarrowbandLines, roles: SourceRoles, nav, stages: PassiveStages
                       ) -> list[tuple[TrackMeasurements, TonalTrack]]:
    """The narrowband targets' records: the sources no bearing track explains and no explained line leaks into,
    fragments of one line joined across gaps (:func:`joined_fragments`), outliers left out, those that span
    ``min_track_s`` with at least 10 periods (module doc, item 3).

    Parameters
    ----------
    nb, roles : NarrowbandLines, SourceRoles
        The lines and sources, and their roles (:func:`source_roles`).
    nav : Navigation
        The array's position and heading (the joining test).
    stages : PassiveStages
        The chain's settings.

    Returns
    -------
    list of (TrackMeasurements, TonalTrack)
        Per target: its bearings (track id = its first source's id, the joined sources' ids in
        ``joined_track_ids``; amplitude = the line's SNR in dB) and its tonal, in order of first period.
    """
    s = stages.settings
    lines = {ln.track_id: ln for ln in nb.lines}
    free = [src for src in nb.sources if src.source_id not in roles.track and src.source_id not in roles.leak]
    targets: list[_Fragment] = []
    for group in _frequency_clusters(free, lines, s.narrowband.same_line_hz):
        frags = [_fragment(src, lines, s.narrowband.min_target_snr_db) for src in group]
        targets += joined_fragments([f for f in frags if len(f.time_s) >= 2], nav, s.narrowband.max_join_gap_s)
    out = []
    for fr in sorted(targets, key=lambda f: f.time_s[0]):
        if fr.time_s[-1] - fr.time_s[0] < s.min_track_s or len(fr.time_s) < MIN_TMA_POINTS:
            continue
        m = TrackMeasurements(fr.source_ids[0], fr.time_s, fr.cone_deg, fr.snr_db, fr.time_s, fr.cone_deg,
                              joined_track_ids=fr.source_ids[1:])
        out.append((m, tonal_at(fr.time_s, fr.frequency_hz, fr.snr_db, fr.time_s, stages)))
    return out
