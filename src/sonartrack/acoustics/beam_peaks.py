"""Peaks of a bearing-time record's window: the level normalised across bearing (median and MAD) and its maxima."""

from __future__ import annotations

import numpy as np

from sonartrack.acoustics.beamformer_settings import BeamformerSettings

#: MAD of a Gaussian sample = 0.6745 sigma, so 1.4826 MAD estimates sigma
MAD_TO_SIGMA = 1.4826


def normalise_across_bearing(power: np.ndarray, settings: BeamformerSettings) -> np.ndarray:
    """Detection statistic z = (P - median_b P) / max(1.4826 MAD_b P, spread_floor |median_b P|), per window.

    Why median and MAD: the ships occupy a few beams of the grid, so the median across bearing is the noise
    background and the MAD its spread, both unmoved by the ships (breakdown point 50 %); a split-window (CFAR)
    normaliser would need a guard width matched to the beam width, which changes 20-fold across the band
    and with cone angle. z is invariant to the recording's scale and offset (any recording level works);
    for noise-only windows it is roughly standard normal at each beam (P sums ~2 n_bins chi-square terms).
    Works on (B,) or (K, B) (each row normalised alone).

    Where that breaks: loud ships near endfire, whose beams there are 1 / sin(theta) times wider in cone angle, lift
    more than half of the uniform cone-angle grid (two ships at 20-25 deg on 24 x 1.25 m), so the median and MAD are
    theirs and a weaker ship at z 6-7 over the true background is measured at 2-3. With ``censor_passes`` > 0 the
    median and MAD are measured again over the beams below the threshold, repeatedly (a censored estimate, as the
    LOFAR two-pass normaliser's, acoustics/lofar.py): noise alone, with no beam at the threshold, is normalised
    exactly as before; a row with fewer than a quarter of its beams below the threshold keeps its previous z.

    Parameters
    ----------
    power : numpy.ndarray
        (B,) or (K, B) beam powers (any linear unit), beams along the last axis.
    settings : BeamformerSettings
        Its ``spread_floor`` (dimensionless), ``threshold`` and ``censor_passes``.

    Returns
    -------
    numpy.ndarray
        z (dimensionless), same shape; 0 where the spread is 0.
    """
    p = np.asarray(power, dtype=float)
    z = _robust_z(p, p, settings.spread_floor)
    for _ in range(settings.censor_passes):
        keep = z < settings.threshold
        # at least a quarter of the beams stay in the background: a row mostly above threshold keeps its last z
        enough = keep.sum(axis=-1, keepdims=True) >= max(3, p.shape[-1] // 4)
        new = np.where(enough, _robust_z(p, np.where(keep | ~enough, p, np.nan), settings.spread_floor), z)
        if np.array_equal(new, z):
            break
        z = new
    return z


def _robust_z(p: np.ndarray, background: np.ndarray, spread_floor: float) -> np.ndarray:
    """(p - median) / max(1.4826 MAD, spread_floor |median|) with the median and MAD of ``background`` along the last
    axis (NaN: left out)."""
    median = np.median if background is p else np.nanmedian
    med = median(background, axis=-1, keepdims=True)
    spread = MAD_TO_SIGMA * median(np.abs(background - med), axis=-1, keepdims=True)
    spread = np.maximum(spread, spread_floor * np.abs(med))
    return np.divide(p - med, spread, out=np.zeros_like(p), where=spread > 0)


def pick_beam_peaks(z: np.ndarray, cone_deg: np.ndarray, settings: BeamformerSettings) -> tuple[np.ndarray, np.ndarray]:
    """(cone angle deg (k,), amplitude = z (k,)) of the local maxima of z at or above the threshold.

    The grid is mirrored at 0 and 180 deg (cos is even there), so a target at endfire is a local maximum;
    a parabola through the three beams around each maximum refines the angle (offset in (-0.5, 0.5) beams)
    and the height. At most ``max_peaks`` peaks, the highest, in increasing cone angle.

    Parameters
    ----------
    z : numpy.ndarray
        (B,) statistic of one window.
    cone_deg : numpy.ndarray
        (B,) the beams' cone angles (deg from the array's forward axis, 0 = ahead), uniform in 0..180.
    settings : BeamformerSettings
        Its ``threshold`` (on z) and ``max_peaks``.

    Returns
    -------
    cone_deg : numpy.ndarray
        (k,) refined cone angles (deg, within 0..180).
    amplitude : numpy.ndarray
        (k,) refined peak heights of z.
    """
    return pick_beam_peaks_rows(np.asarray(z, dtype=float)[None], cone_deg, settings)[0]


def pick_beam_peaks_rows(z: np.ndarray, cone_deg: np.ndarray, settings: BeamformerSettings
                         ) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`pick_beam_peaks` of each row of z (K, B), the K windows of a batch in one set of array operations:
    the same element-wise formulas (the same numbers), the ``max_peaks`` cut made per row where a row holds more.

    Parameters
    ----------
    z : numpy.ndarray
        (K, B) statistic of K windows.
    cone_deg : numpy.ndarray
        (B,) the beams' cone angles (deg), uniform in 0..180.
    settings : BeamformerSettings
        Its ``threshold`` and ``max_peaks``.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Per row, (cone angles deg (k,), amplitudes (k,)) as :func:`pick_beam_peaks` gives them.
    """
    z = np.asarray(z, dtype=float).reshape(-1, np.shape(z)[-1])
    padded = np.concatenate([z[:, 1:2], z, z[:, -2:-1]], axis=1)
    mid = padded[:, 1:-1]
    rows, idx = np.nonzero((mid > padded[:, :-2]) & (mid >= padded[:, 2:]) & (mid >= settings.threshold))
    y0, y1, y2 = padded[rows, idx], padded[rows, idx + 1], padded[rows, idx + 2]
    den = y0 - 2.0 * y1 + y2
    delta = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
    delta = np.clip(delta, -0.5, 0.5)
    height = y1 - 0.25 * (y0 - y2) * delta
    angle = np.clip(cone_deg[idx] + delta * (cone_deg[1] - cone_deg[0]), 0.0, 180.0)
    bounds = np.searchsorted(rows, np.arange(z.shape[0] + 1))
    out = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        ang, h = angle[a:b], height[a:b]
        if b - a > settings.max_peaks:
            keep = np.sort(np.argsort(-h, kind="stable")[: settings.max_peaks])
            ang, h = ang[keep], h[keep]
        out.append((ang, h))
    return out
