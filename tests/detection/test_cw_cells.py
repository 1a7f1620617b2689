"""The CW front end (detection/cw_cells.py) and the MFTD across CW pings (detection/ping_mftd.py) on pings written
here from the equations, not by sim/.

The generator: element n of a uniform line array sits s_n = ((N - 1)/2 - n) d ahead of the centre (element 0 the
front); a plane-wave echo from cone angle theta, leading edge at the centre at travel time t0, Doppler f_d, reaches
element n at t_n = t0 - s_n cos(theta) / c. A CW of length tau at carrier f_c, received at f_c + f_d, has the
complex envelope at f_c

    x_n(t) = a exp(2 pi i f_d (t - t_n)) exp(-2 pi i f_c t_n),   t_n <= t < t_n + tau,

plus complex white noise of unit variance per sample.
"""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.matched_filter import Waveform
from sonartrack.core.errors import InputError
from sonartrack.detection.cells import FrontEndSettings, detect_ping
from sonartrack.detection.cfar import os_mean_factor
from sonartrack.detection.cw_cells import (
    CwEstimate,
    CwNormaliserSettings,
    cw_noise_estimate,
    cw_ping_cells,
    cw_threshold,
    equal_tail_map,
    first_searched_delay_s,
)
from sonartrack.detection.cw_ridge import beam_ridge_notch, ridge_notch, ridge_range_rates
from sonartrack.detection.ping_mftd import CellAxes, PingMftd, PingMftdSettings

FS, FC, TAU, C, N, D = 200.0, 1500.0, 1.0, 1500.0, 16, 0.5


def cw_ping(rng, echoes, window_s=30.0, noise=1.0):
    """(N, samples) complex baseband of CW echoes (t0 s, cone deg, f_d Hz, amplitude) in white noise (module doc)."""
    t = np.arange(int(window_s * FS)) / FS
    s = ((N - 1) / 2.0 - np.arange(N)) * D
    x = noise * (rng.standard_normal((N, t.size)) + 1j * rng.standard_normal((N, t.size))) / np.sqrt(2.0)
    for t0, cone_deg, fd, a in echoes:
        tn = t0 - s * np.cos(np.deg2rad(cone_deg)) / C
        on = (t[None] >= tn[:, None]) & (t[None] < tn[:, None] + TAU)
        x += on * a * np.exp(2j * np.pi * fd * (t[None] - tn[:, None])) * np.exp(-2j * np.pi * FC * tn)[:, None]
    return x.astype(np.complex64)


def test_threshold_law_matches_monte_carlo_of_sorted_exponentials():
    """P(y / max(x_f, sqrt(x_e x_l)) > alpha), each x an OS estimate, by sorting exponentials (not by the Beta law,
    the convolution or the integral)."""
    law = CwEstimate((12, 9), (4, 3))
    rng = np.random.default_rng(3)
    n = 400_000

    def os(nn, k):
        return np.sort(rng.exponential(1.0, (n, nn)), axis=1)[:, k - 1] / os_mean_factor(nn, k)

    m = np.maximum(os(12, 9), np.sqrt(os(4, 3) * os(4, 3)))
    y = rng.exponential(1.0, n)
    for alpha in (3.0, 8.0, 14.0):
        p = law.pfa(alpha)
        measured = float(np.mean(y / m > alpha))
        assert abs(measured - p) < 5 * np.sqrt(p / n) + 2e-5, (alpha, p, measured)
    draws = law.draw(np.random.default_rng(4), (n,))
    assert abs(float(np.mean(y / draws > 8.0)) - law.pfa(8.0)) < 5 * np.sqrt(law.pfa(8.0) / n)


