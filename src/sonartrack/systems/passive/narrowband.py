"""Narrowband stage of the passive chain: LOFAR lines -> line tracks -> sources -> tonals and targets.

1. Lines. The LOFAR gram per beam (acoustics/lofar.py; computed in the front end's pass when the front end offers
   it, else in a pass of its own) and its line detections. A detection sits on the gram's grids (beams 3 deg
   apart, bins 1 / window apart), so its cone angle and frequency are refined by the vertex of the parabola
   through the log of the line's power over the background, P - mu = P (1 - 1 / z), of the cell and its two
   neighbours along that axis. Across beams, first the beam of the largest P - mu within ``CLIMB_BEAMS`` of the
   detection's (climbing): the detection is a peak of z = P / mu, and where a loud ship's broadband noise raises
   mu in the next beams, z peaks beside the line (default scene: the submarine's 200 Hz line peaks in z 6 deg
   from its true cone angle while the tanker is 2 deg beside it; P - mu peaks within a degree),

       delta = (a - c) / (2 (a - 2 b + c)),   |delta| <= 1/2  (cells a, b, c; b the peak)

   (Gaussian interpolation: the parabola through the log of three spectral values, exact for a Gaussian peak;
   Gasior & Gonzalez, "Improving FFT frequency measurement resolution by parabolic and Gaussian spectrum
   interpolation", AIP Conf. Proc. 732, 2004, sec. 3; applied across beams too, where the main lobe is close to a
   Gaussian).
   With ``[narrowband] mftd`` (off by default), paper P1's MFTD over each line's bearing-time record adds the
   periods the single-period threshold missed (systems/passive/line_mftd.py) before the refinement.
   A detection whose background window reaches past the recording's own band (a recording band-limited inside the
   LOFAR band: empty bins, which halve the background) is tested again on its live reference bins
   (:func:`off_band_edges`).
   Then tracked in frequency and bearing and grouped into sources (tracking/line_tracks.py).
2. Sources and bearing tracks. A source whose bearing history follows a confirmed bearing track (RMS cone-angle
   difference over their common periods within ``match_beamwidths`` broadside beamwidths at the source's
   frequency, at least ``min_overlap`` periods) belongs to that track: it gives the track its tonal when the
   track's own beam showed none (tonal_pass.py). A source that no track explains, on a frequency that no
   explained line carries (within ``same_line_hz``: a loud ship's line leaks into other beams at its own
   frequency), is a target the broadband front end missed.
3. Narrowband targets. Such sources on one frequency (within ``same_line_hz``) are fragments of one line when one
   constant-velocity target explains their bearings through the array's motion and turn (:func:`join_statistic`:
   the predictive test of the later fragment against the earlier one's target, the bearings b = h +- theta on
   either side from the navigation, so a line that broke where the array turned is tied to its continuation by the
   turn's cone-angle shift on its side). Fragments are taken in time order, each continuing the target it passes the
   test with (``max_join_gap_s``), and a target's cone angles off its constant-velocity fit are left out as outliers
   (:func:`without_outliers`). A record that spans ``min_track_s`` with at least 10 periods goes to the same side
   decision and TMA as a bearing track (systems/passive/targets.py), its bearings the lines' refined cone angles per
   period (every detection at least ``min_target_snr_db`` over the background) and its tonal their refined
   frequencies.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.acoustics.lofar import LineDetections, LofarGram, LofarSettings, line_threshold
from sonartrack.acoustics.tonal import TonalTrack, frequency_sigma_hz
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.settings import PassiveStages
from sonartrack.tracking.line_tracks import LineSource, LineTrack

#: beams a detection's cone angle may climb to the peak of the line's power over the background (module doc)
CLIMB_BEAMS = 3
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
class NarrowbandLines:
    """The narrowband stage's lines: ``gram`` (None when the recording is shorter than one integration period),
    the confirmed line tracks and the sources they group into."""

    gram: LofarGram | None
    lines: tuple[LineTrack, ...]
    sources: tuple[LineSource, ...]


@dataclass(frozen=True, slots=True)
class SourceRoles:
    """What each line source is (by source id): ``track`` -> the index of the bearing track (into the chain's
    long-enough tracks) it follows; ``leak`` -> the frequency (Hz) of the explained line it repeats; the rest are
    candidate targets."""

    track: dict[int, int]
    leak: dict[int, float]


def _vertex(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Offset of the vertex of the parabola through (-1, a), (0, b), (1, c), within [-1/2, 1/2] (module doc)."""
    den = a - 2.0 * b + c
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(den < 0, 0.5 * (a - c) / den, 0.0)
    return np.clip(np.nan_to_num(d), -0.5, 0.5)


