"""The K shape fitted per group of beams (detection/cells.py heavy_tail_statistic, shape_groups): beams whose
reverberation is spikier than the others' keep the stated false-alarm rate."""

import numpy as np

from sonartrack.detection.cells import FrontEndSettings, heavy_tail_statistic, shape_groups
from sonartrack.detection.cfar import noise_estimate, os_threshold


def test_shape_groups_cover_every_beam_once():
    for n_b, n_d, m in ((61, 12000, 20000), (61, 300, 20000), (7, 5000, 10000), (61, 100, None)):
        groups = shape_groups(n_b, n_d, m)
        covered = np.concatenate([np.arange(n_b)[g] for g in groups])
        assert covered.tolist() == list(range(n_b))
        if m is not None and n_b * n_d >= 2 * m:
            assert all((g.stop - g.start) * n_d >= m for g in groups)
    assert shape_groups(61, 100, 20000) == [slice(0, 61)]  # too few cells for two groups


def _k_cells(rng, nu: float, shape) -> np.ndarray:
    """K-distributed intensity (Ward's compound: gamma texture of shape nu, mean 1, times exponential speckle),
    drawn here from its definition, independently of the library's K law."""
    texture = rng.gamma(nu, 1.0 / nu, size=shape) if np.isfinite(nu) else np.ones(shape)
    return texture * rng.exponential(1.0, size=shape)


def test_spiky_beams_keep_the_false_alarm_rate_when_fitted_apart():
    rng = np.random.default_rng(5)
    n_b, n_d = 6, 12000
    y = np.concatenate([_k_cells(rng, np.inf, (4, 1, n_d)), _k_cells(rng, 0.5, (2, 1, n_d))]).astype(np.float32)
    pfa = 1e-3
    rates = {}
    for cells in (None, 10000):
        s = FrontEndSettings(heavy_tail_cells=cells)
        mu = noise_estimate(y, s.cfar)
        out, shapes = heavy_tail_statistic(y / mu, s)
        alpha = os_threshold(pfa, s.cfar.n_reference, s.cfar.rank)
        rates[cells] = (float(np.mean(out[:4] >= alpha)), float(np.mean(out[4:] >= alpha)))
    # one shape for all beams: the spiky beams alarm far above the stated rate
    assert rates[None][1] > 4 * pfa
    # fitted per group: every group within a factor 2 of it
    assert all(0.5 * pfa < r < 2 * pfa for r in rates[10000])
    assert n_b * n_d > 0