def test_pooled_statistic_draws_follow_the_max_of_sorted_exponential_cells():
    """The calibration's draws of the max of 4 normalised noise cells (one uniform each, by the law's survival
    table) against the max of 4 cells y / max(x_f, sqrt(x_e x_l)), each x an OS estimate by sorting exponentials."""
    law = CwEstimate((12, 9), (4, 3))
    rng = np.random.default_rng(13)
    n = 100_000

    def os(nn, k):
        return np.sort(rng.exponential(1.0, (n, 4, nn)), axis=-1)[..., k - 1] / os_mean_factor(nn, k)

    s = (rng.exponential(1.0, (n, 4)) / np.maximum(os(12, 9), np.sqrt(os(4, 3) * os(4, 3)))).max(axis=1)
    draws = law.draw_statistic(np.random.default_rng(14), (n,), pool=4)
    for alpha in (1.0, 3.0, 6.0, 10.0):
        p = 1.0 - (1.0 - law.pfa(alpha)) ** 4
        for x in (s, draws):
            assert abs(float(np.mean(x > alpha)) - p) < 5 * np.sqrt(p / n) + 1e-5, (alpha, p)
    x, a = law.survival_table()
    assert x[0] == 0.0 and a[0] == 0.0 and np.all(np.diff(x) > 0)
    np.testing.assert_allclose(np.exp(-np.interp([2.0, 9.0, 20.0], a, x)), [law.pfa(v) for v in (2.0, 9.0, 20.0)],
                               rtol=1e-3)


def test_normaliser_keeps_its_false_alarm_rate_in_homogeneous_noise():
    s = CwNormaliserSettings()
    rng = np.random.default_rng(5)
    y = rng.exponential(1.0, (40, 120, 61)).astype(np.float32)
    stat = y / cw_noise_estimate(y, s, 4, 2)
    pfa = 1e-3
    rate = float(np.mean(stat > cw_threshold(pfa, s)))
    assert 0.6 * pfa < rate < 1.5 * pfa, rate
    assert s.estimate() == CwEstimate((12, 9), (4, 3))


def test_normaliser_keeps_its_rate_on_a_steeply_falling_background():
    """Reverberation falling 10 dB a second from 1.5 s down to the noise (the first seconds after the blanking): the
    greatest-of with the earlier cells masked the cells there, the later cells alone alarm; the geometric mean of
    both is the level where the log level is linear (and above it at the knee), from the first searched delay."""
    from sonartrack.detection.cw_cells import first_searched_delay_s

    rng = np.random.default_rng(8)
    delay = np.arange(120) * 0.25
    level = 10.0 ** (4.0 - np.clip(delay - 1.5, 0.0, None))[None, :, None] + 1.0
    y = (rng.exponential(1.0, (30, 120, 61)) * level).astype(np.float32)
    s = CwNormaliserSettings(delay_guard=1)
    stat = y / cw_noise_estimate(y, s, 4, 2)
    first = int(round(first_searched_delay_s(FrontEndSettings(), s, TAU) / 0.25))
    assert first == 14  # blank 1.5 s + 2 pulse lengths (one guard pulse)
    pfa = 1e-3
    assert float(np.mean(stat[:, first:first + 24] > cw_threshold(pfa, s))) < 2 * pfa
    d = np.arange(first, first + 8)
    late = np.sort(np.stack([y[:, d + 4 * k] for k in range(2, 6)], -1), -1)[..., 2] / os_mean_factor(4, 3)
    assert float(np.mean(y[:, d] / late > cw_threshold(pfa, s))) > 5 * pfa  # the later cells alone under-estimate


def test_ridge_rates_and_notch_by_hand():
    """Array heading north, source and receiver both at 2 m/s north: a stationary scatterer ahead closes at 4 m/s
    (rdot = -4), abeam 0, at cone 60 deg -4 cos 60 = -2 on both sides; heading east, cone 90: starboard is south,
    port north, both 0 for an eastward motion."""
    r = ridge_range_rates(np.array([0.0, 60.0, 90.0, 180.0]), 0.0, [0.0, 2.0], [0.0, 2.0])
    np.testing.assert_allclose(r, [[-4, -4], [-2, -2], [0, 0], [4, 4]], atol=1e-12)
    r = ridge_range_rates([90.0], np.pi / 2, [0.0, 1.0], [0.0, 1.0])  # moving north with the axis east
    np.testing.assert_allclose(r, [[2.0, -2.0]], atol=1e-12)  # starboard (south) opens, port (north) closes
    notch = ridge_notch(np.array([-3.0, -2.5, -1.0, 0.0]), np.array([[-2.0, -2.0]]), 1.0)
    assert notch.tolist() == [[True, True, True, False]]


