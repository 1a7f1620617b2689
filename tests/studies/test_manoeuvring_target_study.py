"""The manoeuvring-target study: follows the study contract; its scenes are the family it states; its noncentrality
is the GLR's (checked against the nonlinear two-leg fit on a noise-free record); its CV test rejects a zig and keeps
a straight leg; its summary and claims have their shape on a tiny run."""

import json

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.core.units import KNOT_MPS
from sonartrack.io import toml as toml_io
from sonartrack.sim.manoeuvre_scene import OWN_PATTERNS, ManoeuvreSceneSettings, draw_manoeuvre_scene
from sonartrack.studies import manoeuvring_target as study


def test_contract_surface_and_toml_round_trip(tmp_path):
    mod = studies.load("manoeuvring-target")
    assert mod is study and study.STUDY_ID == "manoeuvring-target" and study.TITLE and study.PAPER
    cfg = study.Config.quick()
    assert cfg.runs <= study.Config().runs
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg


def test_scenes_are_the_stated_family():
    s = ManoeuvreSceneSettings()
    patterns, cv = set(), 0
    for seed in range(40):
        sc = draw_manoeuvre_scene(s, np.random.default_rng(seed))
        patterns.add(sc.own_pattern)
        t, c = sc.time_s, sc.change_times_s
        legs = np.diff(np.r_[t[0], c])
        assert np.all((legs >= s.leg_s[0]) & (legs <= s.leg_s[1]))
        assert not len(c) or t[-1] - c[-1] >= s.leg_s[0]  # the last leg lasts at least the shortest leg
        assert np.all((np.abs(sc.turn_deg) >= 20.0) & (np.abs(sc.turn_deg) <= 120.0))
        speeds = np.hypot(*sc.velocities_mps.T) / KNOT_MPS
        assert np.all((speeds >= 4.0 - 1e-9) & (speeds <= 15.0 + 1e-9))
        changed = sc.speed_change_kn != 0
        assert np.allclose(np.diff(speeds)[changed], sc.speed_change_kn[changed])
        turns = np.degrees(np.diff(np.unwrap(np.arctan2(*sc.velocities_mps.T))))
        assert np.allclose(turns, sc.turn_deg, atol=1e-6)
        # the bearings are the true target's, seen from the ownship; the target's position is continuous
        d = sc.target_xy_m(t) - sc.own_xy_m
        assert np.allclose(np.arctan2(d[:, 0], d[:, 1]), sc.bearing_rad)
        assert np.all((np.hypot(*d.T) >= s.min_range_m) & (np.hypot(*d.T) <= s.max_range_m))
        assert np.allclose(sc.target_xy_m(c - 1e-6), sc.target_xy_m(c + 1e-6), atol=1e-3)
        cv += len(c) == 0
    assert patterns == set(OWN_PATTERNS) and 4 <= cv <= 22  # 30 % of 40 constant-velocity scenes


def _two_legs(course2_deg=200.0):
    """Noise-free record: target 8 km north at 10 kn west, turning to ``course2_deg`` (70 deg to port) at 1805 s;
    ownship on two legs."""
    t = np.arange(0.0, 2400.0, 20.0)
    own = np.where(t[:, None] < 900, np.c_[3.0 * t, 0 * t], np.c_[2700.0 + 0 * t, 3.0 * (t - 900)])
    v1 = 10 * KNOT_MPS * np.array([-1.0, 0.0])
    v2 = 10 * KNOT_MPS * np.array([np.sin(np.radians(course2_deg)), np.cos(np.radians(course2_deg))])
    params = np.r_[0.0, 8000.0, v1, v2]
    pos = params[:2] + np.minimum(t, 1805.0)[:, None] * v1 + np.maximum(t - 1805.0, 0)[:, None] * v2
    d = pos - own
    return t, own, params, np.array([1805.0]), np.arctan2(d[:, 0], d[:, 1])


def test_noncentrality_is_the_glr_of_the_true_change():
    """On a noise-free record the GLR at the true time is the noncentrality (to the linearisation: a 30 deg turn):
    the CV fit's cost minus the two-leg fit's, both whitened, on the same window."""
    from sonartrack.tma.batch_ml import ml_bearings_only
    from sonartrack.tma.legs import fit_legs

    t, own, params, c, z = _two_legs(240.0)
    sigma = np.radians(0.5)
    for after in (120.0, 300.0):
        lam = study.noncentrality(t, own, sigma, params, c, 0, c[0] + after, 1800.0)
        w = (t > c[0] - 1800.0) & (t <= c[0] + after)
        cv = ml_bearings_only(z[w], t[w], own[w], sigma, x_init=np.r_[params[:2] + t[w][0] * params[2:4],
                                                                      params[2:4]], check=False).objective
        two = fit_legs(t[w], z[w], own[w], sigma, c, refine=False, params_init=np.r_[params[:2] + t[w][0] *
                                                                                      params[2:4], params[2:]])
        assert lam == pytest.approx(cv - two.objective, rel=0.1)
    assert study.noncentrality(t, own, sigma, params, c, 0, c[0] + 300.0, 1800.0) > lam / 2 > 0


