"""The ping MFTD's tiles and its threshold: the tile plan over travel time, the statistic per tile, and the
threshold calibrated on noise-only tiles drawn as the chain's own normaliser makes them (paper P1's detector run on
tiles of a ping stack; detection/ping_mftd.py uses these)."""

from __future__ import annotations

import functools

import numpy as np

from sonartrack.core.random import trial_rng
from sonartrack.detection.cfar import CfarSettings, cfar_normalise
from sonartrack.detection.mftd import MftdDetector
from sonartrack.detection.prior import prior_constant
from sonartrack.models.swerling import NOISE_MEAN

#: below this many expected noise exceedances the threshold comes from the fitted exponential tail
MIN_EMPIRICAL_EXCEEDANCES = 20
#: the tail fraction of the noise statistics the exponential excess is fitted to
TAIL_FRACTION = 0.05
#: noise-only trials drawn and decided at once by the calibration
CALIBRATION_CHUNK = 250


def tile_plan(n_time: int, tile_cells: int, margin: int) -> list[tuple[int, int, int, int]]:
    """(lo, hi, own_lo, own_hi) per tile: the tile covers cells [lo, hi), all of one length L = min(n, owned +
    2 margin) (tiles at the ends are shifted inwards), and owns [own_lo, own_hi); the owned ranges partition
    0..n_time.

    Parameters
    ----------
    n_time : int
        Number of travel-time cells.
    tile_cells : int
        Cells owned by each tile (the last may own fewer).
    margin : int
        Cells added on each side of the owned range.

    Returns
    -------
    list of tuple of int
        One (lo, hi, own_lo, own_hi) per tile, in order of ``own_lo``.
    """
    length = min(n_time, tile_cells + 2 * margin)
    out = []
    for own_lo in range(0, n_time, tile_cells):
        own_hi = min(own_lo + tile_cells, n_time)
        lo = int(np.clip(own_lo - margin, 0, n_time - length))
        out.append((lo, lo + length, own_lo, own_hi))
    return out


def tail_threshold(stats, pfa: float) -> float:
    """Threshold with P(S > t) = pfa from noise-only statistics: the empirical quantile (at most pfa n above it)
    when pfa n >= MIN_EMPIRICAL_EXCEEDANCES, else the exponential-excess tail fitted above the 95 % quantile
    (module doc).

    Parameters
    ----------
    stats : array (n,)
        Noise-only statistics S.
    pfa : float
        Wanted exceedance probability, in (0, 1).

    Returns
    -------
    float
        The threshold, on the scale of ``stats``.
    """
    s = np.sort(np.asarray(stats, float))
    n = len(s)
    if pfa * n >= MIN_EMPIRICAL_EXCEEDANCES:
        return float(s[n - 1 - int(np.floor(pfa * n))])
    u = float(np.quantile(s, 1.0 - TAIL_FRACTION))
    beta = float(np.mean(s[s > u] - u))
    return u + beta * np.log(TAIL_FRACTION / pfa)