@pytest.mark.parametrize("t0, cone, fd", [(12.37, 63.0, 3.3), (20.81, 118.0, -6.1)])
def test_detection_offsets_against_an_independent_ping(t0, cone, fd):
    """A CW echo written from its equation is detected at its delay, cone angle and Doppler."""
    rng = np.random.default_rng(11)
    x = cw_ping(rng, [(t0, cone, fd, 0.3)])
    fe = FrontEndSettings()
    cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, CwNormaliserSettings())
    det = detect_ping(cells, cw_threshold(fe.pfa, CwNormaliserSettings()))
    near = np.abs(det.travel_time_s - t0) < 1.0
    assert near.sum() >= 1
    k = np.argmax(np.where(near, det.statistic, -np.inf))
    # quarter-pulse cells refined by the parabola through log s; the delay estimate of neighbouring cells (each from
    # its own residue class of references) differs from cell to cell, which moves the parabola: 0.13 s of the 1 s
    assert abs(det.travel_time_s[k] - t0) < 0.15
    assert abs(det.cone_deg[k] - cone) < 1.5
    assert abs(det.doppler_hz[k] - fd) < 0.2  # filters 0.5 Hz apart, refined
    np.testing.assert_allclose(det.range_rate_mps[k], -C * det.doppler_hz[k] / FC)
    assert len(det) <= 12  # the echo and noise peaks: Pfa 1e-5 x ~4e5 cells = 4 expected, P(> 11 more) < 1e-3


def beam_power_by_elements(cone_deg, beam_deg, n=N, d=D, f=FC, c=C):
    """|(1/N) sum_n exp(2 pi i f s_n (cos theta - cos theta_b) / c)|^2, element by element (not the closed form)."""
    s_n = ((n - 1) / 2.0 - np.arange(n)) * d
    ph = 2j * np.pi * f * s_n[None, :] * (np.cos(np.deg2rad(cone_deg)) - np.cos(np.deg2rad(beam_deg)))[:, None] / c
    return np.abs(np.exp(ph).mean(axis=1)) ** 2


def test_beam_ridge_by_hand():
    """Axis north, source and receiver at 2 m/s north (rdot = -4 cos theta on both mirrors): the broadside beam's
    ridge spans -4 cos theta over its -10 dB main lobe (edges found on the element sum), plus the margin; the
    forward endfire beam of a half-wavelength array also hears astern (its grating lobe): both ends of the band."""
    from scipy.optimize import brentq

    edge = brentq(lambda t: beam_power_by_elements([t], 90.0)[0] - 0.1, 90.0, 99.0)  # the lobe's -10 dB edge
    half = 4.0 * abs(np.cos(np.deg2rad(edge)))
    rates = np.linspace(-6.0, 6.0, 1201)
    notch = beam_ridge_notch(rates, [90.0, 0.0], 0.0, [0.0, 2.0], [0.0, 2.0], LineArray(N, D), FC, C, -10.0, 0.5)
    inside = rates[notch[0]]
    assert abs(inside.max() - (half + 0.5)) < 0.03 and abs(inside.min() + half + 0.5) < 0.03
    assert notch[1][np.argmin(abs(rates + 4.0))] and notch[1][np.argmin(abs(rates - 4.0))]
    assert not notch[1][np.argmin(abs(rates))]  # broadside's rate is not in the endfire beam's lobes


def test_notch_removes_the_ridge_cells_only():
    """Platforms still (the sea's Doppler 0 in every beam, a ridge only the margin wide): an echo at 0.2 m/s goes, one
    at 5 m/s stays."""
    rng = np.random.default_rng(2)
    x = cw_ping(rng, [(10.0, 90.0, 0.2, 0.3), (15.0, 90.0, -5.0, 0.3)])
    fe = FrontEndSettings()
    s = CwNormaliserSettings()
    cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, s,
                          motion=(0.0, np.zeros(2), np.zeros(2)))
    det = detect_ping(cells, cw_threshold(fe.pfa, s))
    assert not (np.abs(det.travel_time_s - 10.0) < 1.0).any()  # 0.2 m/s from the ridge: notched
    assert (np.abs(det.travel_time_s - 15.0) < 0.1).any()  # 5 m/s from it: kept
    assert np.all(cells.statistic[:, :, np.abs(cells.range_rate_mps) <= 1.0] == 0)