def refined_detections(gram: LofarGram, d: LineDetections) -> LineDetections:
    """The detections with cone angle and frequency refined between the grids' cells (module doc, item 1).

    Parameters
    ----------
    gram : LofarGram
        The integrated gram.
    d : LineDetections
        Its line detections (acoustics/lofar.py ``detect_lines``).

    Returns
    -------
    LineDetections
        The same rows, cone angle (deg) climbed and interpolated, frequency (Hz) interpolated; a cell at a grid's
        edge keeps its value there.
    """
    if not len(d):
        return d
    z = np.asarray(gram.statistic, float)
    excess = np.asarray(gram.power, float) * (1.0 - 1.0 / np.maximum(z, 1e-12))
    loge = np.log(np.maximum(excess, np.finfo(float).tiny))
    n_b, n_f = loge.shape[1], loge.shape[2]
    ti = np.searchsorted(gram.time_s, d.time_s)
    k = np.clip(np.searchsorted(gram.freqs_hz, d.frequency_hz - 1e-9), 0, n_f - 1)
    b = np.asarray(d.beam, np.int64)
    for _ in range(CLIMB_BEAMS):  # to the peak of P - mu across beams
        near = np.stack([np.clip(b + j, 0, n_b - 1) for j in (-1, 0, 1)])
        b = near[np.argmax(loge[ti, near, k], axis=0), np.arange(len(b))]
    inner_f, inner_b = (k > 0) & (k < n_f - 1), (b > 0) & (b < n_b - 1)
    kf, bb = np.clip(k, 1, n_f - 2), np.clip(b, 1, n_b - 2)
    df = np.where(inner_f, _vertex(loge[ti, b, kf - 1], loge[ti, b, kf], loge[ti, b, kf + 1]), 0.0)
    db = np.where(inner_b, _vertex(loge[ti, bb - 1, k], loge[ti, bb, k], loge[ti, bb + 1, k]), 0.0)
    bin_hz = float(gram.freqs_hz[1] - gram.freqs_hz[0])
    step_deg = float(gram.cone_deg[1] - gram.cone_deg[0])
    return replace(d, frequency_hz=np.asarray(d.frequency_hz, float) + df * bin_hz,
                   cone_deg=np.clip(gram.cone_deg[b] + db * step_deg, 0.0, 180.0))


#: a reference bin this far below the background is outside the recording's band (its empty bins read ~1e-21 of
#: the noise on a 64 x 0.5 m array recorded to 1000 Hz), not background: integrated noise never falls 30 dB below
#: its mean (Gamma(16, 1/16) < 1e-3 with probability ~1e-60)
DEAD_BIN_DB = -30.0


