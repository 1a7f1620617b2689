"""The expected echo-to-background ratio against hand-worked cases (sim/active_background.py)."""

import numpy as np
import pytest
from scipy.special import j0

from sonartrack.sim.active_background import (
    ambiguity_delay_integral_s,
    echo_background_db,
    reverberation_in_cell,
)
from sonartrack.sim.active_scene import ActiveSceneSettings, Platforms


class SphericalNoAbsorption:
    """20 log10 r per leg, no absorption: the closed form's TL (duck-types sim/active_tl.TransmissionLoss)."""

    def tx(self, range_m, depth_m):
        return 20.0 * np.log10(np.asarray(range_m, float))

    rx = tx


def _still_monostatic(heading_rad: float = 0.0) -> Platforms:
    """Source and array at the origin, still, the array's axis north: Doppler 0 everywhere, path = 2 r."""
    z = np.zeros((1, 2))
    return Platforms(np.zeros(1), z, np.full(1, heading_rad), z, z, z, z, np.full(1, heading_rad))


def _scene(kind: str, strength_db: float, volume_density: float = 0.0) -> ActiveSceneSettings:
    return ActiveSceneSettings(
        waveform={"kind": kind, "duration_s": 1.0, "carrier_hz": 1500.0, "bandwidth_hz": 100.0},
        sonar={"elements": 2, "spacing_m": 0.5},
        reverberation={"boundary": {"density_per_km2": 100.0, "strength_db": strength_db, "shape": 1.0,
                                    "depth_m": 100.0},
                       "volume": {"density_per_km2": volume_density, "strength_db": -150.0, "shape": 1.0,
                                  "depth_m": 50.0},
                       "min_range_m": 10.0}, targets=[])


def test_cw_zero_doppler_delay_integral_is_two_thirds_of_the_pulse():
    # int_{-tau}^{tau} (1 - |u|/tau)^2 du = 2 tau / 3
    assert ambiguity_delay_integral_s("cw", 2.0, 0.0, 0.0) == pytest.approx(4.0 / 3.0, rel=1e-5)


def test_lfm_delay_integral_is_the_resolution_and_cw_off_the_ridge_is_small():
    # B tau = 100: the compressed pulse's energy width is 1 / B at small Doppler offsets
    assert ambiguity_delay_integral_s("lfm", 1.0, 100.0, [0.0, 3.0]) == pytest.approx([0.01, 0.01], rel=0.05)
    # CW: 5 Hz off (5 Doppler cells of 1 / tau) passes < 2 % of the ridge's
    assert ambiguity_delay_integral_s("cw", 1.0, 0.0, 5.0) < 0.02 * 2.0 / 3.0


def test_flat_reverberation_matches_the_closed_form():
    # monostatic, still, S per m^2, two elements lambda/2 apart steered broadside: on the circle r = c t / 2,
    # dA/dt = r c / 2, |b|^2 = cos^2((pi/2) cos a), int_0^2pi |b|^2 da = pi (1 + J0(pi)), J = 2 tau / 3 (CW)
    scene = _scene("cw", -40.0)
    c, t0 = scene.sound_speed_mps, 8.0
    r = c * t0 / 2.0
    expected = 10.0 ** (-4.0) * 10.0 ** (scene.sonar.source_level_db / 10.0) * r ** -4 * r * c / 2.0 \
        * (2.0 / 3.0) * np.pi * (1.0 + j0(np.pi))
    table = (np.linspace(-1, 1, 201), ambiguity_delay_integral_s("cw", 1.0, 0.0, np.linspace(-1, 1, 201)))
    got = reverberation_in_cell(scene, SphericalNoAbsorption(), _still_monostatic(), 0, t0, np.pi / 2, 0.0, table)
    assert got == pytest.approx(expected, rel=1e-3)


