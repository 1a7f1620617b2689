"""The tma-sensitivity study: follows the study contract, its default reading of South winter *is*
tma-propagation's trial (same seed, same numbers), its intervals compute what they say; the quick preset
runs through the pipeline with figures."""

import json

import numpy as np
import pytest

from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.studies import tma_propagation as base
from sonartrack.studies import tma_sensitivity as study

SEED = 2019


@pytest.fixture(scope="module")
def quick():
    cfg = study.Config.quick()
    outs = [study.run_trial(cfg, trial_rng(SEED, i)) for i in range(cfg.runs)]
    trials = {k: np.stack([o[k] for o in outs]) for k in outs[0]}
    return cfg, trials, study.summarize(trials, cfg)


def test_contract_surface_and_toml_round_trip(tmp_path):
    assert study.STUDY_ID == "tma-sensitivity" and study.TITLE and study.PAPER and study.TRIAL_VERSION >= 1
    cfg = study.Config()
    # the scenario is tma-propagation's, field for field
    assert {k: v for k, v in cfg.model_dump().items() if k in base.Config.model_fields and k != "runs"} == \
        {k: v for k, v in base.Config().model_dump().items() if k != "runs"}
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg
    ids = [r.id for r in study.readings(cfg)]
    assert len(ids) == len(set(ids)) and ids[0] == "south-winter:default"


def test_quick_shapes(quick):
    cfg, trials, summary = quick
    reads = study.readings(cfg)
    assert summary["runs"] == cfg.runs and len(summary["readings"]) == len(reads) == len(summary["table"])
    for r, row in zip(reads, summary["readings"], strict=True):
        assert trials[f"{r.id}_em"].shape == (cfg.runs, 4)
        assert trials[f"{r.id}_sweep"].shape == (cfg.runs, len(study.deltas_of(cfg, r)), 2)
        assert len(row["em_rmse_ci_pct"]) == 4 and len(row["sweep_rmse_pct"]) == len(row["deltas_db"])
        assert row["under_10pct"] in ("holds", "fails", "undecided")
        assert row["leaning"] in ("under", "over", "symmetric", "none")
    json.dumps(summary)  # JSON-serialisable
    assert study.claims(summary, cfg) == []


def test_default_reading_is_tma_propagations_trial():
    """Same seed -> tma-propagation's South winter and East summer EM/MAP errors, bit for bit."""
    cfg = study.Config(south_depths_m=[], tl_windows_m=[], south_r_min_m=[], south_r_max_m=[], east_r_min_m=[],
                       east_depths_m=[], east_envs=["east-summer"], sl_mismatch_db=[0.0], south_sweep_db=[0.0],
                       east_fraction=1.0)
    mine = study.run_trial(cfg, trial_rng(SEED, 3))
    # sweep_fraction tiny: the flag is still drawn (same sequence) but the base trial skips the sweep
    theirs = base.run_trial(base.Config(sweep_fraction=1e-9), trial_rng(SEED, 3))
    np.testing.assert_array_equal(mine["south-winter:default_em"], theirs["south-winter_em"])
    np.testing.assert_array_equal(mine["east-summer:default_em"], theirs["east-summer_em"])


def test_chi2_interval_brackets_the_rmse_and_shrinks_with_n():
    lo, hi = study.chi2_rms_interval(5.0, 20)
    lo2, hi2 = study.chi2_rms_interval(5.0, 2000)
    assert lo < 5.0 < hi and lo < lo2 < 5.0 < hi2 < hi
    # n = 100: sqrt(100 / chi2_{0.975,100} = 129.56) = 0.8786
    assert study.chi2_rms_interval(1.0, 100)[0] == pytest.approx(0.8786, abs=2e-4)


def test_leaning_and_verdict():
    assert study._leaning(-18.0, 3.5) == "under" and study._leaning(-3.0, 6.0) == "over"
    assert study._leaning(-3.0, 3.0) == "symmetric" and study._leaning(None, None) == "none"
    assert study._verdict(True, False) == "holds" and study._verdict(False, True) == "fails"
    assert study._verdict(False, False) == "undecided"


def test_bootstrap_interval_of_a_known_sample():
    """The accuracy block on hand-made errors: RMSE of constant 3 % errors is 3 % with a zero-width interval."""
    cfg = study.Config.quick()
    r = study.readings(cfg)[0]
    em = np.full((40, 4), 3.0)
    em[:, 3] = 12.0
    em = np.vstack([em, np.full((5, 4), np.nan)])  # runs that skipped the reading do not count
    out = study._accuracy({f"{r.id}_em": em}, cfg, r)
    assert out["worst_pct"] == pytest.approx(12.0) and out["worst_ci_pct"] == pytest.approx([12.0, 12.0])
    assert out["under_10pct"] == "fails" and out["runs"] == 40


def test_quick_through_pipeline_with_figures(tmp_path):
    from sonartrack.experiment.pipeline import reproduce
    from sonartrack.report.figures import tma_sensitivity as figs

    def maker(study_id, summary, config):
        import matplotlib

        matplotlib.use("Agg")
        return figs.figures(summary, config)

    reproduce(study, study.Config.quick(), seed=1, out=tmp_path, workers=1, figures=maker)
    out = json.loads((tmp_path / "tma-sensitivity" / "summary.json").read_text())
    assert {"south_accuracy", "east_tolerated", "sensitivity_table"} <= set(out["figures"])
