"""The passive scene simulator against hand-worked physics: plane-wave delays, SL - TL, NL, Doppler; files,
determinism and memory; the sample inputs agree with the scene."""

import tracemalloc

import numpy as np
import pandas as pd
import pytest
from pydantic import ValidationError
from scipy.io import wavfile

from sonartrack.core.random import trial_rng
from sonartrack.core.units import KNOT_MPS
from sonartrack.io import wav_writer
from sonartrack.sim.array_signals import array_blocks, plan_blocks, simulate_recording
from sonartrack.sim.passive_scene import scene_geometry
from sonartrack.sim.scene import PassiveSceneSettings
from sonartrack.systems.simulate import files as scene_files
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.run import STREAMS

C = 1500.0
D = 2.5  # half a wavelength at 300 Hz
OWN_V = 6.0 * KNOT_MPS
SILENT = -100.0  # dB: a level that contributes nothing (1e-10 of the signals below)


def alongside(cone_deg: float, range_m: float, **ship) -> dict:
    """A ship keeping station at ``range_m`` from the array centre at cone angle ``cone_deg`` (starboard), while
    the ownship steams north at 6 kn with the array 200 m astern: the geometry is constant by construction."""
    th = np.deg2rad(cone_deg)
    base = {"name": "s", "x_m": range_m * np.sin(th), "y_m": -200.0 + range_m * np.cos(th), "course_deg": 0.0,
            "speed_kn": 6.0, "source_level_db": SILENT}
    return base | ship


def scene(ships, **kw) -> PassiveSceneSettings:
    base = {"duration_s": 20.0, "noise_level_db": SILENT, "ownship": {"turn_deg": 0.0}, "ships": ships}
    return PassiveSceneSettings(**(base | kw))


def test_inter_element_delay_is_d_cos_theta_over_c():
    s = scene([alongside(70.0, 3000.0, source_level_db=150.0)])
    x = simulate_recording(s, np.random.default_rng(0))
    g = scene_geometry(s, [10.0])
    assert np.rad2deg(g.cone_rad[0, 0]) == pytest.approx(70.0, abs=1e-9)
    # cross-spectrum phase of element n against element 1, over whole blocks: -2 pi f (tau_n - tau_1)
    blocks = x.reshape(16, 20, 4000)
    X = np.fft.rfft(blocks, axis=2)
    f = np.fft.rfftfreq(4000, 1 / 4000)
    band = (f >= 50) & (f < 1000)
    cross = (np.conj(X[0]) * X).sum(axis=1)[:, band]  # (16, n_band)
    phase = np.unwrap(np.angle(cross), axis=1)
    slope = np.array([np.polyfit(f[band], ph, 1)[0] for ph in phase])
    lag_s = -slope / (2 * np.pi)
    expected = np.arange(16) * D * np.cos(np.deg2rad(70.0)) / C  # the rear elements hear it later
    np.testing.assert_allclose(lag_s, expected, atol=1e-9)
    # and the time-domain correlation peak of the end elements sits at that lag (to a parabola's accuracy)
    cc = np.array([np.dot(x[0, 100:-100], x[15, 100 + k:x.shape[1] - 100 + k]) for k in range(20, 50)])
    k = int(np.argmax(cc))
    frac = 0.5 * (cc[k - 1] - cc[k + 1]) / (cc[k - 1] - 2 * cc[k] + cc[k + 1])
    assert (20 + k + frac) / 4000 == pytest.approx(15 * D * np.cos(np.deg2rad(70.0)) / C, abs=0.05 / 4000)


