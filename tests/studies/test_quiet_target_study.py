"""The quiet-target study follows the study contract, its single-window curves match their closed forms, and its
claims read the summary."""

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.studies import quiet_target as study


@pytest.fixture(scope="module")
def quick():
    cfg = study.Config.quick()
    outs = [study.run_trial(cfg, trial_rng(21, i)) for i in range(cfg.runs)]
    trials = {k: np.stack([o[k] for o in outs]) for k in outs[0]}
    return cfg, trials, study.summarize(trials, cfg)


def test_contract_surface(tmp_path):
    mod = studies.load("quiet-target")
    assert mod.STUDY_ID == "quiet-target" and mod.TITLE and mod.PAPER and mod.TRIAL_VERSION >= 1
    cfg = mod.Config.quick()
    assert cfg.runs < mod.Config().runs
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg


def test_trial_is_deterministic_with_fixed_shapes(quick):
    cfg, trials, _ = quick
    a = study.run_trial(cfg, trial_rng(21, 3))
    for k, v in a.items():
        np.testing.assert_array_equal(v, trials[k][3])
    assert a["mftd_gaussian"].shape == (len(cfg.snr_grid_db[0]),)
    assert a["lofar_long"].shape == (len(cfg.tonal_grid_db),)


def test_single_window_levels_match_closed_forms(quick):
    """Single window at pfa 1e-3: Gaussian Pd = 0.5 at mu = Phi^-1(1 - pfa) = 3.09 (9.8 dB); Swerling 1
    Pd = pfa^(1/(1+rho)) = 0.5 at 1 + rho = ln(pfa) / ln(0.5) = 9.97 (9.5 dB)."""
    _, _, s = quick
    for stat, closed_form_db in (("gaussian", 9.8), ("exponential", 9.5)):
        _, lo, hi = s[stat]["level50_single"]
        # the bootstrap interval over the quick preset's 40 trials (+- half a 1.5 dB grid step) holds the closed form
        assert lo - 0.75 <= closed_form_db <= hi + 0.75, (stat, lo, hi)
        assert hi - lo < 6.0


def test_level_at_interpolates():
    assert study.level_at([0, 1, 2], [0.0, 0.4, 0.8], 0.6) == pytest.approx(1.5)
    assert np.isnan(study.level_at([0, 1], [0.0, 0.1], 0.5))
    assert study.level_at([0, 1], [0.9, 1.0], 0.5) == 0.0


def test_claims_read_the_summary(quick):
    cfg, _, s = quick
    cl = {c.id: c for c in study.claims(s, cfg)}
    assert set(cl) == {"mftd-gain-gaussian", "mftd-gain-exponential", "mftd-false-rate-gaussian",
                       "mftd-false-rate-exponential", "lofar-integration-gain"}
    g = s["gaussian"]["gain50_db"]
    assert cl["mftd-gain-gaussian"].holds == (g[0] >= study.MFTD_GAIN_REQUIRED_DB)
    assert g[1] <= g[0] <= g[2]
