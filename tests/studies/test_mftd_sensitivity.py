"""The mftd-sensitivity study: follows the study contract, its summary has the shapes the figures read, its
verdict functions decide hand-worked cases, and the readings meet the exhaustive detector where nothing is
pruned (N >= M^(K-1) for the branch sum, N >= M^K for the kept sum: every reading gives the same statistic)."""

import json

import numpy as np
import pytest

from sonartrack.core.random import trial_rng
from sonartrack.detection.mftd import MftdSettings
from sonartrack.io import toml as toml_io
from sonartrack.studies import mftd_sensitivity as study

SEED = 2024


def stack(outs):
    return {k: np.stack([o[k] for o in outs]) for k in outs[0]}


@pytest.fixture(scope="module")
def quick():
    cfg = study.Config.quick()
    trials = stack([study.run_trial(cfg, trial_rng(SEED, i)) for i in range(40)])
    return cfg, trials, study.summarize(trials, cfg)


def test_contract_surface_and_toml_round_trip(tmp_path):
    assert study.STUDY_ID == "mftd-sensitivity" and study.TITLE and study.PAPER and study.TRIAL_VERSION >= 1
    cfg = study.Config()
    assert cfg.runs >= 1000 and study.Config.quick().runs <= 500
    from sonartrack.studies import mftd

    assert [16, 64] in cfg.planes and cfg.detector == mftd.Config().detector  # the mftd study's default detector
    assert study.default_reading(cfg) == "16x64_smoothed_kept" and study.default_reading(cfg) in {
        r["id"] for r in cfg.readings()}
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg


def test_summary_shapes_and_figures(quick):
    cfg, trials, summary = quick
    json.dumps(summary)
    assert study.claims(summary, cfg) == []
    n_read = len(cfg.planes) * len(cfg.prior_densities) * len(cfg.finals)
    assert len(summary["readings"]) == n_read and len(summary["table"]) == 3 * n_read
    assert summary["pfa"] == pytest.approx(max(study.PFA_CLAIM, 10 / 40))
    for c in summary["readings"]:
        assert len(c["points"]["sigma"]) == len(cfg.sigma_a_family_mps2) == len(c["points"]["sigma_large_n"])
        assert len(c["points"]["n"]) == len(cfg.n_family)
        for p in (p for fam in c["points"].values() for p in fam):
            assert 0 <= p["pd_low"] <= p["pd"] <= p["pd_high"] <= 1 and p["n_h1"] == 40
    kept = summary["first_cell_kept"]["4x64"]
    assert all(len(v) == len(cfg.sigma_a_family_mps2) for v in kept.values())
    assert kept["1"] <= kept["10"] <= kept["30"]  # monotone in N, per sigma_a
    assert trials["first_rank_4x64"].shape == (40, len(cfg.sigma_a_family_mps2))
    import matplotlib.pyplot as plt

    from sonartrack.report.figures import mftd_sensitivity as figs

    out = figs.figures(summary, cfg)
    assert set(out) == {"sensitivity_table", "pd_vs_sigma_a", "pd_vs_n_saturation"}
    for f in out.values():
        plt.close(f)


def _mini(pds, var, cov=0.0, n=1000):
    """An mftd-like summary: curves c0.. with Pd ``pds`` (n H1 trials), bootstrap variance ``var`` each and
    covariance ``cov`` between any two (paired SE of a step: sqrt(2 (var - cov)))."""
    k = len(pds)
    c = np.full((k, k), cov) + np.eye(k) * (var - cov)
    names = [f"c{i}" for i in range(k)]
    return names, {"curves": {nm: {"pfa": [0.01], "pd": [p], "n_h1": n} for nm, p in zip(names, pds, strict=True)},
                   "steps": {"pfa": 0.01, "names": names, "covariance": c.tolist()}}


