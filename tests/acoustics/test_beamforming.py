"""Line-array beamforming front end (acoustics/beamforming.py): steering convention, array gain, normaliser,
peaks, the simulator's ships, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.beamforming import (
    BeamformerSettings,
    beam_powers,
    bearing_time_record,
    cbf_powers,
    front_end_band,
    normalise_across_bearing,
    pick_beam_peaks,
)
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.core.errors import InputError

FS, N, D, C = 4000.0, 16, 2.5, 1500.0
ARRAY = LineArray(N, D, C)


def plane_wave(rng, cone_deg, n=N, d=D, fs=FS, samples=4000, band=(50.0, 300.0)):
    """White band-limited noise arriving from ``cone_deg``: X_n(f) = S(f) exp(-2 pi i f tau_n),
    tau_n = -s_n cos(theta) / c, s_n = ((n_el - 1)/2 - n) d (the simulator's convention, written out here)."""
    f = np.fft.rfftfreq(samples, 1 / fs)
    spec = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * ((f >= band[0]) & (f < band[1]))
    s_n = ((n - 1) / 2 - np.arange(n)) * d
    tau = -s_n * np.cos(np.deg2rad(cone_deg)) / C
    x = np.fft.irfft(spec[None, :] * np.exp(-2j * np.pi * f[None, :] * tau[:, None]), samples, axis=1)
    return x / x.std()  # unit power per element


@pytest.mark.parametrize("cone", [60.0, 120.0, 33.3])
def test_cbf_peaks_at_the_arrival_cone_angle_not_mirrored(cone):
    # the octave below aliasing: the plane wave's band, narrow beams (the parabola's fit on the 1 deg grid)
    s = BeamformerSettings(method="cbf", band_hz=[150.0, 300.0])
    x = plane_wave(np.random.default_rng(1), cone)
    z = normalise_across_bearing(beam_powers(x, FS, ARRAY, s.cone_deg, s), s)
    angle, amp = pick_beam_peaks(z, s.cone_deg, s)
    best = angle[np.argmax(amp)]
    assert abs(best - cone) < 0.2, (best, cone)


def test_split_array_peaks_at_the_arrival_cone_angle():
    s = BeamformerSettings(method="split-array")
    for cone in (84.0, 97.0):  # the unsteered half-arrays hear only near broadside (module doc)
        x = plane_wave(np.random.default_rng(2), cone)
        z = normalise_across_bearing(beam_powers(x, FS, ARRAY, s.cone_deg, s), s)
        angle, amp = pick_beam_peaks(z, s.cone_deg, s)
        assert abs(angle[np.argmax(amp)] - cone) < 1.0


@pytest.mark.parametrize("beams", [37, 36, 3])
def test_cbf_equals_the_direct_sum_over_elements_and_bins(beams):
    """The lag-domain matrix product (module doc; the mirror beams from the first half's products, odd and even
    beam counts) against Y = sum_n exp(+2 pi i f tau_n) X_n summed |Y|^2."""
    rng = np.random.default_rng(4)
    n, m = 5, 256
    x = rng.standard_normal((n, m))
    s = BeamformerSettings(band_hz=[200.0, 1500.0], beams=beams, whiten=False, fft_precision="double")
    got = cbf_powers(x[None], FS, LineArray(n, 0.5, C), s)[0]
    f = np.fft.rfftfreq(m, 1 / FS)
    band = (f >= 200) & (f < 1500)
    spec = np.fft.rfft(x, axis=1)[:, band]
    s_n = ((n - 1) / 2 - np.arange(n)) * 0.5
    want = []
    for theta in np.deg2rad(s.cone_deg):
        tau = -s_n * np.cos(theta) / C
        y = (np.exp(2j * np.pi * f[band][None, :] * tau[:, None]) * spec).sum(axis=0)
        want.append(np.sum(np.abs(y) ** 2))
    np.testing.assert_allclose(got, want, rtol=1e-10)  # the equation to rounding; a wrong steering errs by O(1)


def test_single_precision_fft_stays_within_its_stated_error():
    x = np.random.default_rng(4).standard_normal((16, 4000))
    s = BeamformerSettings(band_hz=[200.0, 1500.0], beams=37, whiten=False)
    single = cbf_powers(x[None], FS, LineArray(16, 0.5, C), s)[0]
    double = cbf_powers(x[None], FS, LineArray(16, 0.5, C), s.model_copy(update={"fft_precision": "double"}))[0]
    assert np.max(np.abs(single / double - 1)) < 1e-5  # ~1e-7 of a bin: far below the normaliser's noise


def test_cbf_array_gain_is_ten_log_n_for_white_noise():
    """Signal power at the steered beam grows as N^2, independent noise as N: gain N = 12.0 dB for 16 elements."""
    rng = np.random.default_rng(5)
    s = BeamformerSettings(method="cbf", beams=181, band_hz=[50.0, 300.0], whiten=False)
    beam = 75
    sig_gain, noise_gain = [], []
    for _ in range(8):
        sig = plane_wave(rng, float(s.cone_deg[beam]))
        noise = rng.standard_normal((N, 4000))
        single_sig = np.sum(np.abs(np.fft.rfft(sig[0])[50:300]) ** 2)
        single_noise = np.sum(np.abs(np.fft.rfft(noise[0])[50:300]) ** 2)
        sig_gain.append(beam_powers(sig, FS, ARRAY, s.cone_deg, s)[beam] / single_sig)
        noise_gain.append(beam_powers(noise, FS, ARRAY, s.cone_deg, s)[beam] / single_noise)
    gain_db = 10 * np.log10(np.mean(sig_gain) / np.mean(noise_gain))
    assert gain_db == pytest.approx(10 * np.log10(N), abs=0.7)


@pytest.mark.parametrize("method", ["cbf", "split-array"])
def test_normaliser_is_invariant_to_the_recording_level(method):
    s = BeamformerSettings(method=method)
    rng = np.random.default_rng(6)
    x = plane_wave(rng, 80.0) + 3 * rng.standard_normal((N, 4000))
    z1 = normalise_across_bearing(beam_powers(x, FS, ARRAY, s.cone_deg, s), s)
    z2 = normalise_across_bearing(beam_powers(1000 * x, FS, ARRAY, s.cone_deg, s), s)
    np.testing.assert_allclose(z1, z2, rtol=1e-5, atol=1e-5)  # single-precision FFT in cbf
    assert z1.max() > 4.0 or method == "split-array"


def test_normaliser_median_and_mad_by_hand():
    s = BeamformerSettings()
    p = np.array([1.0, 2.0, 3.0, 4.0, 100.0])  # median 3, |p - 3| = 2 1 0 1 97 -> MAD 1
    np.testing.assert_allclose(normalise_across_bearing(p, s), (p - 3.0) / 1.4826)
    np.testing.assert_array_equal(normalise_across_bearing(np.zeros(5), s), np.zeros(5))


def test_pick_beam_peaks_parabola_endfire_and_max_peaks():
    s = BeamformerSettings(beams=11, threshold=2.0, max_peaks=2)  # 18 deg steps
    z = np.array([9.0, 5.0, 0.0, 3.0, 4.0, 3.0, 0.0, 5.0, 6.0, 0.0, 0.0])
    angle, amp = pick_beam_peaks(z, s.cone_deg, s)
    # peaks at beam 0 (mirrored: 5, 9, 5 -> exactly 0 deg, 9), beam 4 (3, 4, 3 -> 72 deg), beam 8 (5, 6, 0)
    # beam 8: delta = 0.5 (5 - 0) / (5 - 12 + 0) = -5/14; height 6 - 0.25 * 5 * delta
    np.testing.assert_allclose(angle, [0.0, 8 * 18.0 - 5 / 14 * 18.0])
    np.testing.assert_allclose(amp, [9.0, 6.0 + 0.25 * 5 * 5 / 14])
    s3 = BeamformerSettings(beams=11, threshold=2.0, max_peaks=3)
    angle3, _ = pick_beam_peaks(z, s3.cone_deg, s3)
    np.testing.assert_allclose(angle3[1], 72.0)
    high = BeamformerSettings(beams=11, threshold=8.0)
    assert pick_beam_peaks(z, high.cone_deg, high)[0].tolist() == [0.0]


def test_bearing_time_record_times_levels_and_progress():
    rng = np.random.default_rng(7)
    blocks = [plane_wave(rng, 100.0) + 0.5 * rng.standard_normal((N, 4000)) for _ in range(35)]
    seen = []
    btr = bearing_time_record(iter(blocks), FS, ARRAY, BeamformerSettings(), progress=seen.append)
    assert seen == list(range(35))
    np.testing.assert_allclose(btr.time_s, np.arange(35) + 0.5)
    assert btr.level.shape == (35, 181) and btr.level.dtype == np.float32
    assert set(np.unique(btr.peaks.time_s)) == set(btr.time_s)
    near = np.abs(btr.peaks.bearing_deg - 100.0) < 0.5
    assert len(np.unique(btr.peaks.time_s[near])) == 35
    np.testing.assert_allclose(btr.level[3], normalise_across_bearing(
        beam_powers(blocks[3], FS, ARRAY, btr.cone_deg, BeamformerSettings()), BeamformerSettings()), rtol=1e-5)


def test_simulator_ships_are_found_within_one_degree():
    """The simulator's plane-wave convention and truth cone angles agree with the beamformer's."""
    from sonartrack.sim.array_signals import array_blocks
    from sonartrack.sim.passive_scene import scene_geometry
    from sonartrack.sim.scene import PassiveSceneSettings

    scene = PassiveSceneSettings(duration_s=20.0)
    s = BeamformerSettings()
    array = LineArray(scene.array.elements, scene.spacing_m, scene.sound_speed_mps)
    btr = bearing_time_record(array_blocks(scene, np.random.default_rng(1)), scene.sample_rate_hz, array, s)
    truth = np.rad2deg(scene_geometry(scene, btr.time_s).cone_rad)
    for ship in (0, 1):  # the merchant and the trawler, the two loud ships of the default scene
        hits = 0
        for k, tk in enumerate(btr.time_s):
            at = btr.peaks.bearing_deg[btr.peaks.time_s == tk]
            hits += bool(np.any(np.abs(at - truth[ship, k]) < 1.0))
        assert hits >= 0.8 * len(btr.time_s), (scene.ships[ship].name, hits)


def test_line_array_aliasing_beamwidth_and_automatic_band_by_hand():
    # f_a = c / (2 d) = 1500 / 5 = 300 Hz; the automatic band is the octave below it
    assert ARRAY.aliasing_hz() == 300.0 and ARRAY.aliasing_hz(400.0) == 200.0
    assert ARRAY.band(FS) == Band(150.0, 300.0)
    assert ARRAY.band(400.0) == Band(100.0, 200.0)  # capped at fs / 2
    # 0.89 lambda / (N d) at 225 Hz: lambda = 6.667 m, N d = 40 m -> 0.14833 rad = 8.4989 deg
    assert ARRAY.beamwidth_deg(225.0) == pytest.approx(np.rad2deg(0.89 * (1500.0 / 225.0) / 40.0), rel=1e-12)
    assert ARRAY.beamwidth_deg(225.0) == pytest.approx(8.4989, abs=1e-4)
    assert ARRAY.band(FS, [50.0, 1000.0], allow_grating_lobes=True).centre_hz == 525.0


def test_refusals_name_the_fix():
    with pytest.raises(InputError, match=r"aliases above 300\.0 Hz.*<= 300 Hz"):
        ARRAY.band(FS, [50.0, 1000.0])
    ARRAY.band(FS, [50.0, 1000.0], allow_grating_lobes=True)
    ARRAY.band(FS)  # default band [150, 300) Hz stops at c / (2 d)
    with pytest.raises(InputError, match="half the sample rate"):
        LineArray(16, 0.5, C).band(1500.0, [50.0, 1000.0])
    with pytest.raises(InputError, match="at least 2 elements"):
        LineArray(1, 2.5, C)
    LineArray(2, 2.5, C).band(FS)  # two sensors: paper P0's correlator
    with pytest.raises(InputError, match="in metres"):
        LineArray(16, 250.0, C).band(FS)  # centimetres given as metres: no usable band
    with pytest.raises(InputError, match="spacing must be positive"):
        LineArray(16, -2.5, C)
    with pytest.raises(InputError, match="fewer than 16 samples"):
        front_end_band(ARRAY, BeamformerSettings(window_s=0.002), FS)
    with pytest.raises(InputError, match="aliases"):
        bearing_time_record([np.zeros((16, 4000))], FS, ARRAY, BeamformerSettings(band_hz=[50.0, 900.0]))
    with pytest.raises(InputError, match=r"\(16, 4000\), got \(8, 4000\)"):
        bearing_time_record([np.zeros((8, 4000))], FS, ARRAY, BeamformerSettings())


def test_automatic_band_by_hand():
    # the ships' band [50, 1000) Hz, from at least c / (N d) (an aperture of one wavelength), at most fs / 2
    assert ARRAY.band(FS, auto_hz=[50.0, 1000.0]) == Band(50.0, 1000.0)  # c / (N d) = 37.5 Hz < 50 Hz
    assert ARRAY.band(1500.0, auto_hz=[50.0, 1000.0]) == Band(50.0, 750.0)
    assert LineArray(8, 0.5, C).band(2000.0, auto_hz=[50.0, 1000.0]) == Band(375.0, 1000.0)  # 1500 / 4 m
    assert front_end_band(ARRAY, BeamformerSettings(), FS) == Band(50.0, 1000.0)  # grating lobes accepted
    with pytest.raises(InputError, match="aliases"):  # an explicit band above aliasing still needs consent
        front_end_band(ARRAY, BeamformerSettings(band_hz=[50.0, 1000.0]), FS)
    with pytest.raises(InputError, match="in metres"):
        front_end_band(LineArray(16, 250.0, C), BeamformerSettings(), FS)


def _latin_square():
    """Every pair of (element count, spacing), (element count, rate), (spacing, rate) once: 16 arrays."""
    elements, spacings, rates = (8, 16, 32, 64), (0.5, 1.25, 2.5, 5.0), (2000.0, 4000.0, 8000.0, 16000.0)
    return [(n, d, rates[(i + j) % 4]) for i, n in enumerate(elements) for j, d in enumerate(spacings)]


@pytest.mark.parametrize(("n", "d", "fs"), _latin_square())
def test_any_line_array_finds_a_loud_ship_at_its_cone_angle(n, d, fs):
    """The default front end on 8..64 elements, 0.5..5 m, 2..16 kHz: a ship at 0 dB per element in white noise,
    from a cone angle off the grid, is the highest peak, within 1 deg (its beam is 1.4..40 deg wide)."""
    rng = np.random.default_rng(int(n * 1000 + d * 10 + fs / 1000))
    cone = 37.3 + 11.0 * (n // 8 % 7) + 9.0 * d
    top = min(1000.0, fs / 2)
    signal = plane_wave(rng, cone, n=n, d=d, fs=fs, samples=int(fs), band=(50.0, top))
    x = signal + rng.standard_normal(signal.shape)
    array = LineArray(n, d, C)
    s = BeamformerSettings()
    btr = bearing_time_record([x], fs, array, s)
    assert btr.peaks.amplitude.size >= 1
    best = btr.peaks.bearing_deg[np.argmax(btr.peaks.amplitude)]
    assert abs(best - cone) < 1.0, (n, d, fs, cone, best)


def test_one_blas_thread_sets_and_restores_the_callers_count():
    from sonartrack.acoustics.blas_threads import _set_blas_threads_local, blas_reachable, one_blas_thread

    if not blas_reachable():
        pytest.skip("numpy's OpenBLAS is not reachable here: one_blas_thread does nothing")
    set_threads = _set_blas_threads_local()
    original = set_threads(3)
    try:
        with one_blas_thread():
            assert set_threads(1) == 1  # one thread inside
        assert set_threads(3) == 3  # the caller's 3 restored after
    finally:
        set_threads(original)
