"""The P4 study's contract: config round trip, trial shapes, summary and claims on a small run."""

import numpy as np
import pytest

from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.studies import bistatic_imm_ipda as p4
from sonartrack.tracking.settings import PositionTrackerSettings


def test_config_round_trips_through_toml():
    cfg = p4.Config()
    back = p4.Config.model_validate(__import__("tomllib").loads(toml_io.dumps(cfg.model_dump(mode="json"))))
    assert back == cfg


def test_the_trackers_are_the_library_default_but_for_q():
    """The study declares no tracker setting of its own: each case is the library's tracker with its modes."""
    cfg = p4.Config()
    for q in cfg.cases().values():
        s = cfg.tracker_settings(q)
        assert s.q == list(q)
        assert s.model_dump(exclude={"q"}) == PositionTrackerSettings().model_dump(exclude={"q"})
    assert cfg.tracker.pd == cfg.pd and cfg.tracker.clutter_density_per_m2 == cfg.clutter_density_per_m2
    with pytest.raises(ValueError, match="three modes"):
        p4.Config(tracker=PositionTrackerSettings(q=[1e-4, 0.05]))


def test_figures_are_drawn_from_the_summary():
    import matplotlib.pyplot as plt

    from sonartrack.report.figures import study_figures

    cfg = p4.Config(n_scans=12, turn_start_s=180.0, runs=2)
    trials = [p4.run_trial(cfg, trial_rng(2, i)) for i in range(2)]
    s = p4.summarize({k: np.stack([t[k] for t in trials]) for k in trials[0]}, cfg)
    figs = study_figures(p4.STUDY_ID, s, cfg)
    assert list(figs)[0] == "scenario" and {"ctt_rate", "mode_probabilities"} <= set(figs)
    assert not hasattr(p4, "figures")
    for f in figs.values():
        plt.close(f)


def test_scenario_matches_the_paper():
    cfg = p4.Config()
    assert cfg.n_scans * cfg.scan_period_s == 3000.0
    region = cfg.sonar().region
    assert abs(region.area_m2 * cfg.clutter_density_per_m2 - 40.0) < 1e-9  # 40 clutter points a scan
    truth = cfg.target_states()
    assert np.allclose(np.hypot(truth[:, 2], truth[:, 3]), 3.0, atol=0.01)  # 3 m/s
    assert region.contains(truth[:, :2]).all()  # the target stays inside the clutter region
    ship = cfg.ownship()
    _, vel, heading = ship.state(np.array([0.0, 1499.0, 1500.0 + 100.0]))
    assert np.allclose(np.hypot(vel[:, 0], vel[:, 1]), 2.5)
    assert heading[0] == heading[1] and np.isclose(heading[2] - heading[1], np.deg2rad(0.08) * 100.0)
    # closing target: range shrinks
    pos, _, _ = ship.state(cfg.times_s())
    rng = np.hypot(*(truth[:, :2] - pos).T)
    assert rng[-1] < rng[0] - 5000


def test_trial_is_deterministic_and_shaped():
    cfg = p4.Config(n_scans=15, turn_start_s=210.0)
    a = p4.run_trial(cfg, trial_rng(3, 0))
    b = p4.run_trial(cfg, trial_rng(3, 0))
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])
        per_run = k == "n_measurements" or k.endswith(p4.SET_METRICS)
        assert a[k].shape[0] == (1 if k.endswith(p4.SET_METRICS) else 15) or per_run
    assert set(f"{c}_ctt" for c in cfg.cases()) <= a.keys()


def test_set_metrics_by_hand():
    """Five scans 30 s apart, target at the origin: track 4 holds it 100 m off at scans 1-2, nothing at scan 3,
    track 9 200 m off at scan 4, and track 5 is 5 km away (false) throughout. Cut-off 1000 m, p = 1: GOSPA per
    scan = (localisation or c/2 missed) + c/2 false; switching penalty c/2 x s_k (s: 0, 0, 0, 1/2, 1/2)."""
    cfg = p4.Config(n_scans=5, turn_start_s=60.0, metric_cutoff_m=1000.0)
    truth = np.zeros((5, 4))
    rows = [(30.0, 4, 100.0, 0.0), (60.0, 4, 0.0, 100.0), (120.0, 9, 200.0, 0.0)]
    rows += [(t, 5, 5000.0, 0.0) for t in (0.0, 30.0, 60.0, 90.0, 120.0)]
    m = p4.set_metrics(cfg, truth, np.array(rows, float))
    d = np.array([500 + 500, 100 + 500, 100 + 500, 500 + 500, 200 + 500], float)
    s = np.array([0, 0, 0, 0.5, 0.5]) * 500.0
    np.testing.assert_allclose(m["gospa_m"], [np.mean(np.hypot(d, s))])
    assert m["segments"].tolist() == [2.0] and m["switches"].tolist() == [1.0]
    np.testing.assert_allclose(m["confirm_s"], [30.0])


def test_summary_and_claims_are_computed_from_trials():
    cfg = p4.Config(n_scans=20, turn_start_s=300.0, runs=3)
    trials = [p4.run_trial(cfg, trial_rng(1, i)) for i in range(3)]
    stacked = {k: np.stack([t[k] for t in trials]) for k in trials[0]}
    s = p4.summarize(stacked, cfg)
    assert np.allclose(s["cases"]["imm2"]["ctt_rate"], stacked["imm2_ctt"].mean(axis=0))
    cl = p4.claims(s, cfg)
    assert len({c.id for c in cl}) == len(cl) == 7
    assert all(isinstance(c.holds, bool) for c in cl)
    # a claim must be able to fail: make IMM-IPDA's CTT rate zero and the exp claims fail
    broken = {**stacked, "imm2_ctt": np.zeros_like(stacked["imm2_ctt"]),
              "ipda_small_ctt": np.ones_like(stacked["ipda_small_ctt"])}
    sb = p4.summarize(broken, cfg)
    assert not next(c for c in p4.claims(sb, cfg) if c.id == "exp1-imm-best").holds
    assert next(c for c in p4.claims(sb, cfg) if c.id == "large-q-before").holds is False
