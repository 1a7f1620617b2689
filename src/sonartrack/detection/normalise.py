"""Frame normalisation: put a user's cell values on the noise model's scale (paper P1, eq. 8).

The detector's design SNR and its log-likelihood weights assume noise-only cells exponential with
mean 2 (eq. 8), whose median is 2 ln 2. A receiver's gain is arbitrary, so by default the frames are
scaled so that their median is 2 ln 2: the median is robust to a target occupying a few cells, and
after it the design SNR means what it says whatever the gain.

Heavy-tailed reverberation is put on the same scale by its law: the OS-CFAR statistic of K clutter is mapped onto
its law in exponential noise (:func:`k_to_exponential`) through a K shape fitted to its tail, per ping and beam group
(:func:`k_shape_from_exceedance`), or per delay band and beam group on counts pooled over pings
(:class:`DelayShapes`: the near, reverberation-limited delays are spikier than the far ones).
"""

from __future__ import annotations

import functools

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting
from sonartrack.models.swerling import NOISE_MEAN

#: the ways frames can be normalised: by their median, or left as given
NORMALISATIONS = ("median", "none")
#: median of a noise-only square-law cell, exponential with mean 2 (eq. 8): 2 ln 2
NOISE_MEDIAN = NOISE_MEAN * np.log(2.0)


def normalise_to_noise_median(frames) -> np.ndarray:
    """Scale frames so that their median is a noise cell's: ``y * (2 ln 2 / median(y))`` (paper P1, eq. 8).

    Parameters
    ----------
    frames : array_like
        Square-law cell values (any gain).

    Returns
    -------
    ndarray
        Scaled values, on the noise model's scale (noise mean 2).

    Raises
    ------
    InputError
        If the median is 0.
    """
    y = np.asarray(frames, dtype=float)
    med = float(np.median(y))
    require(med > 0, "the median cell value is 0: cannot normalise by it; set normalisation = 'none' and give "
                     "frames on the noise model's scale (noise mean 2)")
    return y * (NOISE_MEAN * np.log(2.0) / med)


def normalise_frames(frames, how: str = "median") -> np.ndarray:
    """Frames normalised ``how``: "median" (:func:`normalise_to_noise_median`) or "none" (as given).

    Parameters
    ----------
    frames : array_like
        Square-law cell values.
    how : {"median", "none"}, default "median"
        Normalisation.

    Returns
    -------
    ndarray of float
        The normalised frames.

    Raises
    ------
    InputError
        If ``how`` is unknown (or as :func:`normalise_to_noise_median`).
    """
    require(how in NORMALISATIONS, f"normalisation must be one of {NORMALISATIONS}, got '{how}'")
    return normalise_to_noise_median(frames) if how == "median" else np.asarray(frames, dtype=float)


#: the false-alarm level at which the K shape of a ping's statistic is measured (:func:`k_shape_from_exceedance`):
#: common enough that 1e5 cells give +-3 % on it, deep enough to see the tail
SHAPE_PFA = 1e-2


def k_shape_from_exceedance(statistic, n: int, k: int, pfa0: float = SHAPE_PFA) -> float:
    """The K shape nu whose OS-CFAR law gives the observed exceedance of the threshold for ``pfa0`` in exponential
    noise: solve P_K(s >= alpha_0; nu) = (share of cells with s >= alpha_0), alpha_0 = os_threshold(pfa0, N, k)
    (detection/cfar.py :func:`k_os_pfa`; infinity, i.e. exponential, when the share is no larger than pfa0).

    A moment estimate of nu (Watts 1987: <x^2> / <x>^2 = 2 (1 + 1 / nu)) is swayed by the few largest cells; this one
    fits the tail where the detector works, on the statistic the detector thresholds (its CFAR's own estimate
    included), and a few target cells among 1e5 barely move it.

    Parameters
    ----------
    statistic : array_like
        OS-normalised cells s (cells <= 0, blanked, are left out).
    n, k : int
        The CFAR's reference cells N and rank k.
    pfa0 : float
        The level of the fit.

    Returns
    -------
    float
        nu in 0.1 .. 100, or inf.
    """
    from sonartrack.detection.cfar import os_threshold

    s = np.asarray(statistic)
    s = s[s > 0]
    if s.size < 100 / pfa0:
        return float("inf")
    return k_shape_from_share(float(np.mean(s >= os_threshold(pfa0, n, k))), pfa0, n, k)


