"""Detections made by the edge of the recording's band (systems/passive/narrowband.py :func:`off_band_edges`): a
recording band-limited inside the LOFAR band (a 64 x 0.5 m, 16 kHz recording: noise to 1000 Hz in a
375-1500 Hz band, the bins above reading ~1e-21 of it) halves the split-window background just below the edge, and
z = P / mu doubles there. Hand-worked cells against their live reference bins and the F threshold for their number,
cells away from the edge left alone, and the line detector on a noisy band-limited gram."""

from __future__ import annotations

import numpy as np

from sonartrack.acoustics.lofar import LineDetections, LofarGram, LofarSettings, background, detect_lines
from sonartrack.systems.passive.narrowband import off_band_edges

#: two-pass normaliser, L = 16, gap 2, 16 reference bins a side; the F(32, 32 n) threshold at pfa 1e-4 is 2.2493
#: for n = 32 reference bins, 2.2507 for 31, 2.2667 for 23, 2.2938 for 16 (scipy.special.fdtri)
LOFAR = LofarSettings(band_hz=[1.0, 199.0], beams=6, integration=16)
EDGE_BIN = 60  # bins from here up hold no power (1e-21 of the noise below, as the sweep scene's empty band)


def _gram(power: np.ndarray) -> LofarGram:
    """A gram of one period from its (B, F) power, z from the chain's own normaliser."""
    p = power[None].astype(float)
    z = p / np.maximum(background(p, LOFAR), np.finfo(float).tiny)  # as the chain (acoustics/lofar.py)
    return LofarGram(np.array([8.0]), LOFAR.cone_deg, np.arange(p.shape[2], dtype=float), p, z)


def _cells(gram: LofarGram, beams, bins) -> LineDetections:
    b, k = np.asarray(beams, np.int64), np.asarray(bins, np.int64)
    z = gram.statistic[0, b, k]
    return LineDetections(np.full(len(b), 8.0), gram.cone_deg[b], gram.freqs_hz[k], z, 10 * np.log10(z - 1), b)


def _band_limited(cells: dict[tuple[int, int], float]) -> np.ndarray:
    power = np.ones((LOFAR.beams, 100))
    power[:, EDGE_BIN:] = 1e-21
    for (b, k), v in cells.items():
        power[b, k] = v
    return power


def test_a_cell_by_the_edge_is_tested_on_its_live_reference_bins_at_their_threshold():
    # bin 57: reference bins 39..54 (1) and 60..75 (empty): mu = 16 / 32 = 1/2, z = 2 P; live: 16 bins of mean 1,
    # threshold 2.2938. Bin 50: 34..47 and 53..68, of which 53..59 live: mu = 23 / 32, live 23 bins, threshold 2.2667.
    # Bin 42: 26..39 and 45..60, only 60 dead: mu = 31 / 32, live 31 bins, threshold 2.2507 (z = 2.29: a detection)
    cells = {(0, 57): 2.0, (1, 57): 3.0, (2, 57): 2.28, (3, 50): 2.27, (4, 50): 2.26, (5, 42): 2.22}  # a cell a beam
    gram = _gram(_band_limited(cells))
    d = _cells(gram, [0, 1, 2, 3, 4, 5], [57, 57, 57, 50, 50, 42])
    z = [4.0, 6.0, 4.56, 2.27 * 32 / 23, 2.26 * 32 / 23, 2.22 * 32 / 31]
    np.testing.assert_allclose(d.statistic, z, rtol=1e-12)
    kept = off_band_edges(gram, d, LOFAR)
    np.testing.assert_array_equal(np.c_[kept.beam, kept.frequency_hz], [[1, 57], [3, 50]])
    np.testing.assert_allclose(kept.statistic, [6.0, 2.27 * 32 / 23], rtol=1e-12)  # z as it was


def test_cells_away_from_the_edge_are_left_alone():
    # bin 30: every reference bin live, so even P = 2.1 (z 2.1 < 2.2493, never a detection) is kept: the test acts
    # only where the window reaches empty bins
    gram = _gram(_band_limited({(0, 30): 2.1, (1, 30): 5.0}))
    kept = off_band_edges(gram, _cells(gram, [0, 1], [30, 30]), LOFAR)
    np.testing.assert_array_equal(kept.beam, [0, 1])
    assert len(off_band_edges(gram, _cells(gram, [], []), LOFAR)) == 0


def test_a_strong_line_in_the_window_is_censored_as_the_normaliser_does():
    # a line of 50 at bin 40 lies in bin 57's lower reference bins; left out (over censor x mu), the live mean stays 1
    gram = _gram(_band_limited({(0, 57): 2.0, (1, 57): 3.0, (0, 40): 50.0, (1, 40): 50.0}))
    kept = off_band_edges(gram, _cells(gram, [0, 1], [57, 57]), LOFAR)
    np.testing.assert_array_equal(kept.beam, [1])


def test_noisy_band_limited_gram_keeps_the_line_and_drops_the_edge():
    rng = np.random.default_rng(5)
    n_t, n_f, line_bin = 40, 100, 20
    p = rng.gamma(16, 1.0 / 16, size=(n_t, LOFAR.beams, n_f))
    p[..., EDGE_BIN:] *= 1e-21
    p[:, 1, line_bin] += 3.0  # a line 3x the background in the middle beam
    p[:, 1, EDGE_BIN - 4] += 3.0  # and one by the edge
    z = p / np.maximum(background(p, LOFAR), np.finfo(float).tiny)
    gram = LofarGram((np.arange(n_t) + 0.5) * 16.0, LOFAR.cone_deg, np.arange(n_f, dtype=float), p, z)
    d = detect_lines(gram, LOFAR)
    by_edge = (d.frequency_hz >= EDGE_BIN - 18) & (d.frequency_hz < EDGE_BIN) & (d.frequency_hz != EDGE_BIN - 4)
    assert by_edge.sum() >= 100  # the edge's false lines; noise alone would give pfa 1e-4 of its 4080 cells
    kept = off_band_edges(gram, d, LOFAR)
    assert np.sum((kept.frequency_hz >= EDGE_BIN - 18) & (kept.frequency_hz < EDGE_BIN - 4)) <= 2  # ~0.2 expected
    for line in (line_bin, EDGE_BIN - 4):  # every period of both lines, in their beam
        assert np.sum((kept.frequency_hz == line) & (kept.beam == 1)) == n_t


def test_the_narrowband_stage_makes_no_line_of_the_edge():
    from sonartrack.systems.passive import PassiveSettings
    from sonartrack.systems.passive.narrowband import narrowband_lines

    stages = PassiveSettings(spacing_m=2.5, elements=16).stages(4000.0)  # [narrowband]: the LOFAR settings above
    rng = np.random.default_rng(7)
    n_t, n_f = 60, 100
    p = rng.gamma(16, 1.0 / 16, size=(n_t, LOFAR.beams, n_f))
    p[..., EDGE_BIN:] *= 1e-21
    p[:, 1, 20] += 3.0
    z = p / np.maximum(background(p, LOFAR), np.finfo(float).tiny)
    gram = LofarGram((np.arange(n_t) + 0.5) * 16.0, LOFAR.cone_deg, np.arange(n_f, dtype=float), p, z)
    f = np.array([ln.mean_frequency_hz for ln in narrowband_lines(gram, stages).lines])
    assert np.any(np.abs(f - 20.0) < 0.5)  # the line (the bins over the edge make lines of their own: the
    # normaliser's round-off there, acoustics/lofar.py, left alone)
    assert not np.any((f > EDGE_BIN - 20) & (f < EDGE_BIN))
