"""The quiet-target study follows the study contract, its scenes put the quiet target at the stated levels (measured
on the simulated samples), its judging functions and level interpolation agree with hand-worked cases, and its
supporting cell rows match their closed forms."""

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.core.random import trial_rng
from sonartrack.io import toml as toml_io
from sonartrack.sim.array_signals import array_blocks
from sonartrack.sim.passive_scene import received_levels, scene_geometry
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.studies import quiet_target as study

#: one micropascal squared in pascals squared
UPA2 = 1e-12


def test_contract_surface(tmp_path):
    mod = studies.load("quiet-target")
    assert mod.STUDY_ID == "quiet-target" and mod.TITLE and mod.PAPER and mod.TRIAL_VERSION >= 2
    cfg = mod.Config.quick()
    assert cfg.runs <= mod.Config().runs
    assert cfg.hours() < mod.Config().hours()
    path = tmp_path / "c.toml"
    path.write_text(toml_io.dumps(cfg.model_dump(mode="json")))
    assert toml_io.validate(study.Config, toml_io.load(path)) == cfg


def test_config_refuses_unpaired_or_unordered_levels():
    with pytest.raises(ValueError, match="one tonal level per broadband level"):
        study.Config(levels_db=[-3.0, 0.0, 3.0], tonal_db=[10.0, 13.0])
    with pytest.raises(ValueError, match="must increase"):
        study.Config(levels_db=[0.0, -3.0], tonal_db=[10.0, 13.0])


# --- scene builder: levels land where stated, measured on the samples ------------------------------------------


def _element_power(scene: PassiveSceneSettings) -> float:
    """Mean square pressure (Pa^2) of element 1 over the recording."""
    x = np.concatenate([b[0] for b in array_blocks(scene, np.random.default_rng(scene.seed))])
    return float(np.mean(x**2))


@pytest.mark.parametrize("propagation_range_m", [3000.0, 12000.0])
def test_placed_ship_broadband_snr_measured_on_the_samples(propagation_range_m):
    """Broadband: the ship alone (ambient silenced after placing) has element power RL_bb (f_hi - f_lo); the ambient
    alone NL (f_hi - f_lo); their ratio is the stated SNR per hydrophone."""
    base = PassiveSceneSettings(ships=[], duration_s=20.0, seed=3)
    ship = study.placed_ship(base, "q", 70.0, -1.0, propagation_range_m, 10.0, 5.0, -7.0, 200.0, -60.0, 10.0)
    silent = base.model_copy(update={"noise_level_db": -100.0, "ships": [ship]})
    ambient = base.model_copy(update={"seed": 4})
    snr = 10 * np.log10(_element_power(silent) / _element_power(ambient))
    # 20 s x 950 Hz of Gaussian noise: power estimates to ~1 %; the range changes by <1 % over 20 s
    assert snr == pytest.approx(-7.0, abs=0.3)


def test_placed_ship_tonal_snr_measured_on_the_samples():
    """Tonal: with the broadband 60 dB below the ambient and the ambient silenced, the element's power is the
    tonal's a^2 / 2; over the ambient's power in 1 Hz (NL) it is the stated tonal SNR per hydrophone."""
    base = PassiveSceneSettings(ships=[], duration_s=10.0, seed=5)
    ship = study.placed_ship(base, "q", 110.0, 1.0, 6000.0, -15.0, 5.0, -60.0, 200.0, -8.0, 5.0)
    silent = base.model_copy(update={"noise_level_db": -100.0, "ships": [ship]})
    nl_pa2_per_hz = UPA2 * 10 ** (base.noise_level_db / 10)
    assert 10 * np.log10(_element_power(silent) / nl_pa2_per_hz) == pytest.approx(-8.0, abs=0.2)


