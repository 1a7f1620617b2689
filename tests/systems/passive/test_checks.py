"""The recording's checks before the passive chain: silence, DC, clipping, bands, channel delays, aperture.

Each case is a small synthetic recording whose answer is known by construction: a plane wave delayed by a whole
number of samples between neighbouring channels, noise clipped at a level whose share of samples follows from the
Gaussian tail, a band-limited noise whose spectrum is zero outside its band.
"""

import numpy as np
import pytest
from scipy.stats import norm

from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.core.errors import InputError
from sonartrack.systems.passive import checks
from sonartrack.systems.passive.checks import check_aperture, check_recording, excerpt_starts, first_pass

FS = 4000.0
M = 4000  # 1 s windows


def windows(x: np.ndarray) -> list[np.ndarray]:
    """(N, n) -> whole windows of M samples (one excerpt)."""
    return [x[:, k * M:(k + 1) * M] for k in range(x.shape[1] // M)]


def band_noise(rng, n_ch: int, seconds: int, lo: float, hi: float) -> np.ndarray:
    """Independent Gaussian noise per channel with nothing outside [lo, hi) Hz (zeroed rfft bins)."""
    x = rng.standard_normal((n_ch, seconds * M))
    spec = np.fft.rfft(x, axis=1)
    f = np.fft.rfftfreq(x.shape[1], 1 / FS)
    spec[:, (f < lo) | (f >= hi)] = 0.0
    return np.fft.irfft(spec, x.shape[1], axis=1)


def plane_wave(rng, n_ch: int, seconds: int, step: int, snr: float = 1.0) -> np.ndarray:
    """A common broadband signal reaching channel n ``n * step`` samples later, plus independent noise."""
    s = rng.standard_normal(seconds * M + 2 * n_ch * abs(step) + 1)
    x = np.stack([s[n_ch * abs(step) - n * step: n_ch * abs(step) - n * step + seconds * M] for n in range(n_ch)])
    return snr * x + rng.standard_normal(x.shape)


def run(x, *, spacing=2.5, band=(100.0, 300.0), window_s=1.0, quantum=None, elements=None):
    fp = first_pass([windows(x)], FS)
    array = LineArray(elements or x.shape[0], spacing)
    return check_recording(fp, name="rec.wav", array=array, band=Band(*band), window_s=window_s, quantum=quantum)


def test_clean_noise_passes_without_warning():
    assert run(np.random.default_rng(0).standard_normal((4, 10 * M))) == []


def test_silence_is_refused():
    with pytest.raises(InputError, match="only zeros"):
        run(np.zeros((4, 5 * M)))


def test_dc_only_is_refused_and_a_dc_offset_on_noise_is_not():
    with pytest.raises(InputError, match="constant"):
        run(np.full((4, 5 * M), 0.37))
    assert run(0.37 + np.random.default_rng(1).standard_normal((4, 5 * M))) == []


def test_a_dead_channel_is_a_warning():
    x = np.random.default_rng(2).standard_normal((4, 5 * M))
    x[2] = 0.0
    (line,) = run(x)
    assert line.startswith("warning:") and "channel(s) 3 of 4" in line


def test_square_wave_is_refused():
    x = 0.8 * np.sign(np.random.default_rng(3).standard_normal((4, 5 * M)))
    with pytest.raises(InputError, match="100 % of the samples"):
        run(x)


def test_clipped_noise_is_a_warning_with_the_gaussian_tail_share():
    # clipping at 2.3 sd puts 2 Q(2.3) = 2.1 % of the samples at +-2.3 sd
    x = np.clip(np.random.default_rng(4).standard_normal((4, 20 * M)), -2.3, 2.3)
    (line,) = run(x)
    share = float(line.split("warning: rec.wav: ")[1].split(" %")[0])
    assert share == pytest.approx(100 * 2 * norm.sf(2.3), abs=0.1)
    assert "clipping" in line


def test_a_faint_integer_recording_is_not_called_clipped():
    # 16-bit samples of sd 0.3 step sit at -1, 0, 1: 2 Q(0.5 / 0.3) = 9.6 % at the extremes, but no clipping
    q = 2.0**-15
    x = np.round(np.random.default_rng(5).standard_normal((4, 10 * M)) * 0.3) * q
    assert run(x, quantum=q) == []
    (line,) = run(x)  # judged as float samples, the same values look clipped
    assert "clipping" in line


def test_band_narrower_than_the_resolution_is_refused_and_a_few_bins_warned():
    x = np.random.default_rng(6).standard_normal((4, 5 * M))
    with pytest.raises(InputError, match="narrower than the frequency resolution"):
        run(x, band=(200.2, 200.7))
    with pytest.raises(InputError, match="narrower than the frequency resolution"):
        run(x, band=(200.0, 200.5))  # one bin, half a resolution wide
    (line,) = run(x, band=(200.0, 202.0))
    assert "holds 2 frequency bin(s)" in line


def test_band_without_signal_is_refused_and_names_where_the_signal_is():
    x = band_noise(np.random.default_rng(7), 4, 10, 50.0, 500.0)
    assert run(x, band=(100.0, 400.0)) == []
    with pytest.raises(InputError, match=r"holds no signal .* lies in (49|50)-(500|501) Hz"):
        run(x, band=(1000.0, 1500.0))


def test_band_30_to_60_db_down_is_a_warning():
    rng = np.random.default_rng(8)
    x = band_noise(rng, 4, 10, 50.0, 500.0) + 10 ** (-40 / 20) * band_noise(rng, 4, 10, 1000.0, 1500.0)
    (line,) = run(x, band=(1000.0, 1500.0))
    assert "lies 40 dB below" in line


@pytest.mark.parametrize("step", [3, -5])
def test_delay_between_channels_is_measured(step):
    fp = first_pass([windows(plane_wave(np.random.default_rng(9), 4, 10, step))], FS)
    for p in range(3):
        k = int(np.argmax(fp.pair_z[p]))
        # channel p + 1 hears it `step` samples later: G_12 = X_p conj(X_p+1) peaks at lag -step
        assert fp.lag_s[k] == pytest.approx(-step / FS)
        assert fp.pair_z[p, k] > 20


def test_delays_longer_than_the_spacing_allows_are_refused():
    # 12 samples = 3 ms between neighbours: they are at least 4.5 m apart at 1500 m/s
    x = plane_wave(np.random.default_rng(10), 2, 10, 12)
    assert run(x, spacing=5.0, band=(50.0, 150.0)) == []
    with pytest.raises(InputError, match=r"3\.00 ms apart, more than the 1\.67 ms a spacing of 2\.5 m"):
        run(x, spacing=2.5, band=(50.0, 150.0))


def test_incoherent_channels_give_no_delay_error():
    assert run(np.random.default_rng(11).standard_normal((2, 10 * M)), spacing=0.5, band=(100.0, 1400.0)) == []


def test_aperture_in_kilometres_and_centimetres_is_refused():
    band = Band(150.0, 300.0)
    check_aperture(LineArray(16, 2.5), band, 1.0)
    # 16 x 2.5 mm = 4 cm; beamwidth 0.89 lambda / (N d) = 0.89 x 6.67 m / 0.04 m rad: far beyond 60 deg
    with pytest.raises(InputError, match="shorter than a wavelength"):
        check_aperture(LineArray(16, 0.0025), band, 1.0)
    # 15 x 250 m = 3750 m: 2.5 s to cross, more than half a 1 s window
    with pytest.raises(InputError, match="2.5 s to cross"):
        check_aperture(LineArray(16, 250.0), band, 1.0)
    check_aperture(LineArray(16, 250.0), Band(1.0, 2.9), 10.0)  # a 10 s window holds it (2.5 < 5 s)


def test_beamwidth_limit_matches_the_hand_formula():
    # N d = 0.89 lambda / (60 deg in rad): just longer passes, just shorter fails
    lam = 1500.0 / 225.0
    nd = 0.89 * lam / np.deg2rad(checks.MAX_BEAMWIDTH_DEG)
    check_aperture(LineArray(4, 1.01 * nd / 4), Band(150.0, 300.0), 1.0)
    with pytest.raises(InputError):
        check_aperture(LineArray(4, 0.99 * nd / 4), Band(150.0, 300.0), 1.0)


def test_excerpts_spread_over_the_file_without_overlap():
    spans = excerpt_starts(1200, 4000, FS)
    assert spans[0][0] == 0 and spans[-1][1] == 1200 * 4000
    assert all(b - a == 10 * 4000 for a, b in spans)
    assert all(spans[i][1] <= spans[i + 1][0] for i in range(len(spans) - 1))
    assert excerpt_starts(20, 4000, FS) == [(0, 20 * 4000)]  # a short file is read whole


def ar1(rng, n: int, rho: float) -> np.ndarray:
    """Unit-variance AR(1) noise."""
    e = rng.standard_normal(n) * np.sqrt(1 - rho**2)
    x = np.empty(n)
    x[0] = rng.standard_normal()
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
    return x


def test_residuals_of_the_stated_noise_are_consistent():
    rng = np.random.default_rng(20)
    t = np.arange(600.0)
    sigma = np.deg2rad(0.3)
    assert checks.residual_check(t, sigma * rng.standard_normal(600), sigma).consistent
    # AR(1) errors with rho = 0.5 are consistent once the stated inflation (1 + rho) / (1 - rho) = 3 is given
    e = sigma * ar1(rng, 600, 0.5)
    assert checks.residual_check(t, e, sigma, inflation=3.0).consistent
    assert not checks.residual_check(t, e, sigma, inflation=1.0).consistent


def test_residuals_larger_than_stated_fail_the_chi_square():
    rng = np.random.default_rng(21)
    t = np.arange(300.0)
    sigma = np.deg2rad(0.1)
    res = checks.residual_check(t, 1.5 * sigma * rng.standard_normal(300), sigma)
    assert res.chi2 > res.limit and not res.consistent
    # the limit is the 99.9 % quantile of chi-square(296): mean 296, sd sqrt(592)
    assert res.limit == pytest.approx(296 + 3.09 * np.sqrt(592), rel=0.03)
    assert "disagree" in res.note()


def test_a_slow_structure_left_in_the_residuals_fails_the_block_test_only():
    # a 0.5 sigma wave over 240 s: the total chi-square hardly moves (+12 %), the 30 s block means do
    rng = np.random.default_rng(22)
    t = np.arange(600.0)
    sigma = 1.0
    e = rng.standard_normal(600) * np.sqrt(1 - 0.125) + 0.5 * np.sin(2 * np.pi * t / 240.0)
    res = checks.residual_check(t, e, sigma)
    assert res.chi2 <= res.limit
    assert res.block_chi2 > res.block_limit and not res.consistent


# ---------------------------------------------------------------- is a determined range supported by its record?


def leg_turn_leg(t):
    """The ownship: north at 6 kn, a 45 deg turn to port at 0.5 deg/s from 150 s, then straight (positions, m)."""
    from sonartrack.sim.platforms import ManeuveringTrack

    track = ManeuveringTrack(0.0, 0.0, 3.0866, 0.0, ((150.0, 240.0, -np.deg2rad(0.5)),))
    return track.state(np.asarray(t, float))[0]


def bearings(t, own, target_xy0, v, sigma, seed):
    x = target_xy0[0] + v[0] * t - own[:, 0]
    y = target_xy0[1] + v[1] * t - own[:, 1]
    return np.arctan2(x, y) + sigma * np.random.default_rng(seed).standard_normal(t.size)


def test_profile_rise_is_quadratic_where_the_range_is_well_determined():
    # a near target (2 km): the likelihood is close to Gaussian, so holding the final range 1 CRB sd away
    # raises J by ~1 and 2 sd away by ~4 (noise-free bearings: the fit is the truth, J = 0 there)
    from sonartrack.tma.batch_ml import crb

    t = np.arange(0.0, 400.0, 2.0)
    own = leg_turn_leg(t)
    sigma = np.deg2rad(0.3)
    x0 = np.array([1500.0, 1300.0, -1.0, 2.0])
    z = bearings(t, own, x0[:2], x0[2:], 0.0, 0)
    end = x0 + np.array([x0[2], x0[3], 0, 0]) * t[-1]
    d = end[:2] - own[-1]
    r = float(np.hypot(*d))
    F = np.eye(4)
    F[0, 2] = F[1, 3] = t[-1]
    P = F @ crb(x0, t - t[0], own, sigma) @ F.T
    u = d / r
    sd = float(np.sqrt(u @ P[:2, :2] @ u))
    assert sd < 0.1 * r
    assert checks.range_profile_rise(t, z, own, sigma, end, r) == pytest.approx(0.0, abs=1e-6)
    # the likelihood in r is skewed (flatter outwards); the mean of the two sides cancels the cubic term
    up, down = (checks.range_profile_rise(t, z, own, sigma, end, r + k * sd) for k in (1.0, -1.0))
    assert up < 1.0 < down
    assert 0.5 * (up + down) == pytest.approx(1.0, rel=0.05)
    up2, down2 = (checks.range_profile_rise(t, z, own, sigma, end, r + k * sd) for k in (0.5, -0.5))
    assert 0.5 * (up2 + down2) == pytest.approx(0.25, rel=0.05)


def _ml(t, z, own, sigma_deg):
    """The passive chain's ML: the side decision's multi-start fit (covariance scaled by sigma^2) as the solution."""
    from dataclasses import replace

    from sonartrack.tma.records import BearingRecord, OwnshipTrack
    from sonartrack.tma.settings import TmaSettings
    from sonartrack.tma.sides import fit_cv_target
    from sonartrack.tma.solve import solve_tma

    fit = fit_cv_target(z, t, own)
    fit = replace(fit, covariance=fit.covariance * np.deg2rad(sigma_deg) ** 2)
    sensor = OwnshipTrack(time_s=t, x_m=own[:, 0], y_m=own[:, 1])
    settings = TmaSettings(method="ml", sigma_bearing_deg=sigma_deg)
    return solve_tma(BearingRecord(time_s=t, bearing_rad=z), sensor, settings, ml_fit=fit, unobservable="flag",
                     record_checks=False)  # as the chain calls it: its own checks follow


@pytest.mark.parametrize("seed", range(4))
def test_a_near_target_stays_determined(seed):
    from sonartrack.systems.passive.targets import determination_checked

    t = np.arange(0.0, 300.0, 1.0)
    own = leg_turn_leg(t)
    near = _ml(t, bearings(t, own, (1500.0, 1300.0), (-1.0, 2.0), np.deg2rad(0.3), seed), own, 0.3)
    assert near.solution.range_flags()[-1]
    assert determination_checked(near) is near


@pytest.mark.parametrize("seed", range(4))
def test_a_far_target_the_turn_barely_touches_is_not_determined(seed):
    # 13 km ahead on the port bow: the turn to port heads the ownship at it, so it moves the line of sight little;
    # the first-order covariance still calls the range determined (sd ~ half the range), the likelihood cannot
    # tell it from twice as far
    from sonartrack.systems.passive.targets import UNSUPPORTED_RANGE, determination_checked

    t = np.arange(0.0, 300.0, 1.0)
    own = leg_turn_leg(t)
    far = _ml(t, bearings(t, own, (-12000.0, 8000.0), (2.0, 0.0), np.deg2rad(0.5), seed), own, 0.5)
    assert far.solution.range_flags()[-1]
    checked = determination_checked(far)
    assert not checked.solution.range_flags().any()
    assert checked.warnings[-1].startswith(UNSUPPORTED_RANGE)


@pytest.mark.parametrize("elements", [16, 64])
def test_memory_estimate_matches_the_front_ends_arrays(elements):
    """The steering matrix's estimate is the bytes of the matrix the front end builds, and a batch's the peak
    tracemalloc sees while one batch of band spectra is beamformed (within 30 %)."""
    import tracemalloc

    from sonartrack.acoustics.beamforming import BATCH_WINDOWS, _band_steering, _cbf_from_spectra
    from sonartrack.systems.passive.settings import PassiveSettings

    st = PassiveSettings(spacing_m=1.25).stages(8000.0, channels=elements)
    steering_need, batch_need = (need for need, _, _ in checks.memory_needs(st, 600)[:2])
    idx, steer = _band_steering(elements, 8000, 8000.0, st.array, st.front_end, st.band)
    assert steering_need == pytest.approx(steer[0].nbytes + steer[1].nbytes, rel=0.01)
    rng = np.random.default_rng(0)
    shape = (BATCH_WINDOWS, elements, idx.size)
    tracemalloc.start()
    try:
        spectra = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(np.complex64)
        tracemalloc.reset_peak()
        _cbf_from_spectra(spectra, steer, True)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert 0.7 < peak / batch_need < 1.3


def test_a_three_day_recording_is_refused_for_its_lofar_gram_and_not_without_the_narrowband_pass():
    from sonartrack.systems.passive.settings import PassiveSettings

    days = 3 * 86400  # the gram: about 1.5 GB a day at 16 x 4 kHz (20 bytes a cell), over the 2 GB limit
    with pytest.raises(InputError, match="LOFAR gram"):
        checks.check_memory(PassiveSettings(spacing_m=2.5).stages(4000.0, channels=16), days)
    quiet = PassiveSettings.model_validate({"spacing_m": 2.5, "narrowband": {"enabled": False}})
    checks.check_memory(quiet.stages(4000.0, channels=16), days)


def test_chi_square_quantile_is_scipy_stats_to_the_bit():
    from scipy.stats import chi2

    from sonartrack.core.gaussian import chi2_quantile

    for q in (0.95, 0.99, 0.9973):
        for dof in (1, 2, 7, 40, 999):
            assert chi2_quantile(q, dof) == float(chi2.ppf(q, dof))


def test_memory_is_refused_on_the_sum_of_the_arrays_held_at_once():
    """Two arrays each under the limit but over it together (a 100 s window at 16 x 4 kHz: the steering matrix and
    a batch of band spectra, each about half the limit) are refused, and the message names the larger one's fix."""
    from sonartrack.systems.passive.settings import PassiveSettings

    stages = PassiveSettings(spacing_m=2.5, window_s=100.0).stages(4000.0, channels=16)
    needs = [n for n, _, _ in checks.memory_needs(stages, 1)]
    assert max(needs) < checks.MEMORY_LIMIT_BYTES < sum(needs)
    with pytest.raises(InputError, match="working arrays would take .* window_s"):
        checks.check_memory(stages, 1)
    checks.check_memory(PassiveSettings(spacing_m=2.5, window_s=20.0).stages(4000.0, channels=16), 1)
