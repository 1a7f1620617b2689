"""The active scene: bistatic truth against P4's geometry module, a target's echo through the front end at its
true travel time, cone angle and Doppler, the noise and reverberation levels, determinism, and the scene files
(written, read back, and refused when they disagree)."""

import numpy as np
import pandas as pd
import pytest
from pydantic import ValidationError

from sonartrack.acoustics.active_beams import LineArray
from sonartrack.core.errors import InputError
from sonartrack.core.random import trial_rng
from sonartrack.detection.cells import FrontEndSettings, detect_ping, detection_threshold, ping_front_end
from sonartrack.models.bistatic import bistatic_inputs
from sonartrack.sim.active_scene import (
    ActiveSceneSettings,
    ScattererSettings,
    ping_geometry,
    target_truth,
    transmission_loss_model,
)
from sonartrack.sim.active_signals import UPA2_PA2, draw_scatterers, ping_samples

QUIET = {"density_per_km2": 0.0, "strength_db": -60.0, "shape": 1.0, "depth_m": 100.0}


def scene(**kw) -> ActiveSceneSettings:
    base = {"duration_s": 60.0, "ownship": {"turn_deg": 0.0}}
    base.update(kw)
    return ActiveSceneSettings(**base)


def one_target(kind="lfm", x=6000.0, y=4000.0, course=250.0, speed=8.0, ts=25.0, reverb=False, **kw):
    target = {"name": "t", "x_m": x, "y_m": y, "course_deg": course, "speed_kn": speed, "target_strength_db": ts}
    rv = {} if reverb else {"reverberation": {"boundary": QUIET, "volume": QUIET}}
    return scene(waveform={"kind": kind}, targets=[target], target_fluctuation="steady", **rv, **kw)


def test_truth_matches_p4_geometry_and_the_doppler_sign():
    s = one_target()
    truth = target_truth(s, transmission_loss_model(s))
    plat = ping_geometry(s)
    t, theta = bistatic_inputs(np.stack([truth["x_m"], truth["y_m"]], -1), plat.tx_xy, plat.rx_xy,
                               plat.array_heading_rad, s.sound_speed_mps)
    np.testing.assert_allclose(truth["travel_time_s"], t, rtol=1e-12)
    np.testing.assert_allclose(truth["cone_deg"], np.rad2deg(np.abs(theta)), atol=1e-9)
    # the range rate is the time derivative of the bistatic range (finite difference over a short scene)
    fine = scene(targets=[s.targets[0].model_dump()], ping_interval_s=0.5, duration_s=2.0,
                 waveform={"duration_s": 0.1}, sample_rate_hz=800.0)
    ft = target_truth(fine, transmission_loss_model(fine))
    rate = np.gradient(ft["bistatic_range_m"], 0.5)
    np.testing.assert_allclose(ft["range_rate_mps"][1:-1], rate[1:-1], atol=1e-3)
    assert np.all(truth["range_rate_mps"] < 0) and np.all(truth["doppler_hz"] > 0)  # closing: up-shifted


@pytest.mark.parametrize("kind", ["lfm", "cw"])
def test_target_echo_appears_at_its_truth_after_the_front_end(kind):
    s = one_target(kind)
    tl = transmission_loss_model(s)
    plat = ping_geometry(s)
    truth = pd.DataFrame(target_truth(s, tl, plat)).iloc[0]
    fe = FrontEndSettings()
    cells = ping_front_end(ping_samples(s, plat, 0, tl, trial_rng(s.seed, 0)), s.sample_rate_hz,
                           s.waveform.waveform(), LineArray(s.sonar.elements, s.spacing_m), fe)
    det = detect_ping(cells, detection_threshold(fe))
    best = int(np.argmax(det.statistic))
    cone_step = cells.cone_deg[1] - cells.cone_deg[0]
    delay_step = cells.delay_s[1] - cells.delay_s[0]
    expected_delay = truth.lfm_delay_s if kind == "lfm" else truth.travel_time_s
    assert abs(det.travel_time_s[best] - expected_delay) <= delay_step
    assert abs(det.cone_deg[best] - truth.cone_deg) <= cone_step
    if kind == "cw":
        assert abs(det.doppler_hz[best] - truth.doppler_hz) <= cells.doppler_hz[1] - cells.doppler_hz[0]
        assert abs(det.range_rate_mps[best] - truth.range_rate_mps) <= 1.0
    else:
        assert np.isnan(det.doppler_hz[best]) and not cells.doppler_measured
        # the LFM's coupling moves the peak by -f_d tau / B: here several cells, so the truth must carry it
        assert abs(truth.lfm_delay_s - truth.travel_time_s) > 2 * delay_step