def test_too_short_a_bank_is_a_clear_error():
    y = np.ones((2, 40, 9), np.float32)
    with pytest.raises(InputError, match="Doppler bank"):
        cw_noise_estimate(y, CwNormaliserSettings(), 4, 2)


def test_mftd_on_cw_pings_finds_the_target_delay_and_doppler():
    """Issue 34: every MFTD detection of CW pings sat at the first searched delay; here the target's delay and
    Doppler are found."""
    T, rate, t_first, cone = 30.0, -4.0, 14.0, 75.0  # bistatic range rate -4 m/s: f_d = +4 Hz, -0.08 s a ping
    fd = -FC * rate / C
    rng = np.random.default_rng(21)
    fe, s = FrontEndSettings(beams=31, max_range_rate_mps=8.0), CwNormaliserSettings()  # small: a fast test
    mftd, out = None, []
    for k in range(4):
        t0 = t_first + k * T * rate / C
        x = cw_ping(rng, [(t0, cone, fd, 0.08)], window_s=20.0)
        cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, s, time_s=k * T, ping=k)
        if mftd is None:
            mftd = PingMftd(CellAxes.of(cells), T, 1e-6, C, PingMftdSettings(calibration_trials=200), cfar=s.estimate())
        out.append(mftd.push(cells))
    last, t_last = out[-1], t_first + 3 * T * rate / C
    assert len(last) >= 1
    k = int(np.argmax(last.statistic))
    assert abs(last.travel_time_s[k] - t_last) < 0.3  # a pooled cell is two quarter-pulse delays
    assert abs(last.doppler_hz[k] - fd) < 0.5  # one filter
    assert abs(last.range_rate_mps[k] - rate) < 0.5
    assert abs(last.cone_deg[k] - cone) < 3.0
    assert not np.any(last.delay_cell == 0)


def test_doppler_estimate_alone_has_rohlings_os_threshold():
    """With no delay estimate the normaliser is one OS-CFAR across Doppler: the integral's threshold is Rohling's
    closed form (detection/cfar.py)."""
    from sonartrack.detection.cfar import os_threshold

    s = CwNormaliserSettings(delay_reference=None)
    assert s.estimate() == CwEstimate((12, 9), None)
    for pfa in (1e-3, 1e-5):
        np.testing.assert_allclose(cw_threshold(pfa, s), os_threshold(pfa, 12, 9), rtol=2e-3)


def test_one_sided_law_matches_monte_carlo_and_the_map_carries_its_tail_to_the_two_sided_law():
    """The early delays' statistic y / max(x_f, x_l), each x an OS estimate by sorting exponentials: its tail is the
    one-sided law's integral, and mapped by equal tails its cells exceed the two-sided law's thresholds at their
    false-alarm rates (the map checked on Monte Carlo cells, not on the tables it is built from)."""
    one, two = CwEstimate((12, 9), (4, 3), 0.0), CwEstimate((12, 9), (4, 3))
    assert CwNormaliserSettings(early_search="late").early_estimate() == one
    rng = np.random.default_rng(21)
    n = 400_000

    def os(nn, k):
        return np.sort(rng.exponential(1.0, (n, nn)), axis=1)[:, k - 1] / os_mean_factor(nn, k)

    s = rng.exponential(1.0, n) / np.maximum(os(12, 9), os(4, 3))
    for alpha in (3.0, 8.0, 14.0):
        p = one.pfa(alpha)
        assert abs(float(np.mean(s > alpha)) - p) < 5 * np.sqrt(p / n) + 2e-5, (alpha, p)
    trend = CwEstimate((12, 9), (4, 3), 0.875)
    assert CwNormaliserSettings(early_search="trend", delay_guard=1).early_estimate() == trend  # r = 3.5 / 4
    assert CwNormaliserSettings().early_estimate() is None  # off by default (module doc: false alarms measured)
    s_trend = rng.exponential(1.0, n) / np.maximum(os(12, 9), os(4, 3) ** 1.875 / os(4, 3) ** 0.875)
    for alpha in (3.0, 8.0, 14.0):
        p = trend.pfa(alpha)
        assert abs(float(np.mean(s_trend > alpha)) - p) < 5 * np.sqrt(p / n) + 2e-5, (alpha, p)
    assert one.pfa(8.0) > 1.05 * two.pfa(8.0)  # one side: a noisier estimate, a heavier tail (x_f tames it)
    mapped = equal_tail_map(s, one, two)
    for pfa in (1e-2, 1e-3, 1e-4):
        rate = float(np.mean(mapped > two.threshold(pfa)))
        assert abs(rate - pfa) < 5 * np.sqrt(pfa / n), (pfa, rate)
    grid = np.array([0.5, 2.0, 9.0, 30.0, 5e4])
    assert np.all(np.diff(equal_tail_map(grid, one, two)) > 0)
    assert np.all(equal_tail_map(grid[2:], one, two) < grid[2:])  # in the tail the one-sided cells are marked down