class _Scene:
    """What noise_free_glr reads of a scene, from a two-leg record made here."""

    def __init__(self, t, own, params, c, z):
        self.time_s, self.own_xy_m, self.params, self.change_times_s, self.bearing_rad = t, own, params, c, z

    def target_xy_m(self, times):
        v = self.params[2:].reshape(-1, 2)
        a = np.c_[np.minimum(times, self.change_times_s[0]), np.maximum(times - self.change_times_s[0], 0.0)]
        return self.params[:2] + a @ v


@pytest.mark.parametrize("course2_deg", [240.0, 200.0, 120.0])
def test_noise_free_glr_is_the_cv_cost_of_noise_free_bearings(course2_deg):
    """The nonlinear noncentrality is the CV ML's cost on the window's noise-free bearings: no more than an
    independent CV fit started at the true first leg (it tries that start and others), within 10 % of the
    linearised noncentrality on a 30 deg turn, and positive on every turn."""
    from sonartrack.tma.batch_ml import ml_bearings_only

    t, own, params, c, z = _two_legs(course2_deg)
    sigma = np.radians(0.5)
    for after in (120.0, 300.0):
        nl = study.noise_free_glr(_Scene(t, own, params, c, z), sigma, 0, c[0] + after, 1800.0)
        w = (t > c[0] - 1800.0) & (t <= c[0] + after)
        cv = ml_bearings_only(z[w], t[w], own[w], sigma, x_init=np.r_[params[:2] + t[w][0] * params[2:4],
                                                                      params[2:4]], check=False).objective
        assert 0 < nl <= cv * (1 + 1e-6)
        if course2_deg == 240.0:
            lam = study.noncentrality(t, own, sigma, params, c, 0, c[0] + after, 1800.0)
            assert nl == pytest.approx(lam, rel=0.1)


def test_cv_test_rejects_a_zig_and_keeps_a_straight_leg():
    t, own, params, c, z = _two_legs()
    rng = np.random.default_rng(5)
    sigma = np.full(len(t), np.radians(0.5))

    class Scene:  # what cv_rejected reads of a scene
        time_s, own_xy_m = t, own

    zig = Scene()
    zig.params = params
    assert study.cv_rejected(zig, study.noisy_bearings(z, sigma, rng), sigma, 1e-3)[0]
    straight = Scene()
    straight.params = params[:4]
    d = params[:2] + t[:, None] * params[2:4] - own
    p = [study.cv_rejected(straight, study.noisy_bearings(np.arctan2(d[:, 0], d[:, 1]), sigma, rng), sigma, 1e-3)[1]
         for _ in range(5)]
    assert min(p) > 1e-3


def test_summary_intervals_hold_their_estimates():
    med = study._median_interval([3.0, 1.0, 2.0, 5.0, 4.0, 6.0, 7.0, 8.0, 9.0, 10.0, np.nan])
    assert med["n"] == 10 and med["median"] == 5.5 and med["low"] <= 5.5 <= med["high"]
    rate = study._poisson_rate(3, 30.0)
    assert rate["low"] < 0.1 < rate["high"] and rate["rate"] == pytest.approx(0.1)
    assert study._poisson_rate(0, 10.0)["low"] == 0.0


def test_quick_trials_summary_and_claims_shape():
    cfg = study.Config.quick().model_copy(update={"runs": 2, "advice_draws": 2, "advice_others": 1})
    outs = [study.run_trial(cfg, trial_rng(3, i)) for i in range(cfg.runs)]
    assert all(o.keys() == outs[0].keys() and all(np.shape(o[k]) == np.shape(outs[0][k]) for k in o) for o in outs)
    assert outs[0]["zig_time_s"].shape == (study.MAX_ZIGS,)
    trials = {k: np.stack([o[k] for o in outs]) for k in outs[0]}
    summary = study.summarize(trials, cfg)
    json.dumps(summary)
    claims = study.claims(summary, cfg)
    assert [c.id for c in claims] == ["zigs-detected", "false-zigs", "current-leg-crb", "no-rejected-cv-determined",
                                      "advice-realised"]
    assert all(c.ours and c.tolerance != "-" for c in claims)