def test_placed_ship_geometry():
    """At t_ref the ship lies at the stated range and cone angle, on the stated side."""
    base = PassiveSceneSettings(ships=[], duration_s=300.0)
    ship = study.placed_ship(base, "q", 60.0, -1.0, 7000.0, 30.0, 8.0, -10.0, 200.0, 3.0, 150.0)
    g = scene_geometry(base.model_copy(update={"ships": [ship]}), np.array([150.0]))
    assert g.range_m[0, 0] == pytest.approx(7000.0, rel=1e-9)
    assert np.rad2deg(g.cone_rad[0, 0]) == pytest.approx(60.0, abs=1e-6)
    assert np.sin(g.bearing_rad[0, 0] - g.array_heading_rad[0]) < 0  # port


def test_sweep_scene_puts_one_quiet_target_at_each_level():
    cfg = study.Config(levels_db=[-21.0, 0.0], tonal_db=[-8.0, 13.0], sweep_duration_s=200.0)
    rng = np.random.default_rng(1)
    for j, (bb, tn) in enumerate(zip(cfg.levels_db, cfg.tonal_db, strict=True)):
        scene = study.sweep_scene(cfg, j, rng)
        assert [s.name for s in scene.ships] == [t[0] for t in study.TRAFFIC] + ["quiet"]
        g = scene_geometry(scene, np.array([100.0]))
        lv = received_levels(scene, g)
        assert lv.broadband_db[-1, 0] - scene.noise_level_db == pytest.approx(bb, abs=1e-6)
        assert lv.tonal_db[-1, 0] - scene.noise_level_db == pytest.approx(tn, abs=1e-6)
        assert cfg.cone_range_deg[0] <= np.rad2deg(g.cone_rad[-1, 0]) <= cfg.cone_range_deg[1]
        assert lv.broadband_db[0, 0] > lv.broadband_db[-1, 0]  # the traffic is louder


# --- judging on hand-made cases ---------------------------------------------------------------------------------


def test_held_windows_time_cone_and_frequency():
    tw = np.array([9.5, 10.5, 11.5])
    truth = np.array([52.0, 52.0, 52.0])
    held = study.held_windows([10.5], [50.0], tw, truth, 0.5, 3.0)
    np.testing.assert_array_equal(held, [False, True, False])
    assert not study.held_windows([10.5], [48.0], tw, truth, 0.5, 3.0).any()  # 4 deg off, tolerance 3
    # a line's row covers the windows of its 16 s period
    tw16 = np.arange(32) + 0.5
    held = study.held_windows([8.0], [52.0], tw16, np.full(32, 52.0), 8.0, 3.0)
    np.testing.assert_array_equal(held, tw16 < 16.0)
    # frequency: a line 2 Hz off the target's tonal does not hold it
    f = np.full(3, 200.1)
    assert study.held_windows([10.5], [52.0], tw, truth, 0.5, 3.0, [200.4], f, 1.0)[1]
    assert not study.held_windows([10.5], [52.0], tw, truth, 0.5, 3.0, [202.1], f, 1.0).any()
    assert not study.held_windows([], [], tw, truth, 0.5, 3.0).any()


def test_false_count_against_a_ship():
    base = PassiveSceneSettings(ships=[], duration_s=100.0)
    ship = study.placed_ship(base, "q", 80.0, 1.0, 8000.0, 0.0, 5.0, 0.0, 200.0, 10.0, 50.0)
    scene = base.model_copy(update={"ships": [ship]})
    t = np.arange(100.0) + 0.5
    cone = np.rad2deg(scene_geometry(scene, t).cone_rad[0])
    rows_t = np.concatenate([t, t, t])
    rows_c = np.concatenate([cone + 1.0, cone + 20.0, np.full(100, 150.0)])
    ids = np.repeat([1, 2, 3], 100)
    assert study.false_count(rows_t, rows_c, ids, scene, 3.0) == 2  # tracks 2 and 3 follow no ship
    assert study.false_count(rows_t, rows_c, ids, scene, 25.0) == 1
    assert study.false_count(rows_t, rows_c, ids, base, 3.0) == 3  # no ship: every track is false


