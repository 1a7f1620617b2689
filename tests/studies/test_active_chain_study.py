"""Study active-chain: its scoring helpers on hand-made tracks, the SNR50 fit, and the quick trial through the
contract."""

import numpy as np
import pytest

from sonartrack.core.random import trial_rng
from sonartrack.sim.active_scene import ActiveSceneSettings
from sonartrack.studies import active_chain as ac
from sonartrack.studies.active_chain_claims import _held_detectable, _wilson
from sonartrack.studies.active_chain_family import FamilySettings, draw_scene, is_clutter, target_names
from sonartrack.systems.active.contacts import ActiveGeometry
from sonartrack.systems.active.run import ActiveTracks
from sonartrack.tracking.run import PositionTracks


def _geometry():
    t = np.array([-10.0, 1000.0])
    return ActiveGeometry(t, np.array([[0.0, 150.0]] * 2), np.zeros((2, 2)), np.zeros(2))


def test_mirror_is_the_reflection_about_the_array_axis():
    xy = np.array([[3000.0, 4000.0], [-100.0, 50.0]])
    np.testing.assert_allclose(ac._mirror(_geometry(), np.zeros(2), xy), [[-3000.0, 4000.0], [100.0, 50.0]])


def _tracks(rows):
    """ActiveTracks from (time, id, x, y, confirmed) rows, sd 100 m per axis."""
    t, tid, x, y, conf = (np.array(c) for c in zip(*rows, strict=True))
    n = len(t)
    X = np.stack([x, y, np.zeros(n), np.zeros(n)], -1).astype(float)
    P = np.broadcast_to(np.diag([1e4, 1e4, 1.0, 1.0]), (n, 4, 4)).copy()
    return ActiveTracks(PositionTracks(t.astype(float), tid.astype(np.int64), conf.astype(bool), np.ones(n), X,
                                       np.full(n, 100.0), np.full(n, 100.0), np.full((n, 2), 0.5)), P)


def test_false_track_count_spares_targets_and_mirrors():
    t_truth = np.array([0.0, 10.0])
    xy = np.array([[3000.0, 4000.0], [3000.0, 4010.0]])
    mirror = ac._mirror(_geometry(), t_truth, xy)
    tracks = _tracks([(0.0, 1, 3100.0, 4000.0, True),      # on the target
                      (10.0, 2, -3050.0, 4000.0, True),    # on its mirror: ambiguity, not a false track
                      (10.0, 3, 9000.0, 9000.0, True),     # nowhere: false
                      (10.0, 4, 9000.0, -9000.0, False)])  # nowhere but tentative: not counted
    assert ac._false_track_count(tracks, t_truth, xy, mirror, 1000.0) == 1


def test_snr50_recovers_a_logistic_curve():
    rng = np.random.default_rng(1)
    snr = rng.uniform(0.0, 20.0, 4000)
    hits = rng.random(4000) < 1.0 / (1.0 + np.exp(-(snr - 11.0) / 1.5))
    assert ac.snr50_db(snr, hits) == pytest.approx(11.0, abs=0.3)
    assert np.isnan(ac.snr50_db(snr, np.zeros(4000)))  # never a hit: no crossing to report


@pytest.fixture(scope="module")
def quick_trial():
    """The quick scene with the family pinned to its base (LFM, 16 x 0.5 m, 1500 Hz, no added clutter, the
    maneuvering target's 90 deg turn at 0.8 deg/s): the chain's behaviour there is known; the family's draws are
    tested on their own below."""
    base = FamilySettings(pulses=["lfm"], reverb_models=["k"], elements=[16], spacings_m=[0.5], carriers_hz=[1500.0],
                          bandwidths_hz=[100.0], tows_m=[[300.0, 450.0]], reverb_levels_db=[0.0], clutter_points=[0],
                          turn_deg=[90.0, 90.0], turn_rate_deg_s=[0.8, 0.8])
    config = ac.Config.quick().model_copy(update={"family": base})
    return config, ac.run_trial(config, np.random.default_rng(3))


def test_quick_trial_fills_the_contract(quick_trial):
    config, trial = quick_trial
    n_v, n_t = len(ac.VARIANTS), len(config.scene.targets)
    assert trial["hold"].shape == (n_v, n_t) and trial["false_tracks"].shape == (n_v, 1)
    assert trial["hit_single"].shape == trial["snr_db"].shape == (n_t, len(config.scene.ping_times_s))
    stacked = {k: v[None] for k, v in trial.items()}
    summary = ac.summarize(stacked, config)
    claims = ac.claims(summary, config)
    assert [c.id for c in claims] == ["mftd-earlier-longer", "imm-beats-ipda", "side-resolved", "false-tracks",
                                      "rmse-bound", "held-detectable", "acquisition", "turn-one-row"]
    # targets as listed: a false row holds only false tracks, a row at least one confirmed track
    assert np.all(trial["false_rows"] <= trial["false_tracks"]) and np.all(trial["false_rows"] <= trial["rows"])
    assert np.all(trial["reverb_false_rows"] <= trial["reverb_false_tracks"])
    # the maneuvering target's turn is judged (it turns in the scene); the others do not turn
    i_man = target_names(config.scene).index(ac.MANEUVERING)
    assert np.isfinite(trial["turn_held"][:, i_man]).all() and np.isnan(np.delete(trial["turn_held"], i_man, 1)).all()
    assert summary["acquisition"]["judged"] >= 1
    # the strong target is held by the chain for most of the scene, within a few hundred metres
    assert summary["hold"]["mftd_imm"]["strong"][0] > 0.5
    assert summary["rmse_after_m"]["mftd_imm"]["strong"] < 500.0
    import json

    json.dumps(summary, default=float)  # the store writes it as JSON
    # the threshold sweep, GOSPA and the side decisions are there too
    n_l = len(ac.SINGLE_FACTORS)
    assert trial["hit_mftd_lv"].shape == (n_l, n_t, len(config.scene.ping_times_s))
    assert trial["reverb_false_lv"].shape == (2, n_l)
    # raising a threshold keeps a subset of the detections: never more echo hits
    assert np.all(np.diff(trial["hit_single_lv"].sum(axis=(1, 2))) <= 0)
    assert np.all(np.diff(trial["hit_mftd_lv"].sum(axis=(1, 2))) <= 0)
    assert summary["gospa_m"]["mftd_imm"][0] >= 0 and summary["ospa_m"]["mftd_imm"][0] <= config.match_m
    assert set(summary["equal_false"]["level"]) == {"single", "mftd"}
    # held on detectable pings: a fraction, and never more pings held than the whole-scene hold allows
    assert trial["held_pings"].shape == (n_v, n_t, len(config.scene.ping_times_s))
    np.testing.assert_allclose(trial["held_pings"].mean(axis=2), trial["hold"])
    assert 0.0 <= summary["held_detectable"][0] <= 1.0