def test_ambient_noise_has_the_stated_level():
    s = scene(targets=[], reverberation={"boundary": QUIET, "volume": QUIET})
    plat = ping_geometry(s)
    x = ping_samples(s, plat, 0, transmission_loss_model(s), trial_rng(0, 0))
    expected = UPA2_PA2 * 10 ** (s.noise_level_db / 10) * s.sample_rate_hz
    assert np.mean(np.abs(x) ** 2) == pytest.approx(expected, rel=0.02)
    # independent between elements
    c = np.corrcoef(x[0], x[1])[0, 1]
    assert abs(c) < 0.05


def test_scatterer_field_has_the_stated_scattering_strength():
    pop = ScattererSettings(density_per_km2=20.0, strength_db=-40.0, shape=0.5, depth_m=100.0)
    rng = np.random.default_rng(1)
    r0, r1 = 2000.0, 8000.0
    total = [draw_scatterers(pop, (0.0, 0.0), r0, r1, rng)[1].sum() for _ in range(200)]
    area = np.pi * (r1**2 - r0**2)
    assert np.mean(total) / area == pytest.approx(10 ** (-40.0 / 10), rel=0.05)
    xy, sigma = draw_scatterers(pop, (100.0, -50.0), r0, r1, rng)
    r = np.hypot(xy[:, 0] - 100.0, xy[:, 1] + 50.0)
    assert r.min() >= r0 and r.max() <= r1
    # K-distributed cross-sections: heavier-tailed than exponential (kurtosis of the K intensity with nu = 0.5)
    norm = sigma / (10 ** (-4.0) * r / (pop.density_per_km2 / 1e6 * 1e4))
    assert np.mean(norm**2) == pytest.approx(2 * (1 + 1 / pop.shape), rel=0.25)


def cells_of(s: ActiveSceneSettings, k: int, fe: FrontEndSettings):
    plat = ping_geometry(s)
    x = ping_samples(s, plat, k, transmission_loss_model(s), trial_rng(s.seed, k))
    return ping_front_end(x, s.sample_rate_hz, s.waveform.waveform(), LineArray(16, s.spacing_m), fe)


def test_noise_only_pings_alarm_at_the_stated_pfa():
    # the CFAR's references are a resolution cell apart (about independent), so the closed-form threshold holds;
    # adjacent cells are correlated (overlapping beams, delays sampled at 2 B), so the count spreads more than a
    # binomial: a band of a factor 2 either way over 4 pings (~1.3e6 cells, ~130 alarms expected at 1e-4)
    s = scene(targets=[], reverberation={"boundary": QUIET, "volume": QUIET}, duration_s=120.0)
    fe = FrontEndSettings(pfa=1e-4)
    thr = detection_threshold(fe)
    rate = np.mean([np.mean(cells_of(s, k, fe).statistic >= thr) for k in range(4)])
    assert 0.5 * fe.pfa <= rate <= 2.0 * fe.pfa


def test_reverberation_gives_a_heavy_tailed_background():
    s = scene(targets=[])
    fe = FrontEndSettings(heavy_tail=False)  # the exponential law's CFAR: the simulator's tail is what is tested
    cells = cells_of(s, 0, fe)
    near = cells.statistic[:, cells.delay_s < 8.0]  # reverberation-dominated delays
    assert np.mean(near >= detection_threshold(fe)) > 20 * fe.pfa


def test_same_seed_same_samples_and_pings_are_independent():
    s = one_target(reverb=True)
    tl = transmission_loss_model(s)
    plat = ping_geometry(s)
    a = ping_samples(s, plat, 1, tl, trial_rng(s.seed, 1))
    b = ping_samples(s, plat, 1, tl, trial_rng(s.seed, 1))
    c = ping_samples(s, plat, 1, tl, trial_rng(s.seed + 1, 1))
    assert a.dtype == np.complex64 and a.shape == (16, s.samples_per_ping)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_settings_refuse_what_cannot_be_simulated():
    with pytest.raises(ValidationError, match="zero-bandwidth"):
        scene(waveform={"kind": "lfm", "bandwidth_hz": 0.0})
    with pytest.raises(ValidationError, match="shorter than the ping interval"):
        scene(waveform={"kind": "cw", "duration_s": 30.0})
    with pytest.raises(ValidationError, match="sample_rate_hz"):
        scene(sample_rate_hz=100.0)
    with pytest.raises(ValidationError, match="unique"):
        scene(targets=[{"name": "a", "x_m": 1, "y_m": 1, "course_deg": 0, "speed_kn": 1, "target_strength_db": 0}] * 2)


# --------------------------------------------------------------------------- files