def test_tonal_power_is_sl_minus_tl():
    """A tonal of SL 150 dB re 1 uPa^2 at 1 km: RL = 150 - 20 log10(1000) - alpha(120 Hz) * 1 km (Thorp,
    alpha = 0.0047 dB/km by hand) = 89.995 dB. The mean square of a sinusoid over T = 20 s differs from
    a^2 / 2 by at most 1 / (2 pi f T) ~ 7e-5 relative (3e-4 dB); the noise is 190 dB below: 0.01 dB is loose."""
    s = scene([alongside(90.0, 1000.0, tonal_hz=120.0, tonal_level_db=150.0)])
    x = simulate_recording(s, np.random.default_rng(0))
    f_khz = 0.12
    alpha = 0.11 * f_khz**2 / (1 + f_khz**2) + 44 * f_khz**2 / (4100 + f_khz**2) + 2.75e-4 * f_khz**2 + 0.003
    rl = 150.0 - 60.0 - alpha * 1.0
    measured = 10 * np.log10(np.mean(x**2, axis=1) / 1e-12)
    np.testing.assert_allclose(measured, rl, atol=0.01)


def test_broadband_level_is_sl_minus_tl_over_the_band():
    """Broadband SL 140 dB re 1 uPa^2/Hz at 2 km: RL = 140 - 20 log10(2000) - Thorp at the band centre (224 Hz,
    0.0097 dB/km by hand, x 2 km); power = RL x 950 Hz. 20 s x 950 Hz = 19000 independent bins: the power
    estimate's standard error is 1/sqrt(19000) = 0.7 % (0.03 dB); tolerance 0.15 dB (5 standard errors)."""
    s = scene([alongside(40.0, 2000.0, source_level_db=140.0)])
    x = simulate_recording(s, np.random.default_rng(1))
    f_khz = np.sqrt(50.0 * 1000.0) / 1e3
    alpha = 0.11 * f_khz**2 / (1 + f_khz**2) + 44 * f_khz**2 / (4100 + f_khz**2) + 2.75e-4 * f_khz**2 + 0.003
    rl = 140.0 - 20 * np.log10(2000.0) - 2.0 * alpha
    np.testing.assert_allclose(10 * np.log10(np.mean(x**2, axis=1) / 1e-12 / 950.0), rl, atol=0.15)


def test_ambient_noise_is_nl_over_the_band_independent_and_nothing_outside():
    """NL 73 dB re 1 uPa^2/Hz over 50-1000 Hz: 60 s x 950 Hz = 57000 bins, standard error 0.02 dB; 0.1 dB."""
    from scipy.signal import welch

    s = scene([], duration_s=60.0, noise_level_db=73.0)
    x = simulate_recording(s, np.random.default_rng(2))
    np.testing.assert_allclose(10 * np.log10(np.mean(x**2, axis=1) / 1e-12 / 950.0), 73.0, atol=0.1)
    r = np.corrcoef(x)
    assert np.max(np.abs(r[~np.eye(16, dtype=bool)])) < 0.02  # 1/sqrt(240000) = 0.002 per pair
    f, p = welch(x, fs=4000, nperseg=1024, axis=1)
    psd_db = 10 * np.log10(p.mean(axis=0) / 1e-12)
    assert abs(psd_db[(f > 60) & (f < 990)].mean() - 73.0) < 0.2
    assert psd_db[f > 1100].max() < 73.0 - 25.0  # the band limit holds (block joins leak ~35 dB down)


def test_tonal_carries_the_doppler_shift():
    """Ship dead ahead closing head-on at 10 kn while the array runs north at 6 kn: rdot = -(10 + 6) kn,
    f = f0 (1 - rdot / c) = 200 (1 + 16 kn / 1500) = 201.0975 Hz."""
    ship = {"name": "s", "x_m": 0.0, "y_m": 8000.0, "course_deg": 180.0, "speed_kn": 10.0,
            "source_level_db": SILENT, "tonal_hz": 200.0, "tonal_level_db": 150.0}
    s = scene([ship], duration_s=60.0)
    x = simulate_recording(s, np.random.default_rng(3))[0]
    n = 16 * x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    k = int(np.argmax(spec))
    frac = 0.5 * (spec[k - 1] - spec[k + 1]) / (spec[k - 1] - 2 * spec[k] + spec[k + 1])
    expected = 200.0 * (1.0 + 16.0 * KNOT_MPS / C)
    assert (k + frac) * 4000 / n == pytest.approx(expected, abs=0.01)