def tile_statistics(detector: MftdDetector, stack, tiles, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """P1's statistic S and the best track's last cell (flat index inside the tile) of every beam and tile.

    Parameters
    ----------
    detector : MftdDetector
        The detector of one tile's plane (its grid has the tile's length); every tile has that length.
    stack : array (K, beams, travel-time, Doppler)
        The last K pings' cells on P1's noise scale (mean 2).
    tiles : int array (n, 4)
        (lo, hi, own_lo, own_hi) of each tile (:func:`tile_plan`).
    tol : float
        Tolerance of the restricted branching (``detection/mftd.py``).

    Returns
    -------
    tuple of arrays
        S (beams, n) and the last cell (beams, n) of each tile's best track.
    """
    from sonartrack.detection.mftd_kernel import pruned_kernel
    from sonartrack.detection.pruned import restriction_margin

    y = np.asarray(stack, dtype=float)
    K, g = y.shape[0], detector.grid
    prior = detector.prior(K)
    plane = (g.n_range, g.n_doppler, g.range_cell_m, g.range_rate_cell_mps, g.range_min_m, g.range_rate_min_mps)
    arrays = (prior.S_inv, prior.S_cov, prior.F, prior.L, prior.u, np.asarray(prior.w1, dtype=float))
    snr = detector.snr
    kernel, gain, margin, n_keep = pruned_kernel(), snr / (1.0 + snr), restriction_margin(g.n_cells, tol), \
        int(detector.settings.n_tracks)
    spans = np.asarray(tiles, np.int64)[:, :2]
    half = np.empty((y.shape[1], len(spans)))
    last = np.empty((y.shape[1], len(spans)), np.int64)
    # a loop of kernel calls, not one compiled loop around the kernel: numba cannot cache a function that calls
    # the kernel's closure, and compiling it anew costs seconds in every process
    for b in range(y.shape[1]):
        yb = y[:, b]
        for t, (lo, hi) in enumerate(spans):
            h, hist, _, _ = kernel(np.ascontiguousarray(yb[:, lo:hi].reshape(K, -1)), plane, arrays, gain, margin,
                                   n_keep, 1, True, False)
            half[b, t], last[b, t] = h, hist[0, K - 1]
    return half + prior_constant(prior, snr), last


def noise_tiles(rng: np.random.Generator, shape: tuple[int, int, int], pool: tuple[int, int],
                cfar) -> np.ndarray:
    """One noise-only tile (K, L, D) on P1's scale (mean 2): each cell the max over ``pool`` = (beams, delays) input
    cells; the input cells exponential (mean 1), normalised by ``cfar`` along the delay axis when given (with the
    CFAR's own reference cells around the tile, as in a ping), or, when ``cfar`` is a CW's noise estimate
    (detection/cw_cells.py :class:`CwEstimate`), each divided by its own draw of that estimate (the marginal law of
    the normalised cell; the estimates' correlation between neighbouring cells is left out), then doubled. For a
    CW the pooled cell is drawn directly from that law, the max of pool independent cells y / M by inverse transform
    (:meth:`CwEstimate.draw_statistic`: one uniform per pooled cell, not an exponential and three Beta order
    statistics per input cell; measured: the CW hour's calibration 25 -> 2-4 s of CPU).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the noise.
    shape : tuple of int
        (K frames, L travel-time cells, D Doppler cells) of the tile, after pooling.
    pool : tuple of int
        (beams, delays) pooled into each cell.
    cfar : CfarSettings, CwEstimate, or None
        The normaliser of the cells, or None for none.

    Returns
    -------
    numpy.ndarray
        (K, L, D) float noise statistic.
    """
    K, n_range, n_doppler = shape
    pb, pc = pool
    if cfar is not None and not isinstance(cfar, CfarSettings):  # the max of pb pc cells, each y / M, by its law
        return NOISE_MEAN * cfar.draw_statistic(rng, (K, n_range, n_doppler), pb * pc)
    n = n_range * pc
    half = cfar.guard_cells + cfar.reference_cells if isinstance(cfar, CfarSettings) else 0
    y = rng.exponential(1.0, (K, n_doppler, pb, n + 2 * half)).astype(np.float32)
    if isinstance(cfar, CfarSettings):
        y = cfar_normalise(y, cfar)[..., half: half + n]
    y = y.reshape(K, n_doppler, pb, n_range, pc).max(axis=(2, 4))
    return NOISE_MEAN * np.moveaxis(y, 1, -1).astype(float)


@functools.lru_cache(maxsize=32)
def _calibrated(detector: MftdDetector, shape: tuple[int, int, int], pfa: float, trials: int, seed: int,
                pool: tuple[int, int], tol: float, cfar) -> float:
    """Noise-only tiles (:func:`noise_tiles`) as the beams of one stack (trial i: beam i, from trial_rng(seed, i)),
    one tile each, ``CALIBRATION_CHUNK`` trials at a time (the memory of a few pings' cells, not of every trial)."""
    tile = np.array([[0, shape[1], 0, shape[1]]], np.int64)
    stats = []
    for lo in range(0, trials, CALIBRATION_CHUNK):
        y = np.stack([noise_tiles(trial_rng(seed, i), shape, pool, cfar)
                      for i in range(lo, min(lo + CALIBRATION_CHUNK, trials))], axis=1)
        stats.append(tile_statistics(detector, y, tile, tol)[0][:, 0])
    return tail_threshold(np.concatenate(stats), pfa)