def k_shape_from_share(share: float, pfa0: float, n: int, k: int) -> float:
    """The K shape nu with P_K(s >= alpha_0; nu) = ``share``, alpha_0 = os_threshold(pfa0, N, k) (the solve of
    :func:`k_shape_from_exceedance`, from a share counted elsewhere: :class:`DelayShapes` pools counts over pings).

    Parameters
    ----------
    share : float
        Share of the cells with s >= alpha_0.
    pfa0 : float
        The level alpha_0 is set for in exponential noise.
    n, k : int
        The CFAR's reference cells N and rank k.

    Returns
    -------
    float
        nu in 0.1 .. 100, or inf when the share is no larger than pfa0 (exponential).
    """
    from sonartrack.detection.cfar import K_SHAPES

    if share <= pfa0:
        return float("inf")
    log_p = _exceedance_by_shape(float(pfa0), int(n), int(k))
    if np.log(share) >= log_p[0]:
        return K_SHAPES[0]
    return float(np.exp(np.interp(-np.log(share), -log_p, np.log(K_SHAPES))))


@functools.lru_cache(maxsize=64)
def _exceedance_by_shape(pfa0: float, n: int, k: int) -> np.ndarray:
    """ln P_K(s >= alpha_0; nu) over the tabulated shapes (detection/cfar.py K_SHAPES; falls as nu grows)."""
    from sonartrack.detection.cfar import K_SHAPES, k_os_log_pfa, os_threshold

    alpha0 = os_threshold(pfa0, n, k)
    return np.array([float(k_os_log_pfa(alpha0, v, n, k)) for v in K_SHAPES])


def k_to_exponential(statistic, nu: float, n: int, k: int) -> np.ndarray:
    """The statistic mapped so that in K clutter of shape nu it has the law it has in exponential noise:
    s' = a_exp(P_K(s; nu)), with P_K the OS-CFAR exceedance in K clutter (detection/cfar.py :func:`k_os_pfa`) and
    a_exp its inverse in exponential noise (Rohling's closed form), so that every threshold set for exponential
    noise (the single-ping closed form, the MFTD's calibration on noise) keeps its false-alarm rate in the clutter.
    Monotone: the order of the cells is kept; identity for nu = inf.

    Parameters
    ----------
    statistic : array_like
        OS-normalised cells s >= 0.
    nu : float
        K shape (inf: none).
    n, k : int
        The CFAR's reference cells N and rank k.

    Returns
    -------
    numpy.ndarray
        s' (float32), same shape.
    """
    s = np.asarray(statistic, np.float32)
    if not np.isfinite(nu):
        return s
    log_grid, log_mapped = _exponential_map(float(nu), int(n), int(k))
    out = np.interp(np.log(np.maximum(s, 1e-30)), log_grid, log_mapped)
    return np.where(s > np.exp(log_grid[0]), np.exp(out), s * np.exp(log_mapped[0] - log_grid[0])).astype(np.float32)


