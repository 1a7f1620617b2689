"""The mftd study follows the study contract and its summary agrees with its pieces."""

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.models.swerling import clairvoyant_pd, single_frame_plane_pd
from sonartrack.studies import mftd as study


@pytest.fixture(scope="module")
def small():
    cfg = study.Config(runs=40, n_range=8, n_doppler=32, n_family=[1, 10], sigma_a_family_mps2=[0.5, 1.0],
                       snr_family_db=[5.0, 8.0], large_n=20, h1_fraction=0.6)
    outs = [study.run_trial(cfg, trial_rng(1996, i)) for i in range(40)]
    return cfg, {k: np.stack([o[k] for o in outs]) for k in outs[0]}


def test_contract_surface():
    mod = studies.load("mftd")
    assert mod.STUDY_ID == "mftd" and mod.TITLE and mod.PAPER and mod.TRIAL_VERSION >= 1
    cfg = mod.Config()
    assert (cfg.detector.period_s, cfg.plane.pulse_s, cfg.plane.carrier_hz, cfg.plane.sound_speed_mps) == (
        2.0, 0.125, 30e3, 1500.0)
    assert (cfg.n_frames, cfg.detector.n_tracks, cfg.detector.snr_db, cfg.detector.sigma_a_mps2) == (6, 10, 5.0, 1.0)
    # the study nests the same declarations as `sonartrack detect` (one declaration per group)
    from sonartrack.detection.detect import DetectSettings

    assert type(cfg.plane) is type(DetectSettings().plane) and type(cfg.detector) is type(DetectSettings().detector)
    assert cfg.runs * 1e-3 >= 10 and mod.Config.quick().runs < cfg.runs  # full size reaches Pfa 1e-3


def test_config_round_trips_through_toml(tmp_path):
    cfg = study.Config.quick()
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg


def test_variants_cover_every_family_once():
    cfg = study.Config()
    v = cfg.variants()
    assert len(set(v.values())) == len(v)
    for fam in ("snr", "sigma", "sigma_large_n", "n", "density"):
        for _, name in cfg.family(fam):
            assert name in v


def test_trial_is_deterministic_and_scalar(small):
    cfg, trials = small
    a = study.run_trial(cfg, trial_rng(1996, 3))
    for k, val in a.items():
        assert np.shape(val) == ()
        np.testing.assert_array_equal(val, trials[k][3])
    # a target makes the statistic larger on the same noise far more often than smaller, at every variant
    # (with the kept sum of eq. 20 the statistic is unchanged where the target's track is pruned)
    for name in cfg.variants():
        ok = np.isfinite(trials[f"h1_{name}"])
        h1, h0 = trials[f"h1_{name}"][ok], trials[f"h0_{name}"][ok]
        assert ok.sum() >= 10 and np.mean(h1 > h0) > np.mean(h1 < h0) + 0.3


def test_summary_claims_and_figures(small):
    cfg, trials = small
    s = study.summarize(trials, cfg)
    assert s["pfa"] == [p for p in study.PFA_GRID if p >= 10 / 40 - 1e-15]
    ref = s["references"]["5"]
    np.testing.assert_allclose(ref["clairvoyant"], clairvoyant_pd(np.array(s["pfa"]), 10 ** 0.5, 6))
    np.testing.assert_allclose(ref["single_frame"], single_frame_plane_pd(np.array(s["pfa"]), 10 ** 0.5, 256))
    for c in s["curves"].values():
        assert np.all(np.diff(c["pd"]) >= 0)  # a ROC never decreases with Pfa
        assert np.all(np.array(c["pd_low"]) <= c["pd"]) and np.all(np.array(c["pd"]) <= c["pd_high"])
    out = [c.as_dict() for c in study.claims(s, cfg)]
    assert {c["id"] for c in out} >= {"pd_rises_with_snr", "pd_falls_with_sigma_a", "pd_rises_with_n_and_saturates",
                                      "between_bounds", "k1_closed_form"}
    for c in out:
        assert set(c) == {"id", "text", "paper", "ours", "tolerance", "holds"} and isinstance(c["holds"], bool)
    from sonartrack.report.figures import study_figures

    figs = study_figures("mftd", s, cfg)
    assert list(figs)[0] == "scenario" and {"roc_families", "roc_checks"} <= set(figs)
    import matplotlib.pyplot as plt

    for f in figs.values():
        assert f.axes
        plt.close(f)


def test_paired_bootstrap_matches_binomial_and_paired_se():
    """With a fixed threshold (every H0 statistic 0) Pd is a binomial proportion: the bootstrap variance of
    one curve is p (1 - p) / n1, and the SE of the step between two curves that differ in d trials only is
    the paired SE of the per-trial difference (metrics/statistics.py), far below the unpaired one."""
    from sonartrack.metrics.statistics import paired_difference

    rng = np.random.default_rng(3)
    n = 4000
    a = rng.random(n) < 0.3
    b = a.copy()
    b[rng.choice(np.flatnonzero(a), 60, replace=False)] = False  # b misses 60 of a's detections
    h1a, h1b = np.where(a, 1.0, -1.0), np.where(b, 1.0, -1.0)
    absent = rng.random(n) < 0.5  # target-present stacks in half of the trials only, as h1_fraction does
    h1a[absent], h1b[absent] = np.nan, np.nan
    trials = {"h0_a": np.zeros(n), "h1_a": h1a, "h0_b": np.zeros(n), "h1_b": h1b}
    boot = study.pd_bootstrap(trials, ["a", "b"], 0.01, 2000, seed=5)
    n1 = int(np.sum(~absent))
    p = np.mean(a[~absent])
    assert np.var(boot[:, 0]) == pytest.approx(p * (1 - p) / n1, rel=0.15)
    assert np.mean(boot[:, 0]) == pytest.approx(p, abs=0.003)
    _, se_paired = paired_difference(a[~absent].astype(float), b[~absent].astype(float))
    se_boot = np.std(boot[:, 0] - boot[:, 1])
    assert se_boot == pytest.approx(se_paired, rel=0.15)
    assert se_boot < 0.3 * np.sqrt(2 * p * (1 - p) / n1)  # the unpaired SE would be > 3x larger


def test_step_se_and_claims_use_the_bootstrap(small):
    cfg, trials = small
    s = study.summarize(trials, cfg)
    st = s["steps"]
    assert st["names"] == list(cfg.variants()) and np.shape(st["covariance"]) == (len(st["names"]),) * 2
    # identical curves: a step of exactly zero SE and never significant
    assert study._step_se(s, "default", "default") == 0.0
    assert study._rises(s, "default", "default", st["pfa"]) == (False, False)
