"""Track-before-detect per narrowband line: paper P1's MFTD over each frequency bin's bearing-time record.

A line's cells at one frequency bin k across beams and periods, ``gram.statistic[:, :, k]`` (rows = integration
periods, columns = beams), form a bearing-time record of their own; detection/btr_mftd.py runs P1's pruned MFTD
(Im & Kim 1996, eqs. 9-10, 16-22, Kalman track prior in cone angle and cone-angle rate) over it, its threshold
calibrated by Monte Carlo for ``pfa`` false detections per beam and period.

Cell statistic. In noise the LOFAR statistic z = P / mu is the ratio of a Gamma(L, 1/L) to the mean of R such
variables, F-distributed with (2L, 2LR) degrees of freedom (acoustics/lofar.py, module doc; the line threshold
uses the same law for its normalisers). The detector's Gaussian cell model wants z ~ N(0, 1) in noise, so each cell
is mapped through that law's probability integral transform,

    g = Phi^-1(F_{2L, 2LR}(z)) = -Phi^-1(1 - F_{2L, 2LR}(z))    (computed on the upper tail, exact far out),

N(0, 1) exactly for independent F cells; a line of bin SNR s raises z to ~(1 + s) and g by ~s sqrt(L) for large L
(Wilson-Hilferty), so the Gaussian kernel's mean-shift model applies. The beams of a real gram overlap (3 deg
steps, a beam ~9.5 deg wide at 200 Hz), so their cells are correlated and the false rate there is measured on
noise-only recordings, not assumed.

Which bins. Every bin would cost one MFTD per bin (hundreds); the MFTD runs on the bins of the band a line is in:
every bin with at least ``min_detections`` single-period detections within ``band_bins`` bins of it over the whole
recording, and more than noise alone gives there with probability ``BIN_ALPHA`` (Poisson, the line threshold's pfa
per cell): noise scatters single detections over the bins, a weak line repeats on its own. Its detections
at (period, cone, bin) that no single-period detection lies near (same period, within ``near_beams`` beams and one
bin) become extra line detections (statistic z of their cell), as the chain's broadband MFTD adds peaks the single
window missed.
"""

from __future__ import annotations

import numpy as np

from sonartrack.acoustics.lofar import LineDetections, LofarGram, LofarSettings
from sonartrack.detection.btr_mftd import BtrMftdSettings

#: largest |g| of a mapped cell: beyond it the F law's tail underflows (Phi^-1 of 1e-300 is 37; 8 is far beyond any
#: threshold of the detector and keeps a strong line's cells finite)
G_CLIP = 8.0
#: a bin band is searched when its count of single-period detections over the recording is this improbable under
#: noise alone (Poisson law of the line threshold's pfa; the beams' overlap makes real counts a little higher)
BIN_ALPHA = 1e-3


def gaussianised(z, settings: LofarSettings) -> np.ndarray:
    """LOFAR statistic z mapped to N(0, 1) in noise: g = -Phi^-1(1 - F_{2L,2LR}(z)) (module doc).

    Parameters
    ----------
    z : array_like
        Cells of the normalised gram (power over background, 1).
    settings : LofarSettings
        Integration L and reference bins (R = 2 ``reference_bins``), as :func:`acoustics.lofar.line_threshold`.

    Returns
    -------
    ndarray
        The mapped cells, same shape, clipped to +-``G_CLIP``.
    """
    from scipy.special import fdtrc, ndtri

    dof = 2.0 * settings.integration
    sf = fdtrc(dof, dof * 2 * settings.reference_bins, np.maximum(np.asarray(z, float), 0.0))
    with np.errstate(divide="ignore"):
        return np.clip(-ndtri(sf), -G_CLIP, G_CLIP)


def candidate_bins(n_bins: int, k: np.ndarray, band_bins: int, min_detections: int = 1) -> np.ndarray:
    """The bins with at least ``min_detections`` of the detections' bins ``k`` within ``band_bins`` of them, sorted.

    Parameters
    ----------
    n_bins : int
        Bins of the gram.
    k : int ndarray
        The single-period detections' bins.
    band_bins : int
        Half-width of the band around each.
    min_detections : int
        Fewest detections within the band of a candidate (noise alone puts single detections on scattered bins).

    Returns
    -------
    int ndarray
        The candidate bins.
    """
    count = np.bincount(np.asarray(k, np.int64), minlength=n_bins)[:n_bins]
    near = np.convolve(count, np.ones(2 * band_bins + 1, np.int64), mode="same")
    return np.nonzero(near >= max(min_detections, 1))[0]


def noise_count(cells: int, pfa: float) -> int:
    """Fewest single-period detections among ``cells`` cells that noise alone reaches with probability below
    ``BIN_ALPHA``: 1 + the Poisson(pfa cells) upper quantile.

    Parameters
    ----------
    cells : int
        Cells of a bin band over the recording (periods x beams x bins).
    pfa : float
        The single-period threshold's false-alarm probability per cell.

    Returns
    -------
    int
        The count.
    """
    from scipy.stats import poisson

    return int(poisson.isf(BIN_ALPHA, pfa * cells)) + 1