def test_reverberation_doubles_with_the_strength_and_endfire_beam_differs():
    scene_a, scene_b = _scene("lfm", -40.0), _scene("lfm", -40.0 + 10.0 * np.log10(2.0))
    table = (np.linspace(-1, 1, 21), ambiguity_delay_integral_s("lfm", 1.0, 100.0, np.linspace(-1, 1, 21)))
    args = (SphericalNoAbsorption(), _still_monostatic(), 0, 8.0)
    a = reverberation_in_cell(scene_a, *args, np.pi / 2, 0.0, table)
    assert reverberation_in_cell(scene_b, *args, np.pi / 2, 0.0, table) == pytest.approx(2.0 * a, rel=1e-9)
    # endfire of 2 elements lambda/2 apart: int cos^2((pi/2)(cos a - 1)) da = pi (1 - J0(pi))
    end = reverberation_in_cell(scene_a, *args, 0.0, 0.0, table)
    assert end / a == pytest.approx((1.0 - j0(np.pi)) / (1.0 + j0(np.pi)), rel=1e-3)


def test_noise_only_ebr_is_snr_and_reverberation_lowers_it_by_the_closed_form():
    quiet = _scene("cw", -150.0)
    truth = {"ping": np.array([1]), "travel_time_s": np.array([8.0]), "cone_deg": np.array([90.0]),
             "doppler_hz": np.array([0.0]), "snr_db": np.array([17.0])}
    tl, plat = SphericalNoAbsorption(), _still_monostatic()
    assert echo_background_db(quiet, tl, plat, truth)[0] == pytest.approx(17.0, abs=1e-6)
    loud = _scene("cw", -30.0)
    table = (np.linspace(-2, 2, 401), ambiguity_delay_integral_s("cw", 1.0, 0.0, np.linspace(-2, 2, 401)))
    rev = reverberation_in_cell(loud, tl, plat, 0, 8.0, np.pi / 2, 0.0, table)
    noise = 10.0 ** (loud.noise_level_db / 10.0) / (1.0 * 2)
    assert echo_background_db(loud, tl, plat, truth)[0] == pytest.approx(17.0 - 10 * np.log10(1 + rev / noise),
                                                                         abs=1e-3)
    assert rev / noise > 10.0  # the case is reverberation-limited (the test can tell the two apart)


def test_an_echo_past_the_window_has_no_ebr():
    scene = _scene("lfm", -40.0)
    truth = {"ping": np.array([1]), "travel_time_s": np.array([scene.ping_interval_s + 1.0]),
             "cone_deg": np.array([90.0]), "doppler_hz": np.array([0.0]), "snr_db": np.array([20.0])}
    assert np.isnan(echo_background_db(scene, SphericalNoAbsorption(), _still_monostatic(), truth)[0])


def test_lfm_peak_loss_is_the_unshifted_replica_matched_to_a_doppler_shifted_echo():
    """An LFM echo at Doppler f_d through the zero-Doppler replica: its peak power over a still echo's, by direct
    correlation of the sampled pulses (acoustics/matched_filter.py), against 20 log10(1 - |f_d| / B); a CW: 0 dB."""
    from sonartrack.acoustics.matched_filter import Waveform
    from sonartrack.sim.active_background import lfm_peak_loss_db

    w = Waveform(kind="lfm", carrier_hz=1500.0, bandwidth_hz=50.0, duration_s=1.0)
    fs = 800.0
    r0 = w.replica(fs, 0.0)
    n = len(r0)
    for fd in (5.0, -11.6, 20.0):
        echo = np.concatenate([np.zeros(n), w.replica(fs, fd), np.zeros(n)])
        peak = np.max(np.abs(np.correlate(echo, r0, "valid")) ** 2) / n**2
        assert 10.0 * np.log10(peak) == pytest.approx(lfm_peak_loss_db(w, fd), abs=0.05)
    cw = Waveform(kind="cw", carrier_hz=1500.0, bandwidth_hz=0.0, duration_s=1.0)
    assert lfm_peak_loss_db(cw, np.array([3.0, -7.0])).tolist() == [0.0, 0.0]
