"""Track-before-detect on the bearing-time record: paper P1's MFTD in cone angle and cone-angle rate.

Im & Kim 1996 (paper P1; ``detection/mftd.py``: the N-best pruned detector with its Kalman track prior, eqs.
9-10, 16-22) decide whether a target is in K frames of cells. Here a frame is one line of the bearing-time
record (one window, T = ``window_s``) and its cells are the beams: rows = windows, columns = beams. The state is
w = [theta, thetadot] (cone angle deg, its rate deg/s); P1's plane is one cone-angle axis of beam cells
(d theta the grid step) and ONE rate cell covering +-``max_rate_deg_s`` (a beam measures no rate), so P1's
quantisation covariance R = diag(d theta^2, (2 max_rate)^2) / 12 (eq. 25) carries that ignorance, as the
active chain's MFTD does for a waveform without Doppler (``detection/ping_mftd.py``). Motion: P1 eq. 23 with
sigma_a the cone-angle acceleration (deg/s^2): target manoeuvres and the ownship's.

Cell statistic. P1's log-likelihood ratio of a track is linear in the cells it visits (eq. 10: rho / (2 (1 +
rho)) y for square-law Swerling-1 cells on the noise scale 2):

* ``exponential``: a normalised beam power p (noise mean 1, a Rayleigh envelope's square) is P1's cell,
  y = 2 p, rho = the design SNR;
* ``gaussian``: the front end's z = (P - median) / (1.4826 MAD) (acoustics/beamforming.py), roughly N(0, 1) in
  noise and N(mu, 1) on a target (P sums ~2 n_bins chi-square terms); its log-LR is mu z - mu^2 / 2, so the
  kernel's g y / 2 term (g = rho / (1 + rho)) equals it with y = (2 mu / g) z; here mu = 10^(snr_db / 20)
  (SNR = mu^2, the deflection) and rho = mu^2. The per-frame constants differ from P1's; they do not matter,
  since the threshold is calibrated.

Tiles, threshold and detections as ``detection/ping_mftd.py``: the beam axis is cut into tiles (``tile_beams``
owned, a margin of ceil(max_rate (K - 1) T / d theta) + 1 beams either side), each a P1 test; a tile reports at
most one detection, the last cell of its best track, if it owns it. The threshold lambda (Monte Carlo: P1 gives no
closed form of the pruned statistic's law) is the quantile of S over ``calibration_trials`` seeded noise-only
tiles (independent cells of the stated statistic; pooled cells the max of ``pool_beams``) with
P(S > lambda) = pfa x (beams of a tile), so false detections per beam per window equal the single-window
threshold's pfa; the tail beyond the empirical quantiles is the fitted exponential excess (``tail_threshold``).
Beams of the real record are correlated (a beam is several grid steps wide): pool them (``pool_beams``) or
measure the false-track rate on noise-only records. The first K - 1 windows are decided with the frames there
are (their own thresholds).
"""

from __future__ import annotations

import functools
from collections import deque
from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.random import trial_rng
from sonartrack.core.rows import Rows
from sonartrack.core.settings import Settings, setting

# the detector's modules (detection/mftd.py, ping_mftd.py) are imported where used: the passive system's settings
# import this module's settings at the command line's start


