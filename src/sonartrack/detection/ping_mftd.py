"""Multi-frame track-before-detect across the pings of an active sonar, per beam (paper P1 run sliding).

Im & Kim 1996 (paper P1) decide whether a target is in a K-frame stack of range-Doppler cells
(``detection/mftd.py``: the N-best pruned detector, its Kalman track prior, eqs. 9, 10, 16-22). Here the
frames are the pings of an active sonar: after each ping, for each beam, the last K pings' planes of
travel-time x Doppler cells are one P1 stack, so a detection at ping k integrates the echoes of pings
k-K+1 .. k along tracks that move as a target can.

Plane (per beam). State w = [r_B, rdot_B]: the bistatic range r_B = c t (c the sound speed, t the travel
time of a cell) and its rate d r_B / dt (the range rate of the Doppler cells). Cells: dr = c dt_cell in
range, dv the Doppler cells' range-rate step; a waveform without a Doppler measurement (LFM pulse
compression: one Doppler cell) gets one range-rate cell covering +-``max_range_rate_mps``, so the prior's
quantisation covariance R = diag(dr^2, dv^2) / 12 (eq. 25) carries that ignorance. Motion: eqs. 23-24 with
T = the ping interval and sigma_a the target's bistatic-range acceleration; the ownship's own contribution u
(eq. 23) depends on the unknown target position and is left in sigma_a (u = 0).

Tiles. P1 tests one plane for one target: its N kept tracks all crowd round the strongest echo of the
plane. A beam holds many echoes (targets, reverberation), so its travel-time axis is cut into tiles, each a P1
test of its own: a tile owns ``tile_cells`` travel-time cells and reaches ``margin`` cells either side,
margin = ceil(max_range_rate (K-1) T / dr) + 1, so a target that ends in the owned cells was inside the tile
on all K pings. The tile decides S > lambda (S = log sum over kept tracks of c_theta LR_theta, the statistic
of ``detection/mftd.py``); a detection is the last cell of its best track, reported only if that cell is
one the tile owns (the neighbour owns the others). Detections of one echo in neighbouring beams are merged:
a detection is kept only if no detection of an adjacent beam within one travel-time cell is stronger.

Pooling. An LFM's delay cells are 1/f_s apart and its resolution is 1/B (two cells at the defaults), and the
beams are narrower apart than they are wide, so neighbouring cells are correlated; the MFTD runs on the max over
blocks of ``pool_beams`` x ``pool_cells`` cells (fewer, nearly independent cells, and a quarter of the work),
and a detection is reported at the input cell holding that max at the deciding ping.

Threshold (Monte Carlo: P1 gives no closed form for the pruned statistic's distribution). lambda is set so
that P(S > lambda | noise only) = pfa x (input cells of a tile: L x Doppler cells x the pooled block): a tile reports at
most one detection, in noise its best track ends in any of its cells alike, and it reports only the cells it
owns, so the false detections per input cell per ping are ``pfa``, the single-ping threshold's rate. It is the
empirical quantile of S over ``calibration_trials`` seeded noise-only tiles: input cells exponential (eq. 8),
normalised by the same CFAR as the pings' when it is given (its estimation noise gives the normalised statistic
a heavier tail than the exponential), a pooled cell the max of its block's independent ones (conservative: the
max of correlated cells has the lighter tail); where pfa_tile x trials < 20 the tail is extrapolated by peaks
over threshold: the top 5 % of the noise statistics are fitted by an exponential excess (a generalised Pareto
tail with shape 0), P(S > s) = 0.05 exp(-(s - u) / beta), beta the mean excess over u, the 95 % quantile.
The cells must be on the noise model's scale: ``noise_mean`` (the mean of a noise-only cell of the input; 1
for the CFAR-normalised statistic of ``detection/cells.py``) is scaled to P1's 2. Reverberation the CFAR leaves
heavier-tailed than exponential raises both detectors' false-alarm rates.

The first K - 1 pings are decided with the frames there are (thresholds calibrated for each k < K).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting
from sonartrack.detection.cells import Detections, PingCells
from sonartrack.detection.cfar import CfarSettings
from sonartrack.detection.mftd import MftdDetector, MftdSettings
from sonartrack.detection.mftd_tiles import (  # noqa: F401 - re-exported: the tiles' public names
    CALIBRATION_CHUNK,
    MIN_EMPIRICAL_EXCEEDANCES,
    TAIL_FRACTION,
    _calibrated,
    noise_tiles,
    tail_threshold,
    tile_plan,
    tile_statistics,
)
from sonartrack.models.range_doppler import RangeDopplerGrid
from sonartrack.models.swerling import NOISE_MEAN


class PingMftdSettings(Settings):
    """MFTD across pings (paper P1 run sliding per beam). The ping interval, the sound speed and the false-alarm
    rate are the system's (given to :class:`PingMftd`), not declared here."""

    frames: int = setting(4, "pings K integrated by one decision (P1's frames)", unit="1", ge=1, le=32)
    n_tracks: int = setting(10, "tracks N kept after each ping's pruning (P1, sec. IV). A tile holds ~300 pooled "
                                "cells and a track must be among the N best from its first frame, so a Swerling echo "
                                "that fades early in the window is lost: on synthetic cells (benchmarks/"
                                "mftd_gain_theory.py, K 4, +-15 m/s, pfa 1e-9) SNR50 10.8 dB at N 10, 9.8 at 30, 9.7 "
                                "at 100 (union bound 9.3); in the chain 30 gained within noise (bench_mftd_gain.py) "
                                "and gave the default LFM scene, seed 1, a false row (bench_active_rows.py): 10 kept",
                            unit="1", ge=1, le=10_000)
    snr_db: float = setting(8.0, "design SNR rho of a target cell (P1 eq. 7): a weak target's", unit="dB", ge=-20,
                            le=40)
    sigma_a_mps2: float = setting(0.02, "standard deviation of the bistatic range acceleration between pings (P1 "
                                        "eq. 23): target manoeuvres and the ownship's own motion", unit="m/s^2",
                                  gt=0, le=10)
    max_range_rate_mps: float = setting(15.0, "largest bistatic range rate of a target: sets the tile margin and the "
                                              "range-rate span when the waveform measures no Doppler", unit="m/s",
                                        gt=0, le=200)
    tile_cells: int = setting(128, "travel-time cells a tile owns (one P1 test per tile and beam)", unit="1", ge=1,
                              le=100_000)
    pool_cells: int = setting(2, "the MFTD runs on the max over runs of this many travel-time cells (an LFM's cells "
                                 "are 1/f_s apart, its resolution 1/B: 2 cells at the defaults); 1: every cell",
                              unit="1", ge=1, le=64)
    pool_beams: int = setting(2, "... and over runs of this many adjacent beams (the default 61 beams are 3 deg "
                                 "apart, the 16-element array's beams ~6 deg wide); 1: every beam", unit="1", ge=1,
                              le=16)
    restrict_tol: float = setting(1e-9, "branch only to cells whose prior weight is above this relative to the "
                                        "kept ones (P1's sum loses at most this fraction)", unit="1", gt=0, lt=1e-2)
    calibration_trials: int = setting(2000, "noise-only tiles simulated to calibrate the threshold", unit="1",
                                      ge=100, le=10_000_000)
    seed: int = setting(0, "seed of the calibration's noise-only tiles", unit="1")
    merge_beams: bool = setting(True, "keep a detection only if no adjacent beam has a stronger one within one "
                                      "travel-time cell", unit="1")


