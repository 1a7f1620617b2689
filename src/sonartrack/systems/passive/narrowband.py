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
3. Narrowband targets: the sources no track explains, joined into targets and sent to TMA
   (systems/passive/narrowband_targets.py, :func:`narrowband_records`).
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
    """The line of highest mean SNR (its tonal) of ``source`` among ``lines`` (line tracks by id).

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


def __getattr__(name: str):
    """The narrowband targets' names, now in systems/passive/narrowband_targets.py, still importable from here
    (lazily: that module imports this one)."""
    if name in ("narrowband_records", "cv_fit_residuals_deg", "join_statistic", "without_outliers",
                "joined_fragments"):
        from sonartrack.systems.passive import narrowband_targets

        return getattr(narrowband_targets, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