def _live_background(power: np.ndarray, ti: np.ndarray, b: np.ndarray, k: np.ndarray, mu: np.ndarray,
                     settings: LofarSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Background of the gram's cells (``ti``, ``b``, ``k``) over their split-window reference bins in the band, left
    out the dead ones (below ``DEAD_BIN_DB`` of ``mu``) and, as the two-pass normaliser does, those over ``censor``
    x ``mu``: (mean, count, whether any was dead)."""
    reach = np.arange(settings.gap_bins + 1, settings.gap_bins + 1 + settings.reference_bins)
    idx = k[:, None] + np.concatenate([-reach, reach])[None, :]
    inside = (idx >= 0) & (idx < power.shape[2])
    p = np.asarray(power[ti[:, None], b[:, None], np.clip(idx, 0, power.shape[2] - 1)], float)  # (n, 2 R)
    dead = inside & (p < 10.0 ** (DEAD_BIN_DB / 10.0) * mu[:, None])
    use = inside & ~dead & (p <= settings.censor * mu[:, None])
    n = use.sum(axis=1)
    return np.where(use, p, 0.0).sum(axis=1) / np.maximum(n, 1), n, dead.any(axis=1)


def off_band_edges(gram: LofarGram, d: LineDetections, settings: LofarSettings) -> LineDetections:
    """The detections less those the edge of the recording's band made (module doc, item 1).

    The split-window background mu is the mean of the reference bins on both sides of the bin tested. A recording
    band-limited inside the LOFAR band (64 x 0.5 m: noise to 1000 Hz in a 375-1500 Hz band; 8 x 5 m: from
    50 Hz in a 37.5-150 Hz band) leaves empty bins on one side of the cells near the band's edge, which lower mu
    and raise z = P / mu: within 18 bins of the edge, 0.3-30 % of the cells crossed the threshold instead of pfa,
    and the lines there became narrowband targets following no ship. Such a cell is tested again against the mean
    of its live reference bins, n of them, at the threshold for n (the F(2 L, 2 L n) quantile at pfa, acoustics/
    lofar.py :func:`line_threshold`); a cell with no dead reference bin is left as it is.

    Parameters
    ----------
    gram : LofarGram
        The integrated gram.
    d : LineDetections
        Its line detections (on the gram's cells).
    settings : LofarSettings
        Integration L, gap and reference bins, censoring, pfa.

    Returns
    -------
    LineDetections
        The detections kept.
    """
    if not len(d):
        return d
    ti = np.searchsorted(gram.time_s, d.time_s)
    k = np.clip(np.searchsorted(gram.freqs_hz, np.asarray(d.frequency_hz, float) - 1e-9), 0, len(gram.freqs_hz) - 1)
    b = np.asarray(d.beam, np.int64)
    p = np.asarray(gram.power[ti, b, k], float)
    mu, n, dead = _live_background(gram.power, ti, b, k, p / np.maximum(np.asarray(d.statistic, float), 1e-12),
                                   settings)
    threshold = line_threshold(settings, np.maximum(n, 1))
    keep = ~dead | ((n > 0) & (p >= threshold * mu))
    return LineDetections(*(np.asarray(a)[keep] for a in (d.time_s, d.cone_deg, d.frequency_hz, d.statistic,
                                                            d.snr_db, d.beam)))


def narrowband_lines(gram: LofarGram | None, stages: PassiveStages) -> NarrowbandLines:
    """Lines of the gram, refined, tracked and grouped into sources (module doc, item 1).

    Parameters
    ----------
    gram : LofarGram or None
        The gram (None: no integration period in the recording).
    stages : PassiveStages
        The chain's settings (``[narrowband]``).

    Returns
    -------
    NarrowbandLines
        The gram, the confirmed line tracks and their sources.
    """
    from sonartrack.acoustics.lofar import detect_lines
    from sonartrack.tracking.line_tracks import group_sources, track_lines

    if gram is None:
        return NarrowbandLines(None, (), ())
    cfg = stages.settings.narrowband
    d = detect_lines(gram, cfg)
    if cfg.mftd:  # track-before-detect per line: the periods the single-period threshold missed
        from sonartrack.systems.passive.line_mftd import with_line_mftd

        m = cfg.line_mftd
        d, _ = with_line_mftd(gram, d, cfg, m.pfa, m, m.band_bins, m.near_beams, m.min_detections)
    d = refined_detections(gram, off_band_edges(gram, d, cfg))
    tracker = cfg.line_tracker.build()
    lines = track_lines(d.time_s, d.frequency_hz, d.cone_deg, d.snr_db, tracker)
    return NarrowbandLines(gram, tuple(lines), tuple(group_sources(lines, tracker)))


def source_history(source: LineSource, lines: dict[int, LineTrack], min_snr_db: float = -np.inf
                   ) -> tuple[np.ndarray, np.ndarray]:
    """A source's measured bearing: its strongest line's refined cone angle at each period it was detected at least
    ``min_snr_db`` over the background (a weaker line, often a lower one with a wider beam, would only add error).

    Parameters
    ----------
    source : LineSource
        The source.
    lines : dict of int to LineTrack
        Line tracks by id.
    min_snr_db : float
        Weakest detection kept (dB).

    Returns
    -------
    time_s, cone_deg : ndarray (n,)
        Period centres (s) and cone angles (deg), in time order.
    """
    top = strongest_line(source, lines)
    on = top.detected & (np.nan_to_num(top.snr_db, nan=-np.inf) >= min_snr_db)
    return top.time_s[on], top.measured_cone_deg[on]


def strongest_line(source: LineSource, lines: dict[int, LineTrack]) -> LineTrack:
    """The source's line of highest mean SNR (its tonal).

    Parameters
    ----------
    source : LineSource
        The source.
    lines : dict of int to LineTrack
        Line tracks by id.

    Returns
    -------
    LineTrack
        The line.
    """
    return max((lines[i] for i in source.track_ids), key=lambda ln: float(np.nanmean(ln.snr_db)))


def line_tonal(line: LineTrack, time_s: np.ndarray, stages: PassiveStages) -> TonalTrack:
    """A line track as a target's tonal (:func:`tonal_at` of its detections).

    Parameters
    ----------
    line : LineTrack
        The line.
    time_s : ndarray (n,)
        The target's record times (s), increasing.
    stages : PassiveStages
        The chain's settings.

    Returns
    -------
    TonalTrack
        The tonal.
    """
    on = line.detected
    return tonal_at(line.time_s[on], line.measured_frequency_hz[on], line.snr_db[on], time_s, stages)


def tonal_at(period_s: np.ndarray, frequency_hz: np.ndarray, snr_db: np.ndarray, time_s: np.ndarray,
             stages: PassiveStages) -> TonalTrack:
    """Line measurements as a target's tonal: one frequency per period, stamped at the record time nearest the
    period's centre (within half a period; one measurement per period, as measured); the line's frequency and SNR
    their means, the frequency noise from the estimates (acoustics/tonal.py :func:`frequency_sigma_hz`, outliers
    left out).

    Parameters
    ----------
    period_s, frequency_hz, snr_db : ndarray (p,)
        The line's detections: period centres (s), refined frequencies (Hz), SNR (dB).
    time_s : ndarray (n,)
        The target's record times (s), increasing.
    stages : PassiveStages
        ``tonal`` (the frequency noise estimator's settings) and the period (``[narrowband] integration`` windows).

    Returns
    -------
    TonalTrack
        The tonal.
    """
    half = 0.5 * stages.settings.narrowband.integration * stages.settings.window_s
    t, tp = np.asarray(time_s, float), np.asarray(period_s, float)
    j = np.clip(np.searchsorted(t, tp), 0, len(t) - 1)
    prev = np.clip(j - 1, 0, len(t) - 1)
    j = np.where(np.abs(t[prev] - tp) <= np.abs(t[j] - tp), prev, j)
    ok = np.abs(t[j] - tp) <= half
    times, first = np.unique(t[j[ok]], return_index=True)
    sigma, f = frequency_sigma_hz(np.asarray(frequency_hz, float)[ok][first], stages.tonal)
    snr = float(10.0 * np.log10(np.mean(10.0 ** (np.asarray(snr_db, float) / 10.0))))
    return TonalTrack(float(np.nanmean(frequency_hz)), snr, times, f, sigma)


def _follows(time_s, cone_deg, m: TrackMeasurements, tol_deg: float, min_overlap: int) -> float:
    """RMS cone-angle difference (deg) between a source's history and a bearing track over their common span, or
    inf when they share fewer than ``min_overlap`` periods or differ by more than ``tol_deg``."""
    tt, tc = np.asarray(m.track_time_s, float), np.asarray(m.track_cone_deg, float)
    if len(tt) < 2:
        return np.inf
    common = (time_s >= tt[0]) & (time_s <= tt[-1])
    if common.sum() < min_overlap:
        return np.inf
    rms = float(np.sqrt(np.mean((cone_deg[common] - np.interp(time_s[common], tt, tc)) ** 2)))
    return rms if rms <= tol_deg else np.inf


def source_roles(nb: NarrowbandLines, tracks: list[TrackMeasurements], tonals: list[TonalTrack | None],
                 stages: PassiveStages) -> SourceRoles:
    """Which bearing track each source follows, and which unexplained sources repeat an explained line's frequency
    (module doc, item 2).

    Parameters
    ----------
    nb : NarrowbandLines
        The lines and sources.
    tracks : list of TrackMeasurements
        The chain's bearing tracks long enough for TMA.
    tonals : list of (TonalTrack or None)
        Their tonals from their own beams.
    stages : PassiveStages
        ``[narrowband]`` (``match_beamwidths``, ``same_line_hz``, the line tracker's ``min_overlap``) and the array.

    Returns
    -------
    SourceRoles
        Source id -> track index, and source id -> the frequency (Hz) it leaks from.
    """
    cfg = stages.settings.narrowband
    lines = {ln.track_id: ln for ln in nb.lines}
    follows: dict[int, int] = {}
    for src in nb.sources:
        t, c = source_history(src, lines)
        tol = cfg.match_beamwidths * stages.array.beamwidth_deg(strongest_line(src, lines).mean_frequency_hz)
        rms = [_follows(t, c, m, tol, cfg.line_tracker.min_overlap) for m in tracks]
        if rms and np.isfinite(min(rms)):
            follows[src.source_id] = int(np.argmin(rms))
    claimed = [tn.line_hz for tn in tonals if tn is not None]
    claimed += [lines[i].mean_frequency_hz for s in nb.sources if s.source_id in follows for i in s.track_ids]
    leak = {}
    for src in nb.sources:
        if src.source_id in follows:
            continue
        f = [lines[i].mean_frequency_hz for i in src.track_ids]
        near = [g for g in claimed if min(abs(g - x) for x in f) <= cfg.same_line_hz]
        if near:
            leak[src.source_id] = float(near[0])
    return SourceRoles(follows, leak)


def tonals_from_lines(nb: NarrowbandLines, roles: SourceRoles, tracks: list[TrackMeasurements],
                      tonals: list[TonalTrack | None], stages: PassiveStages) -> list[TonalTrack | None]:
    """Each bearing track's tonal: its own beam's, else that of the strongest line of a source that follows it.

    Parameters
    ----------
    nb : NarrowbandLines
        The lines and sources.
    roles : SourceRoles
        :func:`source_roles`.
    tracks : list of TrackMeasurements
        The bearing tracks.
    tonals : list of (TonalTrack or None)
        Their tonals from their own beams (tonal_pass.py).
    stages : PassiveStages
        The chain's settings.

    Returns
    -------
    list of (TonalTrack or None)
        The tonals, gaps filled where a source follows the track.
    """
    lines = {ln.track_id: ln for ln in nb.lines}
    out = list(tonals)
    for src in nb.sources:
        i = roles.track.get(src.source_id)
        if i is not None and out[i] is None:
            out[i] = line_tonal(strongest_line(src, lines), np.asarray(tracks[i].time_s, float), stages)
    return out


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
    nb : NarrowbandLines
        The lines and sources.
    roles : SourceRoles
        :func:`source_roles`.
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