class BtrMftdSettings(Settings):
    """MFTD over the bearing-time record (module doc). The window, the cone grid and the false-alarm rate are the
    system's (given to :class:`BtrMftd`)."""

    frames: int = setting(8, "windows K integrated by one decision (P1's frames)", unit="1", ge=1, le=64)
    n_tracks: int = setting(20, "tracks N kept after each window's pruning (P1, sec. IV)", unit="1", ge=1,
                            le=10_000)
    snr_db: float = setting(3.0, "design SNR of a target cell: mu^2 of the z statistic, rho of a power cell",
                            unit="dB", ge=-20, le=30)
    statistic: Literal["gaussian", "exponential"] = setting("gaussian", "cell statistic: z ~ N(0, 1) in noise (the "
                                                            "front end's), or a power with noise mean 1", unit="")
    sigma_accel_deg_s2: float = setting(0.01, "standard deviation of the cone-angle acceleration (P1 eq. 23)",
                                        unit="deg/s^2", gt=0, le=10)
    max_rate_deg_s: float = setting(0.5, "largest cone-angle rate of a target (the rate cell's span and the tile "
                                         "margin)", unit="deg/s", gt=0, le=30)
    tile_beams: int = setting(32, "beams a tile owns (one P1 test per tile and window)", unit="1", ge=1)
    pool_beams: int = setting(1, "the MFTD runs on the max over runs of this many adjacent beams", unit="1", ge=1,
                              le=16)
    restrict_tol: float = setting(1e-9, "branch only to cells whose prior weight is above this relative to the "
                                        "kept ones", unit="1", gt=0, lt=1e-2)
    calibration_trials: int = setting(2000, "noise-only tiles simulated to calibrate the threshold", unit="1",
                                      ge=100, le=10_000_000)
    seed: int = setting(0, "seed of the calibration's noise-only tiles", unit="1")

    @property
    def mu(self) -> float:
        """Design mean shift mu = 10^(snr_db / 20) of the z statistic."""
        return float(10.0 ** (self.snr_db / 20.0))


@dataclass(frozen=True, slots=True)
class BtrDetections(Rows):
    """MFTD detections: window index, window centre (s), cone angle (deg) and rate (deg/s) of the best track's
    last cell (the rate the least-squares slope over its K cells: coarse, one cell step over K windows), the
    statistic S (log) and its threshold."""

    window: np.ndarray
    time_s: np.ndarray
    cone_deg: np.ndarray
    cone_rate_deg_s: np.ndarray
    statistic: np.ndarray
    threshold: np.ndarray


def _empty() -> BtrDetections:
    f = np.zeros(0)
    return BtrDetections(np.zeros(0, np.int64), f, f, f, f, f)


