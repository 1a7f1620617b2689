"""The quiet-target study's cell-level part: MFTD, single-window and LOFAR detection of lines on simulated cells.

Noise cells of the bearing-time record and of the LOFAR gram with a line of known level added (no scene, no
chain): the detection probability of paper P1's MFTD against the single-window threshold per statistic, and of
the LOFAR gram's long integration against its short one (:func:`run_cells`). Configured by :class:`CellConfig`.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.detection.btr_mftd import (
    BtrMftd,
    BtrMftdSettings,
    best_tracks,
    btr_mftd,
    noise_cells,
    single_window_threshold,
)

#: the cells' noise statistics: Gaussian (a beam's level) and exponential (a LOFAR cell's power)
STATISTICS = ("gaussian", "exponential")


class CellConfig(Settings):
    """Supporting rows on synthetic cells (the earlier form of this study): single-window and MFTD detection on cells
    of the bearing-time record at ``pfa`` per beam and window (Gaussian z and Rayleigh power cells), and LOFAR line
    detection with one and ``integration`` windows."""

    trials: int = setting(20, "cell trials per study trial", unit="1", ge=1)
    beams: int = setting(64, "beams of a synthetic bearing-time record", unit="1", ge=16)
    pfa: float = setting(1e-3, "false detections per beam and window of both broadband detectors", unit="1", gt=0,
                         lt=0.1)
    max_rate_cells: float = setting(0.2, "largest line rate in beams per window", unit="1", ge=0)
    btr: BtrMftdSettings = setting(default_factory=lambda: BtrMftdSettings(frames=8, tile_beams=64),
                                   doc="the MFTD (K = 8 windows; statistic and design SNR set per statistic)")
    design_snr_db: list[float] = setting(default_factory=lambda: [3.0, 5.0], doc="MFTD design SNR per statistic "
                                         "(gaussian, exponential)", unit="dB")
    snr_grid_db: list[list[float]] = setting(
        default_factory=lambda: [[-3.0 + 1.5 * i for i in range(13)], [0.0 + 1.5 * i for i in range(13)]],
        doc="target cell SNRs per statistic (gaussian: 20 log10 mu; exponential: 10 log10 rho)", unit="dB")
    noise_windows: int = setting(40, "windows of the noise-only record of each trial", unit="1", ge=10)
    bins: int = setting(128, "bins of a synthetic narrowband spectrum", unit="1", ge=48)
    integration: int = setting(16, "windows L of the long narrowband integration", unit="1", ge=2)
    lofar_pfa: float = setting(1e-4, "false-alarm probability per bin and period of the line threshold", unit="1",
                               gt=0, lt=0.1)
    tonal_grid_db: list[float] = setting(default_factory=lambda: [-9.0 + 1.5 * i for i in range(17)],
                                         doc="tonal bin SNRs s (power over the bin's noise)", unit="dB")
    line_grid_db: list[float] = setting(default_factory=lambda: [-10.0 + 1.0 * i for i in range(14)],
                                        doc="bin SNRs s of a line on LOFAR-statistic cells (``integration`` windows "
                                            "per period) for the MFTD per line", unit="dB")

    def mftd(self, statistic: str) -> BtrMftd:
        """The sliding MFTD of one statistic on a ``beams``-beam record of 1 s windows."""
        i = STATISTICS.index(statistic)
        s = self.btr.model_copy(update={"statistic": statistic, "snr_db": self.design_snr_db[i]})
        return BtrMftd(np.arange(float(self.beams)), 1.0, self.pfa, s)


def _line_records(config: CellConfig, m: BtrMftd, statistic: str, rng) -> tuple[np.ndarray, np.ndarray]:
    """(MFTD hit, single hit) per level of ``statistic``: one K-window record with a line per level."""
    K, b, n = m.settings.frames, config.beams, len(config.snr_grid_db[STATISTICS.index(statistic)])
    y = noise_cells(rng, (K, n, b), statistic, 1)
    start = rng.uniform(0.3 * b, 0.7 * b, n)
    rate = rng.uniform(-config.max_rate_cells, config.max_rate_cells, n)
    cells = np.clip(np.rint(start[None] + rate[None] * np.arange(K)[:, None]), 0, b - 1).astype(int)
    snr = np.asarray(config.snr_grid_db[STATISTICS.index(statistic)])
    idx = (np.arange(K)[:, None], np.arange(n)[None], cells)
    if statistic == "gaussian":
        y[idx] += 10 ** (snr / 20)[None]
    else:
        y[idx] *= 1 + 10 ** (snr / 10)[None]
    st, hist = best_tracks(m.detector, y * m.scale, m.tiles[:, :2], m.settings.restrict_tol)
    own = np.array([np.nonzero((m.tiles[:, 2] <= c) & (m.tiles[:, 3] > c))[0][0] for c in cells[-1]])
    i = np.arange(n)
    hit = (st[i, own] > m.threshold(K)) & (np.abs(m.tiles[own, 0] + hist[i, own, -1] - cells[-1]) <= 1)
    single = y[-1, i, cells[-1]] > single_window_threshold(config.pfa, statistic)
    return hit.astype(float), single.astype(float)


def line_cell_records(config: CellConfig, m: BtrMftd, rng) -> tuple[np.ndarray, np.ndarray]:
    """(MFTD hit, single hit) per line level on LOFAR-statistic cells: one K-period record per level, each cell z =
    the mean of L exponential powers over the mean of R = 2 ``reference_bins`` such noise cells (F(2L, 2LR) in
    noise, the mean normaliser's law), a line of bin SNR s moving in beams; the MFTD per line runs on the cells
    mapped to N(0, 1) (systems/passive/line_mftd.py), the single period thresholds z at the F quantile, both at
    ``pfa`` per beam and period."""
    from sonartrack.acoustics.lofar import LofarSettings, line_threshold
    from sonartrack.systems.passive.line_mftd import gaussianised

    lofar = LofarSettings(integration=config.integration, pfa=config.pfa)
    L, R = lofar.integration, 2 * lofar.reference_bins
    K, b, n = m.settings.frames, config.beams, len(config.line_grid_db)
    s = 10 ** (np.asarray(config.line_grid_db) / 10)
    num = rng.gamma(L, 1.0 / L, (K, n, b))
    start = rng.uniform(0.3 * b, 0.7 * b, n)
    rate = rng.uniform(-config.max_rate_cells, config.max_rate_cells, n)
    cells = np.clip(np.rint(start[None] + rate[None] * np.arange(K)[:, None]), 0, b - 1).astype(int)
    idx = (np.arange(K)[:, None], np.arange(n)[None], cells)
    num[idx] = rng.gamma(L, (1.0 + s)[None] / L, (K, n))
    z = num / (rng.gamma(L * R, 1.0 / (L * R), (K, n, b)))
    st, hist = best_tracks(m.detector, gaussianised(z, lofar) * m.scale, m.tiles[:, :2], m.settings.restrict_tol)
    own = np.array([np.nonzero((m.tiles[:, 2] <= c) & (m.tiles[:, 3] > c))[0][0] for c in cells[-1]])
    i = np.arange(n)
    hit = (st[i, own] > m.threshold(K)) & (np.abs(m.tiles[own, 0] + hist[i, own, -1] - cells[-1]) <= 1)
    single = z[-1, i, cells[-1]] >= line_threshold(lofar)
    return hit.astype(float), single.astype(float)


def lofar_hits(config: CellConfig, integration: int, rng) -> np.ndarray:
    """Line detected at the tonal's bin (1/0) per tonal level, after averaging ``integration`` windows."""
    from sonartrack.acoustics.lofar import LofarSettings, background, line_threshold

    s = LofarSettings(integration=integration, pfa=config.lofar_pfa)
    levels = np.asarray(config.tonal_grid_db)
    n, f, k0 = len(levels), config.bins, config.bins // 2
    noise = (rng.standard_normal((integration, n, f)) + 1j * rng.standard_normal((integration, n, f))) / np.sqrt(2)
    noise[:, :, k0] += np.sqrt(10 ** (levels / 10))[None] * np.exp(1j * rng.uniform(0, 2 * np.pi, (integration, 1)))
    p = np.mean(np.abs(noise) ** 2, axis=0)  # (n, F)
    z = p / background(p, s)
    peak = (z[:, k0] > z[:, k0 - 1]) & (z[:, k0] >= z[:, k0 + 1])
    return (peak & (z[:, k0] >= line_threshold(s))).astype(float)


def run_cells(config: CellConfig, rng) -> dict[str, np.ndarray]:
    """One synthetic cell trial: one record per detector and level, one noise-only record per statistic through the
    sliding MFTD (false detections), the LOFAR line detector with one and ``integration`` windows."""
    out: dict[str, np.ndarray] = {}
    for stat in STATISTICS:
        m = config.mftd(stat)
        out[f"mftd_{stat}"], out[f"single_{stat}"] = _line_records(config, m, stat, rng)
        level = noise_cells(rng, (config.noise_windows, config.beams), stat, 1)
        d = btr_mftd(level, m.cone, 1.0, config.pfa, m.settings)
        out[f"false_{stat}"] = np.array([float(len(d))])
    out["lofar_1"] = lofar_hits(config, 1, rng)
    out["lofar_long"] = lofar_hits(config, config.integration, rng)
    # a stream of its own: the other rows keep the draws they had before this row was added
    out["line_mftd"], out["line_single"] = line_cell_records(config, config.mftd("gaussian"), rng.spawn(1)[0])
    return out