def test_level_at_interpolates():
    assert study.level_at([0, 1, 2], [0.0, 0.4, 0.8], 0.6) == pytest.approx(1.5)
    assert np.isnan(study.level_at([0, 1], [0.0, 0.1], 0.5))
    assert study.level_at([0, 1], [0.9, 1.0], 0.5) == 0.0
    # held 0.2, 0.6, 1.0 at -6, -3, 0 dB: 0.8 is half-way from -3 to 0 dB
    assert study.level_at([-6, -3, 0], [0.2, 0.6, 1.0], 0.8) == pytest.approx(-1.5)


def test_held_level_and_paired_gain_hand_worked():
    """Held fractions 0, 0, 0.5, 1 (broadband) and 0, 0.5, 1, 1 (MFTD) at 0, 3, 6, 9 dB: 0.8 is reached at
    6 + 3 (0.3 / 0.5) = 7.8 dB and 3 + 3 (0.3 / 0.5) = 4.8 dB, a gain of 3 dB; identical blocks and trials leave no
    spread."""
    judged = np.full((3, 4, 5), 10.0)  # 3 trials, 4 levels, 5 blocks
    bb = np.array([0.0, 0.0, 0.5, 1.0])[None, :, None] * judged
    mf = np.array([0.0, 0.5, 1.0, 1.0])[None, :, None] * judged
    rng = np.random.default_rng(0)
    lv, gain = study.held_level([0, 3, 6, 9], bb, judged, 0.8, 50, rng, other=mf)
    np.testing.assert_allclose(lv, [7.8, 7.8, 7.8])
    np.testing.assert_allclose(gain, [3.0, 3.0, 3.0])
    # one trial holds the 6 dB target throughout (the others half the time): pooled 0.5 + 0.5 / 3 = 2 / 3 at 6 dB,
    # so 0.8 lies at 6 + 3 (0.8 - 2 / 3) / (1 - 2 / 3) = 7.2 dB; resampling the trials spreads it
    bb2 = bb.copy()
    bb2[0, 2] = 10.0
    lv2, none = study.held_level([0, 3, 6, 9], bb2, judged, 0.8, 300, rng)
    assert none is None
    assert lv2[0] == pytest.approx(7.2)
    assert lv2[1] < lv2[0] < lv2[2]


def _summary(level80, held_any=0.9, determined=1, ratio=1.5, false_targets=0, hours=2.0):
    grid = [-6.0, -3.0, 0.0]
    scenes = {"levels_db": grid, "tonal_db": [x + 13 for x in grid], "hours": hours,
              "false_tracks": {"broadband": 0, "mftd": 1, "narrowband": 3, "broadband_low_init": 5},
              "false_targets": false_targets, "level80_broadband_low_init": [-3.0, -4.0, -2.0],
              "false_targets_upper95": 3.0, "mftd_gain_db": [2.0, 1.0, 3.0]}
    for fe in study.FRONT_ENDS:
        shift = 13.0 if fe == "narrowband" else 0.0  # the narrowband level is on the tonal grid
        scenes[f"level80_{fe}"] = [None if v is None else v + shift for v in level80]
        scenes[f"held_{fe}"] = [0.0, 0.5, 1.0]
    sub = {"held": {"broadband": 0.0, "mftd": 0.0, "narrowband": held_any, "any": held_any}, "runs": 1, "tracked": 1,
           "side_right": 1, "side_decided": 1, "determined": determined, "rmse_over_crb": ratio,
           "levels_db": [-21, -20, -8, -7]}
    return {"scenes": scenes, "submarine": sub}


def test_scene_claims_judge_hand_made_summaries():
    ok = _summary([-1.5, -2.0, -1.0])
    cl = {c.id: c for c in study._level_claims(ok) + [study._gain_claim(ok), study._submarine_claim(ok),
                                                       study._false_claim(ok)]}
    assert all(c.holds for c in cl.values()), [c.id for c in cl.values() if not c.holds]
    censored = _summary([-6.0, -6.0, -6.0])  # held from the lowest level on: below the grid
    assert not any(c.holds for c in study._level_claims(censored))
    never = _summary([None, None, None])  # JSON null: never reached
    assert not any(c.holds for c in study._level_claims(never))
    assert not study._submarine_claim(_summary([0, 0, 0], held_any=0.5)).holds
    assert not study._submarine_claim(_summary([0, 0, 0], determined=0)).holds
    assert not study._submarine_claim(_summary([0, 0, 0], ratio=2.5)).holds
    assert not study._false_claim(_summary([0, 0, 0], false_targets=3, hours=2.0)).holds
    worse = _summary([0, 0, 0])
    worse["scenes"]["mftd_gain_db"] = [-1.0, -2.0, 0.5]
    assert not study._gain_claim(worse).holds