def best_tracks(detector, stack: np.ndarray, spans: np.ndarray, tol: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """P1's statistic S and the best track's cells of every (outer index, tile) of ``stack``.

    Parameters
    ----------
    detector : MftdDetector
        The detector of one tile (its grid has the tile's length, one rate cell).
    stack : ndarray (K, n, cells)
        K frames of n independent records (trials) of cells on P1's scale.
    spans : int ndarray (t, 2)
        [lo, hi) of each tile.
    tol : float
        Restriction tolerance.

    Returns
    -------
    S : ndarray (n, t)
        log sum c_theta LR_theta per record and tile.
    hist : int ndarray (n, t, K)
        The best track's cell per frame (inside the tile).
    """
    from sonartrack.detection.mftd_kernel import pruned_kernel
    from sonartrack.detection.prior import prior_constant
    from sonartrack.detection.pruned import restriction_margin

    y = np.asarray(stack, dtype=float)
    K, g = y.shape[0], detector.grid
    prior = detector.prior(K)
    plane = (g.n_range, g.n_doppler, g.range_cell_m, g.range_rate_cell_mps, g.range_min_m, g.range_rate_min_mps)
    arrays = (prior.S_inv, prior.S_cov, prior.F, prior.L, prior.u, np.asarray(prior.w1, dtype=float))
    snr, kernel = detector.snr, pruned_kernel()
    gain, margin, n_keep = snr / (1.0 + snr), restriction_margin(g.n_cells, tol), int(detector.settings.n_tracks)
    half = np.empty((y.shape[1], len(spans)))
    hist = np.empty((y.shape[1], len(spans), K), np.int64)
    for b in range(y.shape[1]):
        for t, (lo, hi) in enumerate(spans):
            h, hh, _, _ = kernel(np.ascontiguousarray(y[:, b, lo:hi]), plane, arrays, gain, margin, n_keep, 1, True,
                                 False)
            half[b, t], hist[b, t] = h, hh[0]
    return half + prior_constant(prior, snr), hist


def cell_scale(settings: BtrMftdSettings) -> float:
    """Factor from the cell statistic to P1's y (module doc): 2 for a power, 2 mu (1 + rho) / rho for z.

    Parameters
    ----------
    settings : BtrMftdSettings
        Statistic and design SNR.

    Returns
    -------
    float
        The factor.
    """
    if settings.statistic == "exponential":
        return 2.0
    rho = settings.mu**2
    return 2.0 * settings.mu * (1.0 + rho) / rho


def noise_cells(rng: np.random.Generator, shape: tuple[int, ...], statistic: str, pool: int) -> np.ndarray:
    """Noise-only cells (K, ..., L) of the statistic (z ~ N(0, 1) or power ~ Exp(1)), each the max of ``pool``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random numbers.
    shape : tuple of int
        Shape of the returned cells.
    statistic : str
        "gaussian" (z ~ N(0, 1)) or else exponential power (Exp(1)).
    pool : int
        Cells pooled into one by their maximum (beams pooled).

    Returns
    -------
    ndarray, shape ``shape``
        The pooled noise cells.
    """
    draw = rng.standard_normal if statistic == "gaussian" else (lambda s: rng.exponential(1.0, s))
    return draw(tuple(shape) + (pool,)).max(axis=-1)


@functools.lru_cache(maxsize=64)
def _calibrated(detector, frames: int, cells: int, settings: BtrMftdSettings, pfa_tile: float,
                trials: int) -> float:
    from sonartrack.detection.ping_mftd import tail_threshold

    s = settings
    y = np.stack([noise_cells(trial_rng(s.seed, i), (frames, cells), s.statistic, s.pool_beams)
                  for i in range(trials)], axis=1) * cell_scale(s)
    stats, _ = best_tracks(detector, y, np.array([[0, cells]], np.int64), s.restrict_tol)
    return tail_threshold(stats[:, 0], pfa_tile)


class BtrMftd:
    """The sliding MFTD over the bearing-time record (module doc): :meth:`push` one window's cells, get that
    window's detections.

    Parameters
    ----------
    cone_deg : ndarray (B,)
        The beams' cone angles (deg), uniform.
    window_s : float
        Window T (s): the prior's motion step.
    pfa : float
        False detections per beam per window (the single-window threshold's rate).
    settings : BtrMftdSettings, optional
        K, N, design SNR, statistic, motion, tiles, calibration.
    """

    def __init__(self, cone_deg, window_s: float, pfa: float, settings: BtrMftdSettings | None = None):
        from sonartrack.detection.mftd import MftdDetector, MftdSettings
        from sonartrack.detection.ping_mftd import tile_plan
        from sonartrack.models.range_doppler import RangeDopplerGrid

        s = settings or BtrMftdSettings()
        cone = np.asarray(cone_deg, float)
        require(cone.ndim == 1 and cone.size >= 2, "the bearing-time record needs at least two beams")
        require(window_s > 0, f"window_s must be positive, got {window_s}")
        require(0.0 < pfa < 1.0, f"the false-alarm rate must be in (0, 1), got {pfa}")
        self.cone, self.window_s, self.pfa, self.settings = cone, float(window_s), float(pfa), s
        self.pool = min(s.pool_beams, cone.size)
        self.n_cells = cone.size // self.pool
        step = abs(float(cone[1] - cone[0])) * self.pool
        margin = int(np.ceil(s.max_rate_deg_s * max(s.frames - 1, 0) * window_s / step)) + 1
        self.tiles = np.array(tile_plan(self.n_cells, s.tile_beams, margin), np.int64).reshape(-1, 4)
        self.length = int(self.tiles[0, 1] - self.tiles[0, 0])
        grid = RangeDopplerGrid(self.length, 1, step, 2.0 * s.max_rate_deg_s, 0.0, -s.max_rate_deg_s)
        rho_db = s.snr_db if s.statistic == "exponential" else 20.0 * np.log10(s.mu)
        self.detector = MftdDetector(grid, MftdSettings(snr_db=rho_db, period_s=window_s,
                                                        sigma_a_mps2=s.sigma_accel_deg_s2, n_tracks=s.n_tracks))
        self.scale = cell_scale(s)
        self._buffer: deque = deque(maxlen=s.frames)
        self.k = 0

    def threshold(self, frames: int) -> float:
        """lambda for ``frames`` windows: P(S > lambda | noise) = pfa x the beams of a tile (module doc).

        Parameters
        ----------
        frames : int
            Windows in the buffer (K once full; fewer at the start of a record, calibrated with a quarter of the
            trials, at least 100).

        Returns
        -------
        float
            The threshold on the statistic S (log), calibrated by Monte Carlo on noise-only tiles.
        """
        s = self.settings
        pfa_tile = min(self.pfa * self.length * self.pool, 0.5)
        trials = s.calibration_trials if frames == s.frames else max(s.calibration_trials // 4, 100)
        return _calibrated(self.detector, frames, self.length, s, pfa_tile, trials)

    def push(self, cells) -> BtrDetections:
        """Add one window's cells (B,) (the statistic of the settings) and return the detections decided at it.

        Parameters
        ----------
        cells : array_like, shape (B,)
            One window of the bearing-time record, one cell per beam.

        Returns
        -------
        BtrDetections
            The detections whose best track ends in this window inside the tile that owns it (possibly none).
        """
        y = np.asarray(cells, float)
        require(y.shape == self.cone.shape, f"window {self.k} has {y.shape} cells, the record has {self.cone.size} "
                                            "beams")
        pooled = y[: self.n_cells * self.pool].reshape(self.n_cells, self.pool).max(axis=1)
        self._buffer.append(pooled * self.scale)
        stack = np.stack(self._buffer)[:, None, :]  # (k, 1, cells)
        k, lam = stack.shape[0], self.threshold(stack.shape[0])
        stats, hist = best_tracks(self.detector, stack, self.tiles[:, :2], self.settings.restrict_tol)
        t = np.nonzero(stats[0] > lam)[0]
        cells_k = self.tiles[t, 0][:, None] + hist[0, t]  # (n, k) pooled cell per frame
        own = (cells_k[:, -1] >= self.tiles[t, 2]) & (cells_k[:, -1] < self.tiles[t, 3])
        t, cells_k = t[own], cells_k[own]
        window, self.k = self.k, self.k + 1
        if not len(t):
            return _empty()
        step = self.detector.grid.range_cell_m
        rate = np.polyfit(np.arange(k) * self.window_s, cells_k.T * step, 1)[0] if k > 1 else np.zeros(len(t))
        last = cells_k[:, -1]
        beam = last * self.pool + np.argmax(y[: self.n_cells * self.pool].reshape(self.n_cells, self.pool)[last],
                                            axis=1)
        n = len(t)
        return BtrDetections(np.full(n, window, np.int64), np.full(n, (window + 0.5) * self.window_s), self.cone[beam],
                             np.atleast_1d(rate) * np.sign(self.cone[1] - self.cone[0]), stats[0, t], np.full(n, lam))


def btr_mftd(level, cone_deg, window_s: float, pfa: float, settings: BtrMftdSettings | None = None
             ) -> BtrDetections:
    """:class:`BtrMftd` over a whole bearing-time record.

    Parameters
    ----------
    level : ndarray (T, B)
        The record's cells (rows = windows, columns = beams) in the statistic of ``settings``.
    cone_deg : ndarray (B,)
        Beam cone angles (deg).
    window_s : float
        Window (s).
    pfa : float
        False detections per beam per window.
    settings : BtrMftdSettings, optional
        As :class:`BtrMftd`.

    Returns
    -------
    BtrDetections
        Every window's detections, in window order.
    """
    m = BtrMftd(cone_deg, window_s, pfa, settings)
    parts = [m.push(row) for row in np.asarray(level, float)]
    parts = [p for p in parts if len(p)]
    if not parts:
        return _empty()
    return BtrDetections(*[np.concatenate([getattr(p, f) for p in parts]) for f in BtrDetections.__slots__])


def single_window_threshold(pfa: float, statistic: str) -> float:
    """The single-window threshold on one cell at false-alarm probability ``pfa``: Phi^-1(1 - pfa) for z ~ N(0, 1),
    -ln(pfa) for a power ~ Exp(1).

    Parameters
    ----------
    pfa : float
        False-alarm probability per cell.
    statistic : {"gaussian", "exponential"}
        The cell statistic.

    Returns
    -------
    float
        The threshold.
    """
    from scipy.stats import norm

    return float(norm.isf(pfa)) if statistic == "gaussian" else float(-np.log(pfa))