def test_equal_false_gain_takes_each_detector_at_its_most_sensitive_threshold_under_the_rate():
    rng = np.random.default_rng(5)
    runs, n_t, n_p = 6, 2, 200
    snr = rng.uniform(0.0, 25.0, (runs, n_t, n_p))

    def hits(s50):
        return (rng.random(snr.shape) < 1.0 / (1.0 + np.exp(-(snr - s50) / 1.0))).astype(float)

    # single: SNR50 12, 13, 14, 15 dB along its thresholds; MFTD 8, 9, 10, 11 dB; 1 h of reverberation per run.
    # False tracks over the 6 h: single 30, 12, 3, 0 (5, 2, 0.5, 0 per hour: its third threshold is the first at
    # <= 1 per hour); MFTD 6, 0, 0, 0 (its first threshold is at 1 per hour)
    trials = {"snr_db": snr, "hit_single_lv": np.stack([hits(s) for s in (12, 13, 14, 15)], axis=1),
              "hit_mftd_lv": np.stack([hits(s) for s in (8, 9, 10, 11)], axis=1),
              "reverb_false_lv": np.tile(np.array([[5.0, 2.0, 0.5, 0.0], [1.0, 0.0, 0.0, 0.0]]), (runs, 1, 1))}
    eq = ac._equal_false_gain(trials, hours=6.0)
    assert eq["level"] == {"single": 2, "mftd": 0}
    assert eq["gain_db"][0] == pytest.approx(14.0 - 8.0, abs=0.4)
    assert eq["gain_db"][1] < eq["gain_db"][0] < eq["gain_db"][2]


def test_family_draws_cycle_pulse_and_model_and_respect_the_spacing_rule():
    base, fam = ActiveSceneSettings(duration_s=300.0, ping_interval_s=10.0), FamilySettings()
    seen = set()
    for i in range(12):
        scene, axes = draw_scene(base, fam, trial_rng(11, i), "maneuvering")
        assert (fam.pulses[axes[0]], fam.reverb_models[axes[1]]) == (fam.pulses[i % 2], fam.reverb_models[(i // 2) % 3])
        seen.add((axes[0], axes[1]))
        w, d, n = scene.waveform, scene.spacing_m, scene.sonar.elements
        half = 0.5 * w.bandwidth_hz if w.kind == "lfm" else 0.0
        assert d < scene.sound_speed_mps / (w.carrier_hz + half)  # no grating lobe everywhere
        assert n * d >= 0.5 * scene.sound_speed_mps / (w.carrier_hz - half)
        assert scene.sample_rate_hz >= scene.occupied_band_hz
        clutter = [t for t in scene.targets if is_clutter(t.name)]
        assert len(clutter) == fam.clutter_points[axes[8]] and all(t.speed_kn == 0 for t in clutter)
        assert target_names(scene) == target_names(base)
        turned = [t for t in scene.targets if t.name == "maneuvering"][0]
        assert 0.3 <= turned.turn_rate_deg_s <= 1.0 and 60.0 <= abs(turned.turn_deg) <= 180.0
    assert len(seen) == 6
    # the same trial index and seed draw the same scene
    assert draw_scene(base, fam, trial_rng(11, 4), "maneuvering")[0] == draw_scene(base, fam, trial_rng(11, 4),
                                                                                   "maneuvering")[0]


def test_held_detectable_skips_acquisition_and_pools_targets():
    det = np.zeros((1, 2, 10))
    det[0, 0, 2:10] = 1  # target 0: 8 detectable pings, the first 2 its acquisition
    det[0, 1, :] = 0     # target 1: never detectable, not counted
    held = np.zeros((1, 4, 2, 10))
    held[0, 0, 0, 4:7] = 1  # held on 3 of the 6 counted pings
    held[0, 0, 1, :] = 1    # held while undetectable: not counted
    assert _held_detectable({"detectable": det, "held_pings": held}, acquire=2)[0] == pytest.approx(0.5)
    assert np.isnan(_held_detectable({"detectable": det * 0, "held_pings": held}, acquire=2)[0])


def test_wilson_interval_hand_case():
    # 9 of 10: Wilson 95 % interval [0.596, 0.982] (Agresti & Coull 1998's formula by hand)
    p, lo, hi = _wilson(9, 10)
    assert p == 0.9 and lo == pytest.approx(0.5958, abs=1e-3) and hi == pytest.approx(0.9821, abs=1e-3)