def test_verdicts_on_hand_worked_cases():
    from sonartrack.studies import mftd

    # independent curves of n = 1000 (var = p(1-p)/n ~ 2.4e-4): 0.5 -> 0.4 -> 0.3 falls twice; 0.5 -> 0.49 not
    names, s = _mini([0.5, 0.4, 0.3], 2.4e-4)
    assert mftd.trend_verdict(s, names, 0.01, increasing=False) == (True, False, True)
    names, s = _mini([0.5, 0.49, 0.3], 2.4e-4)
    assert mftd.trend_verdict(s, names, 0.01, increasing=False) == (False, False, False)
    # strongly paired curves: a step of 0.01 with paired SE sqrt(2 (2.4e-4 - 2.3e-4)) = 0.0045 is a fall
    # (2.2 SE), though not by the unpaired binomial SE (0.022)
    names, s = _mini([0.5, 0.49], 2.4e-4, cov=2.3e-4)
    assert mftd.trend_verdict(s, names, 0.01, increasing=False) == (True, False, False)
    assert mftd._step_se(s, "c0", "c1") == pytest.approx(np.sqrt(2e-5))
    # rises and saturates: 0.2, 0.4, 0.5, 0.51 -> within 1.96 SE of 0.51 from N = 10 (both SEs)
    names, s = _mini([0.2, 0.4, 0.5, 0.51], 2.4e-4)
    assert mftd.saturation_verdict(s, names, [1, 3, 10, 30], 0.01, 0) == (True, 10)
    assert mftd.saturation_verdict(s, names, [1, 3, 10, 30], 0.01, 1) == (True, 10)
    # the same curves strongly paired: 0.5 -> 0.51 is significant, so no saturation before the largest N
    names, s = _mini([0.2, 0.4, 0.5, 0.51], 2.4e-4, cov=2.35e-4)
    assert mftd.saturation_verdict(s, names, [1, 3, 10, 30], 0.01, 0) == (False, 30)
    # flat: saturated from the start, but no rise
    names, s = _mini([0.3, 0.3, 0.3], 2.4e-4)
    assert mftd.saturation_verdict(s, names, [1, 3, 10], 0.01, 0) == (False, 1)


def test_every_reading_is_exhaustive_when_nothing_is_pruned():
    """1 x 4 plane, K = 2 (M = 4): with N >= M^(K-1) = 4 the branch sum is the exhaustive statistic and with
    N >= M^K = 16 the kept sum is too, so these curves agree trial by trial; the first cell is always kept
    at N >= M; and equal Pd along N is no rise (the N claim cannot hold)."""
    cfg = study.Config(runs=12, planes=[[1, 4]], n_frames=2, detector=MftdSettings(sigma_a_mps2=0.25, n_tracks=4),
                       sigma_a_family_mps2=[0.25], n_family=[4, 16], large_n=16)
    trials = stack([study.run_trial(cfg, trial_rng(SEED, i)) for i in range(12)])
    for dens in cfg.prior_densities:
        for h in ("h0", "h1"):
            ref = trials[f"{h}_{study.curve_id(study.reading_id([1, 4], dens, 'branches'), 0.25, 4)}"]
            for fin, n in (("branches", 16), ("kept", 16)):
                got = trials[f"{h}_{study.curve_id(study.reading_id([1, 4], dens, fin), 0.25, n)}"]
                np.testing.assert_allclose(got, ref, rtol=1e-9)
            pruned = trials[f"{h}_{study.curve_id(study.reading_id([1, 4], dens, 'kept'), 0.25, 4)}"]
            assert np.all(pruned <= ref + 1e-12)  # the kept sum of 4 of 16 tracks is a part of the whole sum
    summary = study.summarize(trials, cfg)
    assert summary["first_cell_kept"]["1x4"]["4"] == [1.0]
    branches = next(c for c in summary["readings"] if c["id"] == "1x4_smoothed_branches")
    assert branches["claims"]["pd_rises_with_n_and_saturates"]["pd"][0] == \
        branches["claims"]["pd_rises_with_n_and_saturates"]["pd"][1]
    assert not branches["claims"]["pd_rises_with_n_and_saturates"]["holds"]


def test_reproduce_end_to_end(tmp_path):
    from sonartrack.experiment import pipeline
    from sonartrack.report.figures import mftd_sensitivity as figs

    cfg = pipeline.resolve_config(study, quick=True, runs=20)
    res = pipeline.reproduce(study, cfg, seed=1, out=tmp_path, workers=1, figures=lambda sid, s, c: figs.figures(s, c))
    assert res.runs == 20 and res.n_claims == 0
    doc = json.loads((tmp_path / "mftd-sensitivity" / "summary.json").read_text())
    assert doc["summary"]["runs"] == 20 and len(doc["figures"]) == 3
