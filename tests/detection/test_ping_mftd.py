"""MFTD across pings (paper P1 run sliding per beam): tiles, threshold, false-alarm rate, a weak moving target."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.detection.ping_mftd import (
    CellAxes,
    PingMftd,
    PingMftdSettings,
    detect_pings,
    merge_across_beams,
    tail_threshold,
    tile_plan,
)

C = 1500.0
T = 30.0


def _axes(n_beams=1, n_time=256, n_doppler=5, dt=0.01, dv=0.5):
    v = (np.arange(n_doppler) - n_doppler // 2) * dv
    return CellAxes(np.linspace(10.0, 170.0, n_beams), 5.0 + np.arange(n_time) * dt, -v, v)


@pytest.mark.parametrize(("n", "own", "margin"), [(256, 32, 10), (100, 32, 40), (20, 64, 5), (97, 7, 0)])
def test_tiles_partition_the_axis_and_share_one_length(n, own, margin):
    tiles = tile_plan(n, own, margin)
    owned = np.concatenate([np.arange(a, b) for _, _, a, b in tiles])
    np.testing.assert_array_equal(owned, np.arange(n))
    lengths = {hi - lo for lo, hi, _, _ in tiles}
    assert lengths == {min(n, own + 2 * margin)}
    for lo, hi, a, b in tiles:
        assert 0 <= lo <= a and b <= hi <= n
        # a tile reaches its margin on each side wherever the axis allows
        assert a - lo >= min(margin, a) and hi - b >= min(margin, n - b)


def test_tail_threshold_empirical_and_extrapolated():
    rng = np.random.default_rng(5)
    x = rng.exponential(1.0, 4000)  # P(X > t) = exp(-t)
    assert tail_threshold(x, 0.05) == pytest.approx(-np.log(0.05), abs=0.15)
    # 4000 x 1e-5 = 0.04 exceedances: the fitted exponential tail gives ln(1e5) = 11.5
    assert tail_threshold(x, 1e-5) == pytest.approx(np.log(1e5), abs=0.8)


def _noise(rng, axes, n_pings):
    return [rng.exponential(1.0, axes.shape) for _ in range(n_pings)]  # CFAR-normalised: noise mean 1


@pytest.mark.parametrize("pfa", [2e-4, 2e-5])
def test_threshold_gives_the_tile_false_alarm_probability(pfa):
    # fresh noise tiles (not the calibration's seeds): the fraction above lambda is pfa x tile cells; with
    # pfa = 2e-5 the tile probability is below 20 / trials, so lambda comes from the fitted tail
    axes = _axes(n_time=64)
    m = PingMftd(axes, T, pfa, C, PingMftdSettings(frames=3, tile_cells=64, calibration_trials=2000, pool_cells=1))
    K, L, D = m.tile_shape(3)
    p_tile = pfa * L * D
    det = m.detector(L)
    from sonartrack.detection.ping_mftd import tile_statistics

    rng = np.random.default_rng(11)
    n = 30_000
    y = rng.exponential(2.0, (K, n, L, D))
    stats, _ = tile_statistics(det, y, np.array([[0, L, 0, L]]))
    hits = int((stats[:, 0] > m.threshold(3)).sum())
    from scipy.stats import binom

    lo, hi = binom.ppf([0.0005, 0.9995], n, p_tile)
    slack = 1.0 if p_tile * 2000 >= 20 else 2.0  # the extrapolated tail is a model: allow a factor 2
    assert lo / slack <= hits <= hi * slack, (hits, n * p_tile)


@pytest.mark.parametrize("pool", [1, 2])
def test_false_detections_per_cell_on_noise_only_pings(pool):
    # pooled cells are the max of independent cells here, as in the calibration: the rate is the stated one
    pfa = 1e-3
    axes = _axes(n_beams=1, n_time=256, n_doppler=3)
    pings = _noise(np.random.default_rng(2), axes, 120)
    s = PingMftdSettings(frames=3, merge_beams=False, pool_cells=pool)
    d = detect_pings(pings, np.arange(120) * T, axes, T, pfa, C, s)
    per_cell = len(d) / (120 * 256 * 3)
    assert 0.5 * pfa <= per_cell <= 1.5 * pfa, per_cell


def test_false_detections_per_cell_after_an_os_cfar():
    # the cells a ping's front end gives: exponential power normalised by the OS-CFAR along delay (heavier-tailed
    # than an exponential); the calibration normalises its noise the same way, so the rate is still pfa
    from sonartrack.detection.cfar import CfarSettings, cfar_normalise

    pfa, cfar = 1e-3, CfarSettings()
    axes = _axes(n_beams=4, n_time=256, n_doppler=1)
    rng = np.random.default_rng(8)
    pings = [np.moveaxis(cfar_normalise(rng.exponential(1.0, (4, 1, 256)), cfar), 1, -1) for _ in range(60)]
    s = PingMftdSettings(frames=3, merge_beams=False, pool_cells=2, pool_beams=2)
    d = detect_pings(pings, np.arange(60) * T, axes, T, pfa, C, s, cfar=cfar)
    per_cell = len(d) / (60 * 4 * 256)
    assert 0.4 * pfa <= per_cell <= 1.5 * pfa, per_cell
    # without telling it the CFAR, the calibration on exponential cells lets through more than pfa
    d_plain = detect_pings(pings, np.arange(60) * T, axes, T, pfa, C, s)
    assert len(d_plain) > len(d)


def _target_pings(rng, axes, snr, n_pings, r0_m=4000.0, rate_mps=-2.0):
    """Noise pings (mean 1) with a Swerling-1 target (mean 1 + snr) on r_B = r0 + rate t, Doppler cell of rate."""
    pings, truth = [], []
    dv = axes.range_rate_mps[1] - axes.range_rate_mps[0]
    j = int(np.argmin(np.abs(axes.range_rate_mps - rate_mps)))
    for k in range(n_pings):
        y = rng.exponential(1.0, axes.shape)
        dt = axes.travel_time_s[1] - axes.travel_time_s[0]
        i = int(round(((r0_m + rate_mps * k * T) / C - axes.travel_time_s[0]) / dt))
        y[0, i, j] = rng.exponential(1.0 + snr)
        pings.append(y)
        truth.append((i, j))
    assert abs(axes.range_rate_mps[j] - rate_mps) < dv
    return pings, np.array(truth)


def test_weak_moving_target_found_by_mftd_more_often_than_by_one_ping():
    rng = np.random.default_rng(4)
    axes = _axes(n_beams=1, n_time=256, n_doppler=9, dt=0.02, dv=0.5)
    snr = 10 ** (8.0 / 10)
    pfa = 1e-4
    n = 150
    pings, truth = _target_pings(rng, axes, snr, n, r0_m=14_000.0, rate_mps=-1.0)
    d = detect_pings(pings, np.arange(n) * T, axes, T, pfa, C, PingMftdSettings(frames=4, snr_db=8.0, pool_cells=1))
    on_target = np.zeros(n, bool)
    for k in range(3, n):
        rows = d.ping == k
        on_target[k] = bool(np.any((np.abs(d.delay_cell[rows] - truth[k, 0]) <= 1)
                                   & (np.abs(d.doppler_cell[rows] - truth[k, 1]) <= 1)))
    mftd_pd = on_target[3:].mean()
    single_pd = pfa ** (1.0 / (1.0 + snr))  # Swerling 1, one cell, one ping (P1's K = 1 check)
    assert mftd_pd > single_pd + 0.1, (mftd_pd, single_pd)  # 147 windows: the SE of Pd is < 0.042
    # the detections reported carry their cell's axes, the delay refined within half a cell
    step = axes.travel_time_s[1] - axes.travel_time_s[0]
    assert np.all(np.abs(d.travel_time_s - axes.travel_time_s[d.delay_cell]) <= 0.5 * step + 1e-12)
    np.testing.assert_allclose(d.range_rate_mps, axes.range_rate_mps[d.doppler_cell])


def test_merge_keeps_the_strongest_of_neighbouring_beams():
    keep = merge_across_beams([0, 1, 2, 5, 1], [10, 11, 30, 10, 50], [3.0, 5.0, 9.0, 1.0, 2.0])
    # beam 0 @10 loses to beam 1 @11; beam 2 @30 is far in time from beam 1 @11; beam 5 alone; beam 1 @50 alone
    np.testing.assert_array_equal(keep, [False, True, True, True, True])


def test_no_doppler_waveform_gets_one_wide_range_rate_cell():
    axes = CellAxes(np.array([90.0]), 5.0 + np.arange(100) * 0.01, np.zeros(1), np.full(1, np.nan))
    m = PingMftd(axes, T, 1e-3, C, PingMftdSettings(max_range_rate_mps=10.0, frames=2, pool_cells=2))
    # one range-rate cell of +-10 m/s; a range cell is 2 pooled cells of 0.01 s at 1500 m/s
    assert m.grid.n_doppler == 1 and m.grid.range_rate_cell_mps == 20.0 and m.grid.range_cell_m == pytest.approx(30.0)
    d = m.push_array(0, 0.0, np.ones(axes.shape))
    assert len(d) == 0 or np.isnan(d.range_rate_mps).all()


def test_bad_ping_shape_is_refused():
    m = PingMftd(_axes(), T, 1e-3, C)
    with pytest.raises(InputError, match="shape"):
        m.push_array(0, 0.0, np.ones((2, 3, 4)))


def test_parabola_offset_finds_the_peak_between_cells():
    from sonartrack.detection.ping_mftd import parabola_offset

    x = np.arange(9.0)
    log_y = -((x - 4.3) ** 2)[None, :, None] * np.ones((3, 1, 1))  # a parabola peaking at delay 4.3
    np.testing.assert_allclose(parabola_offset(log_y, np.array([1]), np.array([4]), np.array([0]), 1), [0.3])
    assert parabola_offset(log_y, np.array([1]), np.array([0]), np.array([0]), 1)[0] == 0.0  # edge: no offset