# --- supporting cell rows ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def cells():
    cfg = study.CellConfig(btr=study.BtrMftdSettings(frames=8, tile_beams=64, calibration_trials=500))
    outs = [study.run_cells(cfg, trial_rng(21, i)) for i in range(40)]
    trials = {k: np.stack([o[k] for o in outs])[None] for k in outs[0]}  # one study trial of 40 cell trials
    return cfg, study._cell_summary(trials, cfg, 100, np.random.default_rng(0))


def test_single_window_levels_match_closed_forms(cells):
    """Single window at pfa 1e-3: Gaussian Pd = 0.5 at mu = Phi^-1(1 - pfa) = 3.09 (9.8 dB); Swerling 1
    Pd = pfa^(1/(1+rho)) = 0.5 at 1 + rho = ln(pfa) / ln(0.5) = 9.97 (9.5 dB)."""
    _, s = cells
    for stat, closed_form_db in (("gaussian", 9.8), ("exponential", 9.5)):
        _, lo, hi = s[stat]["level50_single"]
        # the bootstrap interval over 40 cell trials (+- half a 1.5 dB grid step) holds the closed form
        assert lo - 0.75 <= closed_form_db <= hi + 0.75, (stat, lo, hi)
        assert hi - lo < 6.0


def test_cell_claims_read_the_summary(cells):
    _, s = cells
    cl = {c.id: c for c in study._cell_claims(s)}
    assert set(cl) == {"cells-mftd-gain-gaussian", "cells-mftd-gain-exponential", "cells-mftd-false-rate-gaussian",
                       "cells-mftd-false-rate-exponential", "cells-lofar-integration-gain", "cells-line-mftd-gain"}
    g = s["gaussian"]["gain50_db"]
    assert cl["cells-mftd-gain-gaussian"].holds == (g[0] >= study.MFTD_GAIN_REQUIRED_DB)
    assert g[1] <= g[0] <= g[2]


def test_line_cells_single_level_matches_the_f_law(cells):
    """Single period on LOFAR cells at pfa: z = (1 + s) F(2L, 2LR) on the line, so Pd = 0.5 where
    (1 + s) = t / median(F), t the F quantile at 1 - pfa."""
    from scipy.optimize import brentq
    from scipy.stats import f as f_law

    from sonartrack.acoustics.lofar import LofarSettings

    cfg, s = cells
    d1 = 2 * cfg.integration
    d2 = d1 * 2 * LofarSettings().reference_bins
    t = f_law.isf(cfg.pfa, d1, d2)
    closed_form_db = 10 * np.log10(brentq(lambda x: f_law.sf(t / (1 + x), d1, d2) - 0.5, 1e-3, 100.0))
    _, lo, hi = s["line"]["level50_single"]
    assert lo - 0.5 <= closed_form_db <= hi + 0.5, (closed_form_db, lo, hi)  # +- half a 1 dB grid step


def test_line_mftd_gain_claim(cells):
    _, s = cells
    g = s["line"]["gain50_db"]
    assert g[1] <= g[0] <= g[2]
    assert g[0] > 0  # the MFTD per line detects weaker lines than the single period at the same pfa
    claim = {c.id: c for c in study._cell_claims(s)}["cells-line-mftd-gain"]
    assert claim.holds == (g[0] >= study.MFTD_GAIN_REQUIRED_DB)
    worse = {**s, "line": {**s["line"], "gain50_db": [1.0, 0.0, 2.0]}}
    assert not {c.id: c for c in study._cell_claims(worse)}["cells-line-mftd-gain"].holds