@dataclass(frozen=True, slots=True)
class CellAxes:
    """Axes of one ping's cells (beams x travel-time x Doppler): centres, uniform steps."""

    cone_deg: np.ndarray
    travel_time_s: np.ndarray
    doppler_hz: np.ndarray
    range_rate_mps: np.ndarray

    @property
    def shape(self) -> tuple[int, int, int]:
        """(beams, travel-time cells, Doppler cells) of every ping."""
        return len(self.cone_deg), len(self.travel_time_s), len(self.doppler_hz)

    @property
    def time_step_s(self) -> float:
        """The travel-time cell step (s)."""
        t = np.asarray(self.travel_time_s, float)
        return float(t[1] - t[0]) if len(t) > 1 else 1.0

    @property
    def doppler_measured(self) -> bool:
        """True when the cells carry range rates (a CW; an LFM measures none)."""
        return bool(np.all(np.isfinite(self.range_rate_mps)))

    @classmethod
    def of(cls, cells: PingCells) -> CellAxes:
        """The axes of a ping's :class:`~sonartrack.detection.cells.PingCells`.

        Parameters
        ----------
        cells : PingCells
            One ping's cells (cone angles deg from the array axis, delays s, Doppler Hz, range rates m/s).

        Returns
        -------
        CellAxes
            Those axes as float arrays (``travel_time_s`` from the cells' ``delay_s``).
        """
        return cls(np.asarray(cells.cone_deg, float), np.asarray(cells.delay_s, float),
                   np.asarray(cells.doppler_hz, float), np.asarray(cells.range_rate_mps, float))