def test_truth_bearing_is_array_heading_plus_or_minus_cone():
    s = PassiveSceneSettings(duration_s=1200.0)
    g = scene_geometry(s, np.arange(0.0, 1201.0, 10.0))
    rel = np.angle(np.exp(1j * (g.bearing_rad - g.array_heading_rad[None])))
    np.testing.assert_allclose(np.abs(rel), g.cone_rad, atol=1e-9)
    # the array heading lags the ship's by tow / speed = 200 m / 6 kn = 64.8 s through the turn
    lag = 200.0 / OWN_V
    g2 = scene_geometry(s, np.array([700.0]))
    g3 = scene_geometry(s, np.array([700.0 - lag]))
    assert g2.array_heading_rad[0] == pytest.approx(g3.own_heading_rad[0], abs=1e-9)
    assert g2.array_heading_rad[0] != pytest.approx(g2.own_heading_rad[0], abs=1e-3)


def test_default_scene_crossing_and_levels():
    """The default scene is what the docs say: the merchant and the trawler cross in bearing and cone angle
    near t = 360 s; the submarine is the weak one."""
    s = PassiveSceneSettings()
    t = np.arange(0.0, 1201.0)
    g = scene_geometry(s, t)
    names = [sh.name for sh in s.ships]
    m, tr = names.index("merchant"), names.index("trawler")
    diff = np.angle(np.exp(1j * (g.bearing_rad[m] - g.bearing_rad[tr])))
    crossing = t[np.nonzero(np.diff(np.sign(diff)))[0]]
    assert crossing.size == 1 and abs(crossing[0] - 360.0) < 5.0
    cone_crossing = t[np.nonzero(np.diff(np.sign(g.cone_rad[m] - g.cone_rad[tr])))[0]]
    assert cone_crossing.size == 1 and abs(cone_crossing[0] - 360.0) < 5.0
    assert s.tma_ship_name() == "submarine"


def test_files_round_trip_and_are_deterministic(tmp_path):
    s = scene([alongside(60.0, 3000.0, source_level_db=140.0, tonal_hz=150.0, tonal_level_db=150.0)],
              noise_level_db=70.0, duration_s=5.5)
    write_scene(s, tmp_path / "a", only="passive")
    write_scene(s, tmp_path / "b", only="passive")
    write_scene(s.model_copy(update={"seed": 2}), tmp_path / "c", only="passive")
    a, b, c = ((tmp_path / d / "recording.wav").read_bytes() for d in "abc")
    assert a == b and a != c
    fs, data = wavfile.read(tmp_path / "a" / "recording.wav")
    assert fs == 4000 and data.dtype == np.float32 and data.shape == (22000, 16)
    direct = simulate_recording(s, trial_rng(s.seed, STREAMS["recording"]))
    np.testing.assert_array_equal(data.T, direct.astype(np.float32))
    _, pair = wavfile.read(tmp_path / "a" / "pair.wav")
    np.testing.assert_array_equal(pair, data[:, [0, 8]])
    nav = pd.read_csv(tmp_path / "a" / "nav.csv")
    truth = pd.read_csv(tmp_path / "a" / "truth.csv")
    assert list(nav.columns) == ["time_s", "x_m", "y_m", "heading_deg", "array_x_m", "array_y_m",
                                 "array_heading_deg"]
    assert nav["time_s"].tolist() == [0, 1, 2, 3, 4, 5, 5.5] and len(truth) == 7  # to the end of the recording
    assert truth["cone_deg"].to_numpy() == pytest.approx(60.0, abs=1e-4)
    assert truth["side"].eq("starboard").all()