def test_an_echo_before_the_two_sided_delays_is_found_by_the_early_search():
    """An echo 0.8 s after the blanking, before the first delay with earlier references: found with the early
    search at its delay, not searched without it; the early cells' mapped statistic keeps the false-alarm rate."""
    x = cw_ping(np.random.default_rng(12), [(2.3, 70.0, 4.1, 0.3)])
    fe = FrontEndSettings()
    assert first_searched_delay_s(fe, CwNormaliserSettings(delay_guard=1), TAU) == pytest.approx(3.5)
    assert first_searched_delay_s(fe, CwNormaliserSettings(delay_guard=0), TAU) == pytest.approx(2.5)
    found = []
    for early in ("trend", "late", "off"):
        s = CwNormaliserSettings(early_search=early, delay_guard=1)
        cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, s)
        det = detect_ping(cells, cw_threshold(fe.pfa, s))
        found.append(bool((np.abs(det.travel_time_s - 2.3) < 0.2).any()))
        assert cells.delay_s[0] == pytest.approx(fe.blank_s if early != "off" else 3.5, abs=0.13)
    assert found == [True, True, False]
    y = np.random.default_rng(6).exponential(1.0, (40, 120, 61)).astype(np.float32)
    s = CwNormaliserSettings(early_search="trend")
    stat = equal_tail_map(y[:, :8] / cw_noise_estimate(y, s, 4, 2, early_rows=8)[:, :8], s.early_estimate(),
                          s.estimate())
    assert 0.6e-3 < float(np.mean(stat > cw_threshold(1e-3, s))) < 1.5e-3


def test_references_after_the_blanking_unmask_an_echo_behind_the_blast():
    """A blast 50 dB up in the blanked start, in the echo's beam and Doppler: the earlier delay references of an echo
    at 4.5 s (0 to 3 s back) hold two blast cells and its rank-3-of-4 estimate masks the echo; with the references
    taken after the blanking only the echo is found."""
    x = cw_ping(np.random.default_rng(14), [(0.2, 70.0, 4.1, 100.0), (4.5, 70.0, 4.1, 0.3)])
    fe = FrontEndSettings()
    found = []
    for after in (False, True):
        s = CwNormaliserSettings(references_after_blank=after, delay_guard=1)  # references 3 to 0 s before
        cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, s)
        det = detect_ping(cells, cw_threshold(fe.pfa, s))
        found.append(bool((np.abs(det.travel_time_s - 4.5) < 0.2).any()))
    assert found == [False, True]
    assert CwNormaliserSettings().references_after_blank


def test_without_a_delay_guard_the_echo_stays_out_of_its_own_references():
    """A CW's matched-filter response to its echo is a triangle 2 tau wide at its base: the delay references one
    pulse length either side of the cell (delay_guard 0) hold none of it, so the echo's statistic is the one it has
    with a guard pulse (delay_guard 1)."""
    x = cw_ping(np.random.default_rng(21), [(10.0, 90.0, 2.0, 2.0)])
    fe = FrontEndSettings()
    got = {}
    for guard in (0, 1):
        s = CwNormaliserSettings(delay_guard=guard)
        cells = cw_ping_cells(x, FS, Waveform("cw", TAU, FC), LineArray(N, D), fe, s)
        at = np.unravel_index(np.argmax(cells.statistic), cells.statistic.shape)
        assert abs(cells.delay_s[at[1]] - 10.0) < 0.2
        got[guard] = float(cells.statistic[at])
    # within 1 dB: the echo (29 dB over the noise after the filter) leaking -25 dB into the references would lift mu
    assert got[0] == pytest.approx(got[1], rel=0.26)