@pytest.fixture(scope="module")
def written(tmp_path_factory):
    from sonartrack.systems.simulate.active_files import write_active_scene

    out = tmp_path_factory.mktemp("active")
    s = scene(reverberation={"boundary": QUIET, "volume": QUIET})
    return s, out, write_active_scene(s, out)


def test_scene_files_read_back(written):
    import tomllib

    from sonartrack.systems.active import scene_files as sf

    s, out, paths = written
    assert all(p.exists() for p in paths) and len(paths) == 2 + 3 + 1
    table = sf.read_ping_table(out / sf.PING_TABLE)
    nav = sf.read_active_nav(out / sf.NAV_FILE)
    sf.check_nav_covers(table, nav)
    pings = list(sf.iter_pings(out, table))
    assert [p for p, _, _ in pings] == [1, 2] and [t for _, t, _ in pings] == [0.0, 30.0]
    plat = ping_geometry(s)
    np.testing.assert_array_equal(pings[1][2], ping_samples(s, plat, 1, transmission_loss_model(s),
                                                            trial_rng(s.seed, 1)))
    assert table.waveform(0) == s.waveform.waveform()
    src, arr, head = nav.at(plat.time_s)
    np.testing.assert_allclose(src, plat.tx_xy, atol=1e-5)
    np.testing.assert_allclose(arr, plat.rx_xy, atol=1e-5)
    assert ActiveSceneSettings(**tomllib.loads((out / sf.SCENE_FILE).read_text())) == s
    truth = sf.read_truth(out / sf.TRUTH_FILE)
    assert len(truth) == 2 * len(s.targets)


def test_scene_files_that_disagree_are_refused(written, tmp_path):
    import shutil

    from sonartrack.systems.active import scene_files as sf

    _, out, _ = written
    case = tmp_path / "case"
    shutil.copytree(out, case)
    table = sf.read_ping_table(case / sf.PING_TABLE)
    np.save(case / table.file[0], np.zeros((8, table.samples[0]), np.complex64))
    with pytest.raises(InputError, match="channels"):
        sf.read_ping(case, table, 0)
    np.save(case / table.file[0], np.zeros((16, 100), np.complex64))
    with pytest.raises(InputError, match="samples"):
        sf.read_ping(case, table, 0)
    df = pd.read_csv(case / sf.PING_TABLE)
    for column, value, match in (("bandwidth_hz", 0.0, "zero-bandwidth"), ("duration_s", 30.0, "shorter than the "
                                                                                             "ping interval")):
        bad = df.copy()
        bad[column] = value
        bad.to_csv(case / "bad.csv", index=False)
        with pytest.raises(InputError, match=match):
            sf.read_ping_table(case / "bad.csv")
    nav = pd.read_csv(case / sf.NAV_FILE)
    nav[nav.time_s < 20].to_csv(case / "short_nav.csv", index=False)
    with pytest.raises(InputError, match="does not cover"):
        sf.check_nav_covers(table, sf.read_active_nav(case / "short_nav.csv"))


def test_maneuvering_target_turns_as_stated():
    from sonartrack.sim.active_scene import TargetSettings, target_motion

    tgt = TargetSettings(name="m", x_m=1000.0, y_m=2000.0, course_deg=330.0, speed_kn=8.0, target_strength_db=10.0,
                         turn_start_s=600.0, turn_deg=120.0, turn_rate_deg_s=0.5)
    t = np.arange(0.0, 1500.0, 0.5)
    xy, v = target_motion(tgt, t)
    speed = 8.0 * 1852.0 / 3600.0
    np.testing.assert_allclose(np.hypot(v[:, 0], v[:, 1]), speed, rtol=1e-9)
    course = np.rad2deg(np.arctan2(v[:, 0], v[:, 1])) % 360.0
    assert np.allclose(course[t < 600.0], 330.0) and np.allclose(course[t > 840.0], 90.0)
    # the course changes at 0.5 deg/s in between, to starboard
    mid = (t > 610.0) & (t < 830.0)
    np.testing.assert_allclose((course[mid] - 330.0) % 360.0, 0.5 * (t[mid] - 600.0), atol=1e-6)
    # positions are the integral of the velocities (trapezoid rule, independent of the closed form)
    integral = xy[0] + np.concatenate([[[0.0, 0.0]], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.5, axis=0)])
    np.testing.assert_allclose(xy, integral, atol=0.05)
    # without a turn, the constant-velocity motion of before
    cv = TargetSettings(name="c", x_m=1000.0, y_m=2000.0, course_deg=330.0, speed_kn=8.0, target_strength_db=10.0)
    np.testing.assert_allclose(target_motion(cv, t)[0][t < 600.0], xy[t < 600.0], atol=1e-9)
