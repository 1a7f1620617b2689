"""The bftma-sensitivity study: follows the study contract, its default reading *is* bftma-imm's claim on the
same trials, its definitions and intervals compute what they say."""

import json

import numpy as np
import pytest

from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.studies import bftma_imm
from sonartrack.studies import bftma_sensitivity as study

SEED, N = 2017, 3


def stack(outs):
    return {k: np.stack([o[k] for o in outs]) for k in outs[0]}


@pytest.fixture(scope="module")
def quick():
    cfg = study.Config.quick()
    trials = stack([study.run_trial(cfg, trial_rng(SEED, i)) for i in range(N)])
    return cfg, trials, study.summarize(trials, cfg)


def test_contract_surface_and_toml_round_trip(tmp_path):
    assert study.STUDY_ID == "bftma-sensitivity" and study.TITLE and study.PAPER and study.TRIAL_VERSION >= 1
    cfg = study.Config()
    assert cfg.runs >= 200 and study.Config.quick().runs <= 5
    # the scenario is bftma-imm's, field for field
    assert {k: v for k, v in cfg.model_dump().items() if k in bftma_imm.Config.model_fields and k != "runs"} == \
        {k: v for k, v in bftma_imm.Config().model_dump().items() if k != "runs"}
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg
    assert cfg.chi2_threshold == pytest.approx(13.8155, rel=1e-4)  # chi-square(2) 99.9 % quantile


def test_default_reading_is_bftma_imms_claim_on_the_same_trials(quick):
    """Same seed, same trials: the default cell counts exactly what bftma-imm's mgekf-divergence-end counts,
    and the 'turn' checkpoint what mgekf-divergence-turn counts."""
    cfg, trials, summary = quick
    bcfg = bftma_imm.Config(runs=N)
    bsum = bftma_imm.summarize(stack([bftma_imm.run_trial(bcfg, trial_rng(SEED, i)) for i in range(N)]), bcfg)
    for key, where in (("diverged_end", -1), ("diverged_turn", 0)):
        n = {f: sum(c[key] for c in bsum["cases"].values() if c["filter"] == f) for f in ("mgekf", "ekf")}
        d = {"id": "x", "where": where % len(cfg.checkpoints_s()), "thr": 0.25, "nees": False}
        reading = study.readings(cfg)[0]
        got = {f: sum(int(study.diverged_flags(trials, p[i], d, cfg).sum()) for p in study.reading_pairs(cfg, reading))
               for i, f in enumerate(("mgekf", "ekf"))}
        assert got == n
    cell = summary["cells"]["default"]["end_25"]
    assert (cell["n_mgekf"], cell["n_ekf"]) == (sum(c["diverged_end"] for c in bsum["cases"].values()
                                                    if c["filter"] == "mgekf"),
                                                sum(c["diverged_end"] for c in bsum["cases"].values()
                                                    if c["filter"] == "ekf"))


def test_definitions_on_hand_made_trials():
    """rel = [turn, 1500, 1800, 2100, end, max after turn, min over last window]; nees at the checkpoints."""
    cfg = study.Config.quick()
    rel = np.array([[0.01, 0.3, 0.2, 0.2, 0.2, 0.3, 0.2],    # crossed 25 % once, recovered
                    [0.01, 0.3, 0.3, 0.3, 0.3, 0.3, 0.26],   # diverged and stayed
                    [0.01, 0.1, 0.1, 0.1, np.nan, np.nan, np.nan]])  # filter failed: NaN counts as diverged
    nees = np.array([[1, 50, 50, 50, 50], [1, 2, 2, 2, 2], [1, 1, 1, 1, np.nan]], float)
    trials = {"v__c__rel": rel, "v__c__nees": nees}
    defs = {d["id"]: d for d in study.definitions(cfg)}
    flags = {k: study.diverged_flags(trials, "v__c", defs[k], cfg).tolist()
             for k in ("end_25", "any_25", "persist_25", "t1500_25", "end_nees", "end_25_nees", "end_10")}
    assert flags == {"end_25": [False, True, True], "any_25": [True, True, True], "persist_25": [False, True, True],
                     "t1500_25": [True, True, False], "end_nees": [True, False, True],
                     "end_25_nees": [False, False, True], "end_10": [True, True, True]}


def test_cell_intervals_and_paired_difference():
    """4 runs, the 8 pairs of a reading, divergence in two of them: MGEKF per-run sums [2, 1, 1, 0], EKF
    [0, 0, 1, 0]; paired per-run differences [2, 1, 0, 0]."""
    cfg = study.Config.quick()
    reading = {"id": "r", "variant": "v", "bank": 0}
    pairs = study.reading_pairs(cfg, reading)
    end = len(cfg.checkpoints_s()) - 1
    trials = {}
    mg = {pairs[0][0]: [1, 1, 0, 0], pairs[1][0]: [1, 0, 1, 0]}
    ek = {pairs[0][1]: [0, 0, 1, 0], pairs[1][1]: [0, 0, 0, 0]}
    for a, b in pairs:
        for key, on in ((a, mg.get(a, [0] * 4)), (b, ek.get(b, [0] * 4))):
            rel = np.zeros((4, end + 3))
            rel[:, end] = np.where(np.array(on) > 0, 0.9, 0.1)
            trials[f"{key}__rel"], trials[f"{key}__nees"] = rel, np.ones((4, end + 1))
    cell = study._cell(trials, cfg, reading, {"where": end, "thr": 0.25, "nees": False})
    assert (cell["n_mgekf"], cell["n_ekf"], cell["total"]) == (4, 1, 4 * len(pairs))
    d = np.array([2, 1, 1, 0]) - np.array([0, 0, 1, 0])
    half = 1.96 * d.std(ddof=1) / 2.0
    assert cell["diff_ci"] == pytest.approx([4 * (d.mean() - half), 4 * (d.mean() + half)])
    assert cell["mgekf_ci"][0] < 4 < cell["mgekf_ci"][1] and not cell["holds"]


def test_summary_figures_and_no_claims(quick):
    cfg, _, summary = quick
    json.dumps(summary)
    assert study.claims(summary, cfg) == []
    n_reads, n_defs = len(study.readings(cfg)), len(study.definitions(cfg))
    assert len(summary["table"]) == n_reads + n_defs - 1
    assert all(len(summary["cells"][r["id"]]) == n_defs for r in summary["readings"])
    assert set(summary["series"]) == {f"{m}_{f}_q{q:g}" for m in ("bf", "b") for f in ("mgekf", "ekf")
                                      for q in cfg.imm.q_values}
    import matplotlib.pyplot as plt

    from sonartrack.report.figures import bftma_sensitivity as figs

    out = figs.figures(summary, cfg)
    assert set(out) == {"sensitivity_grid", "sensitivity_table", "per_pair_counts", "error_and_nees"}
    for f in out.values():
        plt.close(f)


def test_reproduce_end_to_end(tmp_path):
    from sonartrack.experiment import pipeline
    from sonartrack.report.figures import bftma_sensitivity as figs

    cfg = pipeline.resolve_config(study, quick=True, runs=2)
    res = pipeline.reproduce(study, cfg, seed=1, out=tmp_path, workers=1,
                             figures=lambda sid, s, c: figs.figures(s, c))
    assert res.runs == 2 and res.n_claims == 0
    doc = json.loads((tmp_path / "bftma-sensitivity" / "summary.json").read_text())
    assert doc["summary"]["runs"] == 2 and len(doc["figures"]) == 4
    assert (tmp_path / "bftma-sensitivity" / "sensitivity_table.png").exists()