def empty_detections() -> Detections:
    """A :class:`~sonartrack.detection.cells.Detections` record with no row.

    Returns
    -------
    Detections
        Every column of length 0 (float or int64).
    """
    f, i = np.zeros(0), np.zeros(0, np.int64)
    return Detections(i, f, f, f, f, f, f, i, i, i)


def concat_detections(parts: list[Detections]) -> Detections:
    """The rows of ``parts`` one after the other.

    Parameters
    ----------
    parts : list of Detections
        Detection records, in order (empty ones are skipped).

    Returns
    -------
    Detections
        All rows; :func:`empty_detections` when no part has a row.
    """
    parts = [p for p in parts if len(p)]
    if not parts:
        return empty_detections()
    return Detections(*[np.concatenate([getattr(p, n) for p in parts]) for n in Detections.__slots__])


class PingMftd:
    """The sliding MFTD over pings (module doc): :meth:`push` one ping's cells, get that ping's detections.

    Parameters
    ----------
    axes : CellAxes
        The cells' axes (every ping has the same).
    period_s : float
        Ping interval T (s): the prior's motion step.
    pfa : float
        False detections per cell per ping (the single-ping threshold's rate).
    sound_speed_mps : float
        Sound speed c (m/s): travel time to bistatic range.
    settings : PingMftdSettings
        K, N, design SNR, sigma_a, tiles, pooling, calibration.
    noise_mean : float
        Mean of a noise-only input cell (1 for a CFAR-normalised statistic); scaled to P1's 2.
    cfar : CfarSettings or CwEstimate, optional
        The CFAR that normalised the cells: the calibration's noise is normalised the same way (its estimation
        noise makes the statistic heavier-tailed than an exponential); a CwEstimate: a CW's normaliser
        (:func:`noise_tiles`).
    """

    def __init__(self, axes: CellAxes, period_s: float, pfa: float, sound_speed_mps: float,
                 settings: PingMftdSettings | None = None, noise_mean: float = 1.0,
                 cfar = None):
        s = settings or PingMftdSettings()
        require(period_s > 0 and sound_speed_mps > 0 and noise_mean > 0,
                "ping interval, sound speed and noise mean must be positive")
        require(0.0 < pfa < 1.0, f"the false-alarm rate must be in (0, 1), got {pfa}")
        self.axes, self.settings, self.pfa, self.scale = axes, s, float(pfa), NOISE_MEAN / float(noise_mean)
        self.cfar = cfar
        self.pool = min(s.pool_cells, axes.shape[1])
        self.pool_b = min(s.pool_beams, axes.shape[0])
        self.n_pooled = axes.shape[1] // self.pool
        self.n_beams = axes.shape[0] // self.pool_b
        require(self.n_pooled >= 1 and self.n_beams >= 1, "the pings hold no travel-time cell or no beam")
        self.grid = self._tile_grid(axes, sound_speed_mps * self.pool, s.max_range_rate_mps)
        margin = int(np.ceil(s.max_range_rate_mps * max(s.frames - 1, 0) * period_s / self.grid.range_cell_m)) + 1
        self.tiles = tile_plan(self.n_pooled, s.tile_cells, margin)
        self._tile_array = np.array(self.tiles, np.int64).reshape(-1, 4)
        self.mftd_settings = MftdSettings(snr_db=s.snr_db, period_s=period_s, sigma_a_mps2=s.sigma_a_mps2,
                                          n_tracks=s.n_tracks)
        self._buffer: deque = deque(maxlen=s.frames)

    @staticmethod
    def _tile_grid(axes: CellAxes, metres_per_cell_s: float, max_rate: float) -> RangeDopplerGrid:
        """The cells of a tile's plane (one range cell here; :meth:`detector` sets the tile's length). The prior
        does not depend on where the tile starts, since its first frame is flat."""
        if axes.doppler_measured and len(axes.range_rate_mps) > 1:
            v = np.asarray(axes.range_rate_mps, float)
            dv = float(abs(v[1] - v[0]))
            v0 = float(min(v[0], v[-1]) - 0.5 * dv)
        else:
            dv, v0 = 2.0 * max_rate, -max_rate
        return RangeDopplerGrid(1, max(len(axes.range_rate_mps), 1), metres_per_cell_s * axes.time_step_s, dv, 0.0,
                                v0)

    def tile_shape(self, frames: int) -> tuple[int, int, int]:
        """(frames, travel-time cells, Doppler cells) of one tile of ``frames`` pings.

        Parameters
        ----------
        frames : int
            Number of pings in the window.

        Returns
        -------
        tuple of int
            (frames, pooled travel-time cells of a tile, Doppler cells).
        """
        lo, hi, _, _ = self.tiles[0]
        return frames, hi - lo, self.axes.shape[2]

    def detector(self, n_range: int) -> MftdDetector:
        """P1's MFTD detector (detection/mftd.py) on a tile of ``n_range`` travel-time cells.

        Parameters
        ----------
        n_range : int
            Pooled travel-time cells of the tile.

        Returns
        -------
        MftdDetector
            The detector on the tile's range-Doppler plane (range cell in m, range-rate cell in m/s), with this
            object's MFTD settings.
        """
        g = self.grid
        grid = RangeDopplerGrid(n_range, g.n_doppler, g.range_cell_m, g.range_rate_cell_mps, 0.0, g.range_rate_min_mps)
        return MftdDetector(grid, self.mftd_settings)

    def threshold(self, frames: int) -> float:
        """lambda for ``frames`` pings: P(S > lambda | noise) = pfa x the input cells of a tile (module doc).

        Parameters
        ----------
        frames : int
            Number of pings in the window (K, or fewer for the first pings).

        Returns
        -------
        float
            Threshold on S, calibrated on noise-only tiles (cached per detector, shape and settings).
        """
        s = self.settings
        shape = self.tile_shape(frames)
        pfa_tile = min(self.pfa * shape[1] * shape[2] * self.pool * self.pool_b, 0.5)
        # the first K - 1 pings' thresholds serve one ping each: a quarter of the trials (tail extrapolated)
        trials = s.calibration_trials if frames == s.frames else max(s.calibration_trials // 4, 100)
        return _calibrated(self.detector(shape[1]), shape, pfa_tile, trials, s.seed, (self.pool_b, self.pool),
                           s.restrict_tol, self.cfar)

    def _pooled(self, y: np.ndarray) -> np.ndarray:
        """The max over each block of ``pool_beams`` x ``pool_cells`` cells (the tail that fills no block is
        dropped)."""
        if self.pool == 1 and self.pool_b == 1:
            return y
        nb, nt = self.n_beams * self.pool_b, self.n_pooled * self.pool
        return y[:nb, :nt].reshape(self.n_beams, self.pool_b, self.n_pooled, self.pool, y.shape[2]).max(axis=(1, 3))

    def push(self, cells: PingCells) -> Detections:
        """Add one ping's cells (a :class:`~sonartrack.detection.cells.PingCells`) and return the detections
        decided at it (``statistic``: S, the log statistic).

        Parameters
        ----------
        cells : PingCells
            The ping's number, transmit time (s) and statistic (beams, travel-time, Doppler).

        Returns
        -------
        Detections
            As :meth:`push_array`.
        """
        det = self.push_array(cells.ping, cells.time_s, cells.statistic, level=cells.level)
        return drop_lobe_images(det, cells)

    def push_array(self, ping: int, time_s: float, cells, level=None) -> Detections:
        """Add one ping's cells and return the detections decided at it.

        Parameters
        ----------
        ping : int
            The ping's number.
        time_s : float
            The ping's transmit time (s).
        cells : array (beams, travel-time, Doppler)
            The normalised square-law statistic of the ping (noise mean ``noise_mean``).
        level : array (beams, travel-time, Doppler), optional
            The CFAR's noise estimate mu of each cell: the cone angle of a detection then comes from the beams'
            power s mu (detection/cells.py :func:`~sonartrack.detection.cells.power_cone_deg`), else from s.

        Returns
        -------
        Detections
            The detections whose windows end at this ping (``statistic``: S, the log statistic).
        """
        y = np.asarray(cells, float)
        require(y.shape == self.axes.shape, f"ping {ping} has cells of shape {y.shape}, the axes say {self.axes.shape}")
        self._buffer.append(self._pooled(y) * self.scale)
        stack = np.stack(self._buffer)  # (k, beams, pooled travel-time, Doppler)
        k = stack.shape[0]
        det = self.detector(self.tile_shape(k)[1])
        stats, last = tile_statistics(det, stack, self._tile_array, self.settings.restrict_tol)
        b, t = np.nonzero(stats > self.threshold(k))
        cell = last[b, t]
        i, j = self._tile_array[t, 0] + cell // self.axes.shape[2], cell % self.axes.shape[2]
        own = (i >= self._tile_array[t, 2]) & (i < self._tile_array[t, 3])
        b, i, j, st = b[own], i[own], j[own], stats[b, t][own]
        if self.settings.merge_beams and len(b):  # (in pooled beams)
            keep = merge_across_beams(b, i, st)
            b, i, j, st = b[keep], i[keep], j[keep], st[keep]
        # the input cell of the pooled block that holds its maximum at this ping
        pb, pc = self.pool_b, self.pool
        bb = (b[:, None] * pb + np.arange(pb)[None, :])[:, :, None]
        dd = (i[:, None] * pc + np.arange(pc)[None, :])[:, None, :]
        flat = np.argmax(y[bb, dd, j[:, None, None]].reshape(len(b), -1), axis=1) if len(b) else np.zeros(0, np.int64)
        return self._detections(ping, time_s, b * pb + flat // pc, i * pc + flat % pc, j, st, y, level)

    def _detections(self, ping: int, time_s: float, b, d, j, st, y: np.ndarray, level=None) -> Detections:
        """The detections at input cells (b, d, j) of this ping, the delay refined by a parabola through the log
        statistic of the cell's neighbours (:func:`parabola_offset`), the cone angle from the beams' power as the
        single-ping detections' (detection/cells.py :func:`~sonartrack.detection.cells.power_cone_deg`)."""
        from sonartrack.detection.cells import power_cone_deg

        a, n = self.axes, len(b)
        log_y = np.log(np.maximum(y, 1e-30))
        cells = PingCells(int(ping), float(time_s), np.asarray(a.cone_deg, float), np.asarray(a.travel_time_s, float),
                          np.asarray(a.doppler_hz, float), np.asarray(a.range_rate_mps, float), y,
                          bool(a.doppler_measured), level)
        cone = power_cone_deg(cells, b, d, j)
        delay = np.interp(d + parabola_offset(log_y, b, d, j, 1), np.arange(len(a.travel_time_s)), a.travel_time_s)
        return Detections(np.full(n, ping, np.int64), np.full(n, float(time_s)), cone, delay,
                          np.asarray(a.doppler_hz, float)[j], np.asarray(a.range_rate_mps, float)[j],
                          np.asarray(st, float), b.astype(np.int64), d.astype(np.int64), j.astype(np.int64))


def drop_lobe_images(det: Detections, cells: PingCells) -> Detections:
    """``det`` without the side- and grating-lobe images of a stronger echo of the same ping (detection/lobes.py
    :func:`~sonartrack.detection.lobes.drop_cell_images`: the array's beam pattern against the ping's cells); as
    they are when the cells carry no :class:`~sonartrack.detection.lobes.LobeBand` (``lobe_margin_db`` not set)."""
    from sonartrack.detection.lobes import drop_cell_images

    return drop_cell_images(det, cells)


def parabola_offset(log_y: np.ndarray, b, d, j, axis: int) -> np.ndarray:
    """Offsets (cells, within +-0.5) of the peak of a parabola through the log statistic at the cells (b, d, j) and
    their two neighbours along ``axis`` (0 beams, 1 delays): delta = (y_- - y_+) / (2 (y_- - 2 y_0 + y_+)), zero
    where the three do not make a maximum or the cell is at an edge.

    Parameters
    ----------
    log_y : numpy.ndarray
        (beams, travel-time, Doppler) log statistic of the ping.
    b, d, j : int arrays (n,)
        Beam, travel-time and Doppler cell of each peak.
    axis : int
        0 to refine along beams, 1 along travel time.

    Returns
    -------
    numpy.ndarray
        (n,) offsets in cells, in [-0.5, 0.5].
    """
    idx = [np.asarray(b), np.asarray(d), np.asarray(j)]
    size = log_y.shape[axis]
    i = idx[axis]
    if size < 3 or not len(i):
        return np.zeros(len(i))
    lo, hi = list(idx), list(idx)
    lo[axis], hi[axis] = np.clip(i - 1, 0, size - 1), np.clip(i + 1, 0, size - 1)
    y0, y1, y2 = log_y[tuple(lo)], log_y[tuple(idx)], log_y[tuple(hi)]
    den = y0 - 2.0 * y1 + y2
    ok = (den < 0) & (i > 0) & (i < size - 1)
    return np.clip(np.where(ok, 0.5 * (y0 - y2) / np.where(ok, den, -1.0), 0.0), -0.5, 0.5)


def merge_across_beams(beam, time_index, statistic) -> np.ndarray:
    """Keep (bool (n,)) the detections with no stronger one in an adjacent beam within one travel-time cell (ties:
    the lower beam wins).

    Parameters
    ----------
    beam : int array (n,)
        Beam index of each detection.
    time_index : int array (n,)
        Travel-time cell of each detection.
    statistic : array (n,)
        Each detection's statistic.

    Returns
    -------
    numpy.ndarray
        (n,) bool, True where the detection is kept.
    """
    b, i, s = (np.asarray(v) for v in (beam, time_index, statistic))
    near = (np.abs(b[:, None] - b[None, :]) == 1) & (np.abs(i[:, None] - i[None, :]) <= 1)
    stronger = (s[None, :] > s[:, None]) | ((s[None, :] == s[:, None]) & (b[None, :] < b[:, None]))
    return ~(near & stronger).any(axis=1)


def detect_pings(cells, ping_time_s, axes: CellAxes, period_s: float, pfa: float, sound_speed_mps: float,
                 settings: PingMftdSettings | None = None, noise_mean: float = 1.0,
                 cfar: CfarSettings | None = None) -> Detections:
    """:class:`PingMftd` over a sequence of pings' cells (each beams x travel-time x Doppler).

    Parameters
    ----------
    cells : iterable of arrays
        One (beams, travel-time, Doppler) array per ping, in time order.
    ping_time_s : array
        The pings' transmit times (s); ping k is number k.
    axes, period_s, pfa, sound_speed_mps, settings, noise_mean, cfar
        As :class:`PingMftd`.

    Returns
    -------
    Detections
        Every ping's detections, in ping order.
    """
    mftd = PingMftd(axes, period_s, pfa, sound_speed_mps, settings, noise_mean, cfar)
    return concat_detections([mftd.push_array(k, float(t), y) for k, (t, y) in enumerate(zip(ping_time_s, cells,
                                                                                            strict=False))])
