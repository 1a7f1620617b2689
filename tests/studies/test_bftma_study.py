"""The bftma-imm study follows the study contract and its pieces agree with each other."""

import json

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.experiment.claims import Claim
from sonartrack.io import toml as toml_io
from sonartrack.report.figures import study_figures
from sonartrack.studies import bftma_imm as study
from sonartrack.tma.settings import ImmSettings

FIGURES = {"scenario", "rmse_position", "rmse_velocity", "rmse_course_speed", "mode_probabilities", "divergence"}


@pytest.fixture(scope="module")
def quick_trials():
    cfg = study.Config.quick()
    outs = [study.run_trial(cfg, trial_rng(2017, i)) for i in range(4)]
    return cfg, {k: np.stack([o[k] for o in outs]) for k in outs[0]}


def test_contract_surface():
    mod = studies.load("bftma-imm")
    assert mod.STUDY_ID == "bftma-imm" and mod.TITLE and mod.PAPER and mod.TRIAL_VERSION >= 1
    cfg = mod.Config()
    assert cfg.runs >= 100 and mod.Config.quick().runs < cfg.runs
    assert cfg.imm == ImmSettings()  # the IMM bank is the one of sonartrack tma, with the same defaults
    assert len(cfg.observer_turns) >= 1 and cfg.f0_hz == 300.0 and cfg.sigma_bearing_deg == 1.0
    assert 0.05 <= cfg.sigma_freq_hz <= 0.1


def test_config_round_trips_through_toml(tmp_path):
    cfg = study.Config.quick()
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    again = toml_io.validate(study.Config, toml_io.load(path))
    assert again == cfg


def test_trial_is_deterministic_with_fixed_shapes(quick_trials):
    cfg, trials = quick_trials
    a = study.run_trial(cfg, trial_rng(2017, 1))
    for k, v in a.items():
        np.testing.assert_array_equal(v, trials[k][1])
    n_rec = len(cfg.record_index())
    for case, (_, _, qs) in cfg.cases().items():
        assert trials[f"{case}_pos"].shape == (4, n_rec)
        if len(qs) > 1:
            assert trials[f"{case}_mu"].shape == (4, n_rec, len(cfg.imm.q_values))
            np.testing.assert_allclose(np.nansum(trials[f"{case}_mu"], axis=-1), 1.0)
    b = study.run_trial(cfg, trial_rng(2017, 2))
    assert not np.array_equal(a["bf_mgekf_imm_pos"], b["bf_mgekf_imm_pos"])


def test_truth_of_the_scenario():
    """The geometry matches the documented choices: range ~10 km at the start, target turn of 90 deg."""
    cfg = study.Config()
    t = cfg.times_s()
    _, vt, ht = cfg.target().state(t)
    po, vo, _ = cfg.observer().state(t)
    pt, _, _ = cfg.target().state(t)
    r = np.hypot(*(pt - po).T)
    assert 9500 < r[0] < 10500 and r.min() > 6000 and r.max() < 11000
    assert np.rad2deg(ht[-1] - ht[0]) == pytest.approx(-90.0)
    assert np.hypot(*vt[0]) == pytest.approx(10 * 1852 / 3600)
    assert np.hypot(*vo[0]) == pytest.approx(5 * 1852 / 3600)


def test_summary_claims_and_figures(quick_trials):
    cfg, trials = quick_trials
    summary = study.summarize(trials, cfg)
    json.dumps(summary)  # JSON-serialisable
    case = summary["cases"]["bf_mgekf_imm"]
    assert len(case["rmse_pos_m"]) == len(cfg.record_index())
    # time-averaged RMSE is the root of the mean of the per-run mean squares
    assert case["rmse_pos_all_m"] == pytest.approx(np.sqrt(np.mean(case["per_run_mse_all"])))
    claims = study.claims(summary, cfg)
    ids = {c.id for c in claims}
    assert {"imm-beats-single-all", "imm-beats-single-post", "frequency-helps", "mgekf-divergence-turn",
            "mgekf-divergence-end"} <= ids
    for c in claims:
        assert isinstance(c, Claim) and c.text and c.paper and c.ours and c.tolerance
        assert isinstance(c.holds, bool)
    import matplotlib.pyplot as plt

    assert not hasattr(study, "figures")  # the pictures live in report/figures/bftma_imm.py
    figs = study_figures("bftma-imm", summary, cfg)
    assert set(figs) >= FIGURES
    for f in figs.values():
        plt.close(f)


def test_reproduce_end_to_end(tmp_path):
    from sonartrack.experiment import pipeline

    cfg = pipeline.resolve_config(study, quick=True, runs=3)
    res = pipeline.reproduce(study, cfg, seed=1, out=tmp_path, workers=1, figures=study_figures)
    assert res.runs == 3 and res.n_claims >= 5
    folder = tmp_path / "bftma-imm"
    doc = json.loads((folder / "summary.json").read_text())
    assert set(doc["figures"]) >= FIGURES
    assert all((folder / f"{name}.png").exists() for name in FIGURES)