@functools.lru_cache(maxsize=512)
def _exponential_map(nu: float, n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(ln s grid, ln a_exp(P_K(s; nu))) of :func:`k_to_exponential`, memoised per shape (:class:`DelayShapes`
    quantises its shapes so that tiles share them)."""
    from sonartrack.detection.cfar import k_os_log_pfa, os_pfa

    grid = np.exp(np.linspace(np.log(0.5), np.log(1e5), 600))
    log_pk = k_os_log_pfa(grid, nu, n, k)  # ln P_K(s >= grid), falling
    log_pe = np.log(np.maximum(os_pfa(grid, n, k), 1e-300))  # ln P_exp(s >= grid), falling
    mapped = np.interp(-log_pk, -log_pe, grid)  # the exponential threshold of the same exceedance
    return np.log(grid), np.log(mapped)


#: delay bands of the K shape's fit (:func:`k_map_by_delay`): each spans delays t .. DELAY_BAND_RATIO t
DELAY_BAND_RATIO = 1.5


def delay_bands(delay_s, n_beams: int, min_cells: int, ratio: float = DELAY_BAND_RATIO) -> list[slice]:
    """Adjacent delay cells in bands each spanning t .. ``ratio`` t (t its first delay), widened until the band holds
    at least ``min_cells`` cells over ``n_beams`` beams; a last band too small is joined to the one before.

    Parameters
    ----------
    delay_s : array_like (D,)
        Delays of the cells (s), increasing, > 0.
    n_beams : int
        Beams across which a band's cells are counted.
    min_cells : int
        Cells a band must hold.
    ratio : float
        Last over first delay of a band (> 1).

    Returns
    -------
    list of slice
        Bands covering 0 .. D once, in order.
    """
    t = np.asarray(delay_s, float)
    least = max(int(np.ceil(min_cells / max(n_beams, 1))), 1)
    edges, start = [0], 0
    while start < t.size:
        end = max(int(np.searchsorted(t, t[start] * ratio, side="left")), start + least)
        if t.size - end < least:
            end = t.size
        edges.append(end)
        start = end
    return [slice(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def k_map_by_delay(stat, n: int, k: int, min_cells: int | None, delay_s=None,
                   ratio: float = DELAY_BAND_RATIO) -> tuple[np.ndarray, np.ndarray]:
    """The OS-normalised statistic (B, J, D) mapped onto its law in exponential noise (:func:`k_to_exponential`)
    through a K shape fitted (:func:`k_shape_from_exceedance`) per Doppler cell and TILE: delay bands of
    :func:`delay_bands`, each cut into groups of adjacent beams of at least ``min_cells`` cells (detection/cells.py
    ``shape_groups``).

    Why by delay: the K shape of a cell's intensity is not a property of the sea alone. A K intensity with additive
    noise of power ratio CNR to the clutter's mean has the law of K with a larger effective shape, the noise
    filling the troughs of the texture (Watts 1985, "Radar detection prediction in K-distributed sea clutter and
    thermal noise"; Ward, Tough & Watts, Sea Clutter, sec. 7.3: K + noise), and the number of scatterers per cell and
    the mix of populations (Abraham & Lyons 2002, "Novel physical interpretations of K-distributed reverberation":
    nu = number of scatterers per cell x their own shape) change with range. Reverberation falls ~30-40 dB a decade
    of delay while the noise does not, so near delays are reverberation-limited and spiky, far ones noise-limited
    and exponential: one shape for a beam's whole window is the far delays' (most of the cells), and the near
    delays keep their K tail. Measured on study active-chain trial 14 (LFM, K, 32 x 1 m at 1 kHz), 20
    reverberation-only pings (benchmarks/bench_near_pfa.py): with one shape per beam group the cells at 2-6 s reach
    the threshold of Pfa 1e-4 13-15 times as often as stated, those beyond 20 s 0.3 times.

    Parameters
    ----------
    stat : array_like (B, J, D)
        s = y / mu (OS-CFAR, N reference cells, rank k) of the searched cells; cells <= 0 are left out of the fits.
    n, k : int
        The CFAR's N and k.
    min_cells : int or None
        Cells a tile holds at least (>= 100 / SHAPE_PFA for a fit); None: one tile per delay band over all beams.
    delay_s : array_like (D,), optional
        The cells' delays (s, > 0); None: one band (the shape per beam group only).
    ratio : float
        A band's last over first delay.

    Returns
    -------
    tuple
        (mapped statistic (B, J, D) float32, the K shape of each cell (B, J, D) float32; inf: exponential).
    """
    from sonartrack.detection.cells import shape_groups

    s = np.asarray(stat, np.float32)
    n_b, n_j, n_d = s.shape
    floor = int(np.ceil(100 / SHAPE_PFA))
    cells = floor if min_cells is None else max(int(min_cells), floor)
    bands = [slice(0, n_d)] if delay_s is None else delay_bands(delay_s, n_b, cells, ratio)
    out = np.array(s, copy=True)
    shapes = np.full(s.shape, np.inf, np.float32)
    for band in bands:
        width = band.stop - band.start
        for group in shape_groups(n_b, width, None if min_cells is None else cells):
            for j in range(n_j):
                tile = s[group, j, band]
                nu = k_shape_from_exceedance(tile, n, k)
                out[group, j, band] = k_to_exponential(tile, nu, n, k)
                shapes[group, j, band] = nu
    return out, shapes


class DelayShapeSettings(Settings):
    """The reverberation's K shape fitted by delay band and beam group, pooled over pings (:class:`DelayShapes`)."""

    tile_cells: int = setting(1000, "cells of one ping in a tile of the fit (adjacent beams x a delay band); the fit "
                                    "pools the tile's counts over `pings` pings", unit="1", ge=100, le=1_000_000)
    band_ratio: float = setting(1.5, "a delay band spans t .. this x t: the reverberation-to-noise ratio, and with it "
                                     "the K shape, changes by ~5 dB across it", unit="1", gt=1, le=100)
    pings: int = setting(20, "pings whose exceedance counts are pooled per tile (the ship moves ~80 m a ping: the sea "
                             "changes slowly against 20 pings)", unit="1", ge=1, le=1000)
    censor_pfa: float = setting(1e-6, "cells near an echo whose mapped statistic reaches the threshold of this Pfa are "
                                      "left out of the counts (DelayShapes._near_strong)", unit="1", gt=0, lt=1e-2)
    censor_cells: int = setting(8, "... within one beam and this many delay cells of it", unit="1", ge=0, le=1000)


class DelayShapes:
    """The OS-normalised statistic of each ping mapped onto its law in exponential noise (:func:`k_to_exponential`)
    through a K shape per Doppler cell and tile (a delay band x a group of adjacent beams, :func:`delay_tiles`), fitted
    to the share of the tile's cells above the level ``alpha_0`` in the pings BEFORE it, up to ``pings`` of them,
    together (:func:`k_shape_from_share` on pooled counts). The level is the deepest of :data:`SHAPE_LEVELS` the pooled
    cells measure (at least 100 of them expected above it in exponential noise; in the warm-up 30 at the first
    level, :data:`WARM_UP_EXCEEDANCES`); a tile with too few pooled cells takes its band's fit over all beams, and
    where that is short too (the first ping) this ping's own fit by beam group (:func:`k_map_by_delay` without
    bands): the first ~3 pings are the warm-up. After the map the ping's counts
    join the pool, censored: the footprint of an echo the map leaves above the threshold of ``censor_pfa`` is left
    out (a target that stays in a 1000-cell tile for 20 pings puts ~10 cells a ping above the level of 1e-2, as many
    as the clutter does: tests/detection/test_delay_shapes.py, a 30 dB echo over 3 beams x 8 cells makes its tile's
    fitted nu 2.3 uncensored against 3.3 censored and elsewhere).

    Why pooled over pings: the shape varies by delay (:func:`k_map_by_delay`) AND across beams by a factor of 10
    (trial 14: nu ~0.8 in the narrow broadside beams, ~8 near endfire at the same delay), so a tile must be narrow in
    both, and one ping's narrow tile holds ~1000 cells: 10 above the level of 1e-2. The counts are two integers per
    tile and level, kept per ping.

    Parameters
    ----------
    n, k : int
        The CFAR's N and rank k.
    settings : DelayShapeSettings
        Tile size, band ratio, pings pooled.
    """

    def __init__(self, n: int, k: int, settings: DelayShapeSettings | None = None):
        from collections import deque

        from sonartrack.detection.cfar import os_threshold

        self.n, self.k, self.settings = int(n), int(k), settings or DelayShapeSettings()
        self.alphas = np.array([os_threshold(p, n, k) for p in SHAPE_LEVELS])
        self.censor_alpha = os_threshold(self.settings.censor_pfa, n, k)
        self.counts: deque = deque(maxlen=self.settings.pings)
        self._axis: tuple | None = None
        self.tiles: list[tuple[slice, slice]] = []

    def _tiles_for(self, n_beams: int, delay_s: np.ndarray) -> None:
        """The tiles of this axis (the pooled counts restart when the cells' axes change)."""
        key = (n_beams, delay_s.size, float(delay_s[0]), float(delay_s[-1]))
        if key != self._axis:
            self._axis, self.counts = key, type(self.counts)(maxlen=self.settings.pings)
            self.tiles = delay_tiles(n_beams, delay_s, self.settings.tile_cells, self.settings.band_ratio)

    def push(self, stat, delay_s, fallback_cells: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Add one ping's statistic and return it mapped, with the shape of each cell.

        Parameters
        ----------
        stat : array_like (B, J, D)
            s = y / mu of the ping's cells (0 where not searched: left out of the counts, left 0).
        delay_s : array_like (D,)
            The cells' delays (s, > 0, increasing; the same for every ping, else the pooling restarts).
        fallback_cells : int, optional
            Beam groups of the fallback fit of this ping alone (cells.py ``heavy_tail_cells``; None: all beams).

        Returns
        -------
        tuple
            (mapped statistic (B, J, D) float32, K shape of each cell (B, J, D) float32; inf: exponential).
        """
        s = np.asarray(stat, np.float32)
        self._tiles_for(s.shape[0], np.asarray(delay_s, float))
        empty = np.zeros((len(self.tiles), s.shape[1], len(self.alphas) + 1), np.int64)
        out, shapes = self._mapped(s, np.sum(self.counts, axis=0) if self.counts else empty, fallback_cells)
        self.counts.append(self._counted(s, ~self._near_strong(out)))
        return out, shapes

    def _counted(self, s: np.ndarray, keep: np.ndarray) -> np.ndarray:
        """(tiles, J, 1 + levels): each tile's cells kept (s > 0) and of them those at or above each level."""
        now = np.zeros((len(self.tiles), s.shape[1], len(self.alphas) + 1), np.int64)
        for t, (beams, band) in enumerate(self.tiles):
            x = np.where(keep[beams, :, band], s[beams, :, band], 0.0)
            now[t, :, 0] = np.sum(x > 0, axis=(0, 2))
            now[t, :, 1:] = np.sum(x[..., None] >= self.alphas, axis=(0, 2))
        return now

    def _near_strong(self, mapped: np.ndarray) -> np.ndarray:
        """Cells within one beam and ``censor_cells`` delays of a cell whose mapped statistic reaches the threshold of
        ``censor_pfa``: an echo's footprint, left out of the counts (a target that stays in a tile for the pooled
        pings would be counted as the clutter's tail and make the map hide it; OS-CFAR's rank leaves the largest
        references out for the same reason)."""
        from scipy.ndimage import maximum_filter

        c = self.settings.censor_cells
        return maximum_filter(mapped >= self.censor_alpha, size=(3, 1, 2 * c + 1), mode="constant")

    def _mapped(self, s: np.ndarray, pooled: np.ndarray, fallback_cells: int | None):
        """s mapped by the shapes of the pooled counts: a tile's own, else its band's over all beams, else this
        ping's own fit by beam group (:func:`k_map_by_delay`)."""
        shape = np.array([[self._shape(pooled[t, j]) for j in range(s.shape[1])] for t in range(len(self.tiles))])
        for start in sorted({b.start for _, b in self.tiles}):
            rows = [t for t, (_, b) in enumerate(self.tiles) if b.start == start]
            for j in range(s.shape[1]):
                whole = self._shape(pooled[rows, j].sum(axis=0))
                shape[rows, j] = np.where(np.isnan(shape[rows, j]), whole, shape[rows, j])
        if np.isnan(shape).any():
            out, shapes = k_map_by_delay(s, self.n, self.k, fallback_cells)
        else:
            out, shapes = np.array(s, copy=True), np.full(s.shape, np.inf, np.float32)
        for t, (beams, band) in enumerate(self.tiles):
            for j in np.nonzero(~np.isnan(shape[t]))[0]:
                nu = quantised_shape(shape[t, j])
                out[beams, j, band] = k_to_exponential(s[beams, j, band], nu, self.n, self.k)
                shapes[beams, j, band] = nu
        return out, shapes

    def _shape(self, counts: np.ndarray) -> float:
        """nu from one tile's pooled counts [cells, above each level] at the deepest level they measure; NaN when
        they measure none."""
        size = counts[0]
        usable = [m for m, p in enumerate(SHAPE_LEVELS) if size * p >= 100]
        if not usable and size * SHAPE_LEVELS[0] < WARM_UP_EXCEEDANCES:
            return float("nan")
        m = usable[-1] if usable else 0
        return k_shape_from_share(counts[m + 1] / size, SHAPE_LEVELS[m], self.n, self.k)


def quantised_shape(nu: float) -> float:
    """nu rounded to 1/20 of a natural-log unit (5 %, well inside a fit's scatter), so that tiles share the memoised
    maps of :func:`k_to_exponential`; inf and shapes above the tabulation (100) stay as they are."""
    if not np.isfinite(nu) or nu >= 100.0:
        return float(nu)
    return float(np.exp(np.round(20.0 * np.log(nu)) / 20.0))


#: a tile's own fit at the first level from this many expected exceedances on (its share then within ~+-35 % at
#: 95 %): in the warm-up a rough fit of its own beats its band's over all beams, which mixes narrow spiky beams with
#: wide ones (study active-chain trial 14, 1 h twin: a false mirror pair confirmed at 2.5 s delay on pings 11-19 with
#: the band's fit until 100)
WARM_UP_EXCEEDANCES = 30

#: the levels (Pfa in exponential noise) at which :class:`DelayShapes` may fit: the deepest its pooled cells measure
SHAPE_LEVELS = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)


def delay_tiles(n_beams: int, delay_s, tile_cells: int, ratio: float = DELAY_BAND_RATIO) -> list[tuple[slice, slice]]:
    """(beams, delays) tiles covering a ping's cells once: :func:`delay_bands` over all beams, each band cut into
    groups of adjacent beams of at least ``tile_cells`` cells (detection/cells.py ``shape_groups``).

    Parameters
    ----------
    n_beams : int
        Beams B.
    delay_s : array_like (D,)
        Delays of the cells (s, > 0, increasing).
    tile_cells : int
        Cells a tile holds at least.
    ratio : float
        A band's last over first delay.

    Returns
    -------
    list of (slice, slice)
        (beam slice, delay slice) of each tile.
    """
    from sonartrack.detection.cells import shape_groups

    out = []
    for band in delay_bands(delay_s, n_beams, tile_cells, ratio):
        out += [(g, band) for g in shape_groups(n_beams, band.stop - band.start, tile_cells)]
    return out