def line_mftd(gram: LofarGram, bins, lofar: LofarSettings, pfa: float, settings: BtrMftdSettings
              ) -> LineDetections:
    """P1's MFTD over the bearing-time record of each bin in ``bins`` (module doc).

    Parameters
    ----------
    gram : LofarGram
        The integrated, normalised gram (T periods, B beams, F bins).
    bins : int array_like
        The bins to search.
    lofar : LofarSettings
        The gram's integration and reference bins (the cells' F law).
    pfa : float
        False detections per beam and period the MFTD threshold is set for.
    settings : BtrMftdSettings
        The MFTD (its statistic must be "gaussian": the cells are mapped to N(0, 1)).

    Returns
    -------
    LineDetections
        One row per MFTD detection off the sidelobes (the line threshold's guard): period centre (s), cone angle
        (deg), the bin's frequency (Hz), z of the cell, SNR 10 log10(z - 1) dB, beam.
    """
    from sonartrack.core.errors import require
    from sonartrack.detection.btr_mftd import btr_mftd

    require(settings.statistic == "gaussian", "the line MFTD maps its cells to N(0, 1): set its statistic "
                                              "to \"gaussian\"")
    period_s = 2.0 * float(gram.time_s[0])  # period k is centred at (k + 1/2) L T
    rows = []
    for k in np.asarray(bins, np.int64):
        z = np.asarray(gram.statistic[:, :, k], float)
        d = btr_mftd(gaussianised(z, lofar), gram.cone_deg, period_s, pfa, settings)
        beam = np.searchsorted(gram.cone_deg, d.cone_deg - 1e-9)
        rows.append((np.asarray(d.window), beam, np.full(len(d), k)))
    t, b, k = (np.concatenate([r[j] for r in rows]).astype(np.int64) if rows else np.zeros(0, np.int64)
               for j in range(3))
    zz = np.asarray(gram.statistic, float)[t, b, k]
    main = _main_lobe(gram, t, b, k, lofar.sidelobe_guard_db)
    t, b, k, zz = t[main], b[main], k[main], zz[main]
    return LineDetections(gram.time_s[t], gram.cone_deg[b], gram.freqs_hz[k], zz,
                          10.0 * np.log10(np.maximum(zz - 1.0, 1e-6)), b)


def _main_lobe(gram: LofarGram, t, b, k, guard_db: float) -> np.ndarray:
    """Cells whose line power over the background P - mu = P (1 - 1 / z) is within ``guard_db`` of the largest over
    the beams at their bin and period (the single-period detector's sidelobe guard, acoustics/lofar.py)."""
    z = np.asarray(gram.statistic[t, :, k], float)  # (n, B)
    excess = np.asarray(gram.power[t, :, k], float) * (1.0 - 1.0 / np.maximum(z, 1e-12))
    return excess[np.arange(len(t)), b] >= excess.max(axis=1, initial=0.0) * 10.0 ** (-guard_db / 10.0)


def with_line_mftd(gram: LofarGram, d: LineDetections, lofar: LofarSettings, pfa: float, settings: BtrMftdSettings,
                   band_bins: int = 1, near_beams: int = 2, min_detections: int = 1
                   ) -> tuple[LineDetections, LineDetections]:
    """The single-period detections ``d`` with the line MFTD's detections that none of them lies near.

    Parameters
    ----------
    gram : LofarGram
        The gram.
    d : LineDetections
        Its single-period line detections (on the gram's grids).
    lofar, pfa, settings
        As :func:`line_mftd`.
    band_bins, min_detections : int
        The bins searched: those with at least ``min_detections`` detections within ``band_bins`` of them.
    near_beams : int
        An MFTD detection within this many beams and one bin of a single-period detection of its period is that
        detection's.

    Returns
    -------
    merged : LineDetections
        ``d`` followed by the added MFTD detections, in time order (stable).
    added : LineDetections
        The added detections alone.
    """
    f = np.asarray(gram.freqs_hz, float)
    kd = np.clip(np.searchsorted(f, np.asarray(d.frequency_hz, float) - 1e-9), 0, len(f) - 1)
    n_min = max(min_detections, noise_count(len(gram.time_s) * len(gram.cone_deg) * (2 * band_bins + 1), lofar.pfa))
    m = line_mftd(gram, candidate_bins(len(f), kd, band_bins, n_min), lofar, pfa, settings)
    km = np.searchsorted(f, np.asarray(m.frequency_hz, float) - 1e-9)
    near = np.array([np.any((d.time_s == t) & (np.abs(np.asarray(d.beam) - b) <= near_beams) & (np.abs(kd - k) <= 1))
                     for t, b, k in zip(m.time_s, m.beam, km, strict=True)], bool)
    added = _take(m, ~near)
    merged = LineDetections(*[np.concatenate([np.asarray(getattr(d, n)), np.asarray(getattr(added, n))])
                              for n in LineDetections.__slots__])
    return _take(merged, np.argsort(merged.time_s, kind="stable")), added


def _take(d: LineDetections, idx) -> LineDetections:
    return LineDetections(*[np.asarray(getattr(d, n))[idx] for n in LineDetections.__slots__])