def test_blocks_are_written_one_at_a_time_and_memory_stays_small(tmp_path, monkeypatch):
    """120 s x 16 channels is 61 MB as float64: written block by block, the peak allocation stays below a tenth."""
    s = PassiveSceneSettings(duration_s=120.0)
    calls = []
    original = wav_writer.WavBlockWriter.write

    def counting(self, block):
        calls.append(np.shape(block))
        return original(self, block)

    monkeypatch.setattr(wav_writer.WavBlockWriter, "write", counting)
    tracemalloc.start()
    try:
        scene_files.write_passive_files(s, tmp_path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    total = 120 * 4000 * 16 * 8
    assert peak < total / 10, f"peak {peak / 1e6:.1f} MB"
    assert calls.count((16, 4000)) == 120 and calls.count((2, 4000)) == 120
    assert (tmp_path / "recording.wav").stat().st_size == 44 + 120 * 4000 * 16 * 4


def test_last_block_may_be_short():
    s = scene([], duration_s=2.25, noise_level_db=60.0)
    shapes = [b.shape for b in array_blocks(s, np.random.default_rng(0))]
    assert shapes == [(16, 4000), (16, 4000), (16, 1000)]
    assert plan_blocks(s).n_blocks == 3


@pytest.mark.parametrize("bad, needle", [
    ({"band_hz": [50.0, 3000.0]}, "band_hz"),
    ({"environment": "baltic"}, "south-summer"),
    ({"samples": {"pair_elements": [1, 17]}}, "pair_elements"),
    ({"samples": {"tma_ship": "nobody"}}, "tma_ship"),
    ({"ships": [alongside(60, 1000), alongside(70, 1000)]}, "unique"),
])
def test_inconsistent_scenes_are_refused(bad, needle):
    with pytest.raises(ValidationError, match=needle):
        PassiveSceneSettings(**bad)


def test_sample_inputs_agree_with_the_scene(tmp_path):
    from sonartrack.io.contacts import read_contacts
    from sonartrack.io.environment import read_profile

    s = PassiveSceneSettings(duration_s=300.0)
    write_scene(s, tmp_path, only="samples")
    assert not (tmp_path / "recording.wav").exists()
    cart = read_contacts(tmp_path / "contacts.csv")
    raw = read_contacts(tmp_path / "raw.csv", nav_path=tmp_path / "raw_nav.csv")
    np.testing.assert_allclose(raw.z, cart.z, rtol=1e-5, atol=0.5)  # the same contacts, two ways
    # ship echoes: within a few sigma of a ship, about pd of them per ping
    g = scene_geometry(s, np.unique(cart.time_s))
    near = 0
    for k, t in enumerate(np.unique(cart.time_s)):
        z = cart.z[cart.time_s == t]
        d = np.linalg.norm(z[:, None, :] - g.ship_xy[:, k][None], axis=-1)
        near += int((d.min(axis=0) < 600.0).sum())
    n_expected = 0.8 * len(s.ships) * g.time_s.size
    assert 0.8 * n_expected < near < 1.2 * n_expected + 5
    brg = pd.read_csv(tmp_path / "brg.csv")
    gt = scene_geometry(s, brg["time_s"].to_numpy())
    resid = np.angle(np.exp(1j * (np.deg2rad(brg["bearing_deg"]) - gt.bearing_rad[2])))
    assert 0.6 < np.rad2deg(resid).std() < 1.5  # sigma 1 deg, 31 samples
    own = pd.read_csv(tmp_path / "own.csv")
    np.testing.assert_allclose(own[["x_m", "y_m"]].to_numpy(), gt.array_xy, atol=0.01)
    frames = np.load(tmp_path / "frames.npy")
    assert frames.shape == (6, 16, 64) and (frames >= 0).all()
    env = read_profile(tmp_path / "ctd.csv")
    assert env.water_depth_m == pytest.approx(193.0, abs=1.0)


def test_int16_writer_states_its_scale(tmp_path):
    x = np.array([[0.0, 1.0, -1.0, 0.5, 3.0], [0.25, -0.25, 2.0, -2.0, -9.0]])
    with wav_writer.wav_block_writer(tmp_path / "a.wav", 2, 8000, "int16", full_scale=2.0) as w:
        w.write(x[:, :2])
        w.write(x[:, 2:])
    fs, data = wavfile.read(tmp_path / "a.wav")
    assert fs == 8000 and data.dtype == np.int16
    expected = np.clip(np.round(x * 32767 / 2.0), -32768, 32767).astype(np.int16)  # 2.0 Pa = full scale
    np.testing.assert_array_equal(data.T, expected)
