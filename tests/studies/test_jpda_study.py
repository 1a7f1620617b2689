"""The jpda-amplitude study follows the study contract and its geometry matches its definitions."""

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.studies import jpda_amplitude as study
from sonartrack.tracking.settings import BearingTrackerSettings


@pytest.fixture(scope="module")
def small():
    cfg = study.Config(runs=3, crossing_angles_deg=[20.0, 90.0], min_distances_deg=[1.0, 6.0], e2e_duration_s=30)
    outs = [study.run_trial(cfg, trial_rng(1994, i)) for i in range(3)]
    return cfg, {k: np.stack([o[k] for o in outs]) for k in outs[0]}


def test_contract_surface():
    mod = studies.load("jpda-amplitude")
    assert mod.STUDY_ID == "jpda-amplitude" and mod.TITLE and mod.PAPER and mod.TRIAL_VERSION >= 1
    cfg = mod.Config()
    assert cfg.runs == 100 and cfg.tracker.gate_deg == 10.0 and cfg.tracker.amplitude_threshold == 5000.0
    assert mod.Config.quick().runs < cfg.runs


def test_config_round_trips_through_toml(tmp_path):
    cfg = study.Config.quick()
    p = tmp_path / "c.toml"
    p.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(p)) == cfg


def test_trackers_assume_the_simulated_clutter():
    cfg = study.Config()
    assert cfg.tracker == BearingTrackerSettings()  # P0's values are the library defaults
    assert cfg.tracker.clutter_density_per_deg == cfg.model().false_density_per_deg
    with pytest.raises(ValueError, match="clutter_density_per_deg"):
        study.Config(false_rate=3.0)


def test_geometries_follow_their_definitions():
    cfg = study.Config()
    for kind, val, truth in cfg.geometries():
        gap = np.abs(truth[:, 0] - truth[:, 1])
        if kind == "psi":
            slope = np.diff(truth[:, 0])[0] - np.diff(truth[:, 1])[0]
            assert np.rad2deg(2 * np.arctan(slope / 2)) == pytest.approx(val)
            assert gap.min() < 1.0
        else:
            assert gap.min() == pytest.approx(val, abs=1e-6)
        assert gap[-1] > 2 * cfg.success_tolerance_deg  # success at the end is unambiguous


def test_encounter_metrics_by_hand(small):
    """Two tracks 1 deg off their targets (GOSPA 2^(1/2) deg, p = 2) whose ids swap at the middle scan only: the
    assignment follows the positions (GOSPA stays 2^(1/2)), each target changes id there and again at the next
    scan (s = 2 at each), so the switching term lambda s^(1/2) = 2.5 x 2^(1/2) at those two scans."""
    cfg, _ = small
    truth = np.column_stack([np.full(5, 80.0), np.full(5, 100.0)])
    est = truth + 1.0
    est[2] = est[2, ::-1]
    g, sw = study.encounter_metrics(cfg, est, truth)
    d = np.full(5, np.sqrt(2.0))
    d[2:4] = np.hypot(np.sqrt(2.0), 2.5 * np.sqrt(2.0))
    assert sw == 2 + 2  # swapped away and back
    np.testing.assert_allclose(g, np.mean(d))


def test_trials_summary_claims_figures(small):
    cfg, trials = small
    again = study.run_trial(cfg, trial_rng(1994, 2))
    for k, v in again.items():
        np.testing.assert_array_equal(v, trials[k][2])
        assert k.endswith(study.METRIC_KEYS) or set(np.unique(v)) <= {0.0, 1.0}
    s = study.summarize(trials, cfg)
    assert set(s["metrics"]) == {f"{c}_{t}{m}" for c in study.CASES for t in study.TRACKERS for m in study.METRIC_KEYS}
    assert set(s["rates"]) == {f"{c}_{t}" for c in study.CASES for t in study.TRACKERS}
    out = study.claims(s, cfg)
    assert {c.id for c in out} >= {"jpda_a_about_90pct", "jpda_falls_with_psi", "jpda_falls_with_L",
                                      "similar_strengths_close", "end_to_end_from_sound"}
    from sonartrack.report.figures import study_figures

    figs = study_figures(study.STUDY_ID, s, cfg)
    assert not hasattr(study, "figures")
    assert list(figs)[0] == "scenario" and "success_rates" in figs
    import matplotlib.pyplot as plt

    for f in figs.values():
        plt.close(f)
