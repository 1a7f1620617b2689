"""The cell lobe-image test (detection/lobes.py cell_images) against the closed-form pattern of a uniform line array
and pings from a small plane-wave generator written here (not the package's simulator)."""

from dataclasses import replace

import numpy as np
import pytest

from sonartrack.acoustics.active_beams import LineArray, cone_grid_deg
from sonartrack.acoustics.matched_filter import Waveform
from sonartrack.detection.cells import (
    FrontEndSettings,
    PingCells,
    detect_ping,
    detect_ping_flagged,
    detection_threshold,
    ping_front_end,
)
from sonartrack.detection.lobes import LobeBand, beam_gain_matrix, cell_images, main_lobe_u, pattern_power

C = 1500.0


def _band(n=8, d=0.5, f_lo=1000.0, f_hi=1000.0, weights=None, margin=3.0) -> LobeBand:
    return LobeBand(n, d, f_lo, f_hi, C, 0.01, margin, weights)


def test_pattern_is_the_uniform_lines_closed_form_by_hand():
    b = _band()  # x = pi f d du / c = pi du / 3
    # du = 3 / 8: N x = pi, the first null
    assert pattern_power(b, np.array(3.0 / 8.0))[0] == pytest.approx(0.0, abs=1e-12)
    # du = 4.5 / 8: N x = 1.5 pi, near the first sidelobe: 1 / (8 sin(3 pi / 16))^2 = 0.05061 (-12.96 dB)
    assert pattern_power(b, np.array(4.5 / 8.0))[0] == pytest.approx(1.0 / (8.0 * np.sin(3.0 * np.pi / 16.0)) ** 2)
    # at d = 1 m a grating lobe at du = c / (f d) = 1.5 is heard at full power
    assert pattern_power(_band(d=1.0), np.array(1.5))[0] == pytest.approx(1.0)
    # the band's frequencies each have their own pattern: at 1200 Hz the 1000 Hz null moved
    two = pattern_power(_band(f_lo=1000.0, f_hi=1200.0), np.array(3.0 / 8.0), n_freq=2)
    assert two[0] == pytest.approx(0.0, abs=1e-12)
    x = np.pi * 1200.0 * 0.5 * (3.0 / 8.0) / C
    assert two[1] == pytest.approx((np.sin(8 * x) / (8 * np.sin(x))) ** 2)


def test_main_lobe_is_the_first_null_and_shading_widens_it():
    assert main_lobe_u(_band()) == pytest.approx(C / (8 * 0.5 * 1000.0), abs=0.003)
    hann = tuple(np.hanning(10)[1:-1])  # 8 non-zero weights
    assert main_lobe_u(_band(weights=hann)) > 1.5 * main_lobe_u(_band())


def test_gain_matrix_is_zero_in_the_main_lobe_and_one_at_a_grating_lobe():
    cone = cone_grid_deg(61)
    u = np.cos(np.deg2rad(cone))
    g = beam_gain_matrix(_band(d=1.0), tuple(u.tolist()))  # lambda / d = 1.5
    b0 = int(np.argmin(np.abs(u - 0.75)))
    b1 = int(np.argmin(np.abs(u - (u[b0] - 1.5))))
    assert g[b1, b0] == pytest.approx(1.0, abs=0.02)
    assert g[b0, b0] == 0.0 and g[b0, b0 + 1] == 0.0
    # a beam beyond the main lobe and off the grating lobe: at most the first sidelobe (-13 dB, band of one tone)
    far = np.abs(u - u[b0]) > 0.6
    far &= np.abs(u - (u[b0] - 1.5)) > 0.4
    assert g[far, b0].max() <= 0.0506 + 1e-6


def _source_and_sidelobe_cells(notched: bool):
    """One ping's cells by hand: a strong echo (power 1e6) in beam b0 at delay cell 20 and its -13 dB sidelobe
    (power 1e6 x the pattern there) in beam b1; the echo's own cells notched (s = 0) when ``notched``."""
    cone = cone_grid_deg(61)
    u = np.cos(np.deg2rad(cone))
    b0 = int(np.argmin(np.abs(u - 0.9)))
    b1 = int(np.argmin(np.abs(u - (u[b0] - 4.5 / 8.0))))
    gain = float(pattern_power(_band(), np.array(u[b1] - u[b0]))[0])
    power = np.ones((61, 40, 6), np.float32)
    power[b0, 20, 1], power[b1, 20, 1] = 1e6, 1e6 * gain
    stat = power.copy()
    if notched:
        stat[b0] = 0.0
    cells = PingCells(1, 0.0, cone, 1.0 + 0.01 * np.arange(40), np.zeros(6), np.zeros(6), stat, True,
                      np.ones_like(stat), _band(), power if notched else None)
    return cells, b0, b1


@pytest.mark.parametrize("notched", [False, True])
def test_a_sidelobe_is_an_image_even_when_its_source_is_notched(notched):
    cells, b0, b1 = _source_and_sidelobe_cells(notched)
    d, j = np.array([20]), np.array([1])
    assert cell_images(cells, np.array([b1]), d, j).tolist() == [True]
    # ten times stronger than the sidelobe allows (10 dB over the pattern, 3 dB margin): a real echo, kept
    loud = cells.power.copy() if cells.power is not None else cells.statistic.copy()
    loud[b1, 20, 1] *= 10.0
    kw = {"power": loud} if cells.power is not None else {"statistic": loud, "level": np.ones_like(loud)}
    assert cell_images(replace(cells, **kw), np.array([b1]), d, j).tolist() == [False]
    # the source itself is no image, nor is the sidelobe at another delay or Doppler
    assert not cell_images(cells, np.array([b0]), d, j).any()
    # the same power at another delay (out of half the 10 ms resolution) or 3 Doppler cells away: no source there
    for d_other, j_other in ((30, 1), (20, 4)):
        moved = cells.power.copy() if cells.power is not None else cells.statistic.copy()
        moved[b1, 20, 1], moved[b1, d_other, j_other] = 1.0, 1e6 * 0.05  # the sidelobe level, moved
        kw = {"power": moved} if cells.power is not None else {"statistic": moved}
        assert not cell_images(replace(cells, **kw), np.array([b1]), np.array([d_other]), np.array([j_other]))[0]


# --- a small plane-wave ping generator (the physics, not sonartrack.sim) ---

def _plane_wave_ping(echoes, n=8, d=0.5, carrier=2000.0, band=400.0, tau=0.5, fs=1000.0, length_s=6.0, seed=3):
    """Complex baseband samples (n, M) of a line of ``n`` elements ``d`` apart (element 0 the front, at +(n-1)d/2
    along the axis) hearing LFM echoes (cone deg, delay s, amplitude) in unit complex white noise: element k hears
    the echo tau_k = -s_k cos(cone) / c later than the centre, its baseband phase exp(-2 pi i f_c tau_k)."""
    rng = np.random.default_rng(seed)
    m = int(length_s * fs)
    t = np.arange(m) / fs
    s = ((n - 1) / 2.0 - np.arange(n)) * d
    x = (rng.standard_normal((n, m)) + 1j * rng.standard_normal((n, m))) / np.sqrt(2.0)
    for cone, delay, amp in echoes:
        lag = -s * np.cos(np.deg2rad(cone)) / C
        for k in range(n):
            tt = t - delay - lag[k]
            inside = (tt >= 0) & (tt < tau)
            pulse = np.exp(1j * np.pi * band * (tt**2 / tau - tt))  # sweeps -B/2 .. +B/2 about the carrier
            x[k] += np.where(inside, amp * pulse * np.exp(-2j * np.pi * carrier * lag[k]), 0.0)
    return x, Waveform("lfm", tau, carrier, band), fs


def _near(det, delay_s, tol_s=0.01):
    return np.abs(det.travel_time_s - delay_s) < tol_s


def test_generated_ping_loses_its_sidelobe_detections_and_keeps_a_real_second_echo():
    # main echo at cone 60 (u 0.5), 62 dB over the noise after the beams and the matched filter; a second echo at
    # cone 120 (u -0.5) 6 dB weaker at the same travel time: the main echo's pattern there is -16.8 dB
    x, w, fs = _plane_wave_ping([(60.0, 3.0, 30.0), (120.0, 3.0, 15.0)])
    arr = LineArray(8, 0.5)
    off = FrontEndSettings(blast_guard_s=None, lobe_margin_db=None)
    on = off.model_copy(update={"lobe_margin_db": 3.0})
    thr = detection_threshold(off)
    raw = detect_ping(ping_front_end(x, fs, w, arr, off), thr)
    cells = ping_front_end(x, fs, w, arr, on)
    kept = detect_ping(cells, thr)
    every, image = detect_ping_flagged(cells, thr)  # the table keeps every detection, the images flagged
    assert len(every) == len(raw) and image.sum() >= 2 and np.array_equal(every.cone_deg[~image], kept.cone_deg)
    lobe_u = C / (8 * 0.5 * (w.carrier_hz + 0.5 * w.bandwidth_hz))  # the main lobe's half-width at the top
    u_raw, u_kept = (np.cos(np.deg2rad(d.cone_deg[_near(d, 3.0)])) for d in (raw, kept))

    def in_lobe(u):
        return (np.abs(u - 0.5) < lobe_u) | (np.abs(u + 0.5) < lobe_u)

    assert (~in_lobe(u_raw)).sum() >= 2  # the generated ping does hold sidelobe detections
    assert in_lobe(u_kept).all()  # every one is withheld
    assert (np.abs(u_kept - 0.5) < lobe_u).any() and (np.abs(u_kept + 0.5) < lobe_u).any()  # both echoes kept


def test_generated_ping_loses_a_real_echo_hidden_under_a_sidelobe():
    # the stated price: a second echo at the same travel time no stronger than the main echo's pattern there
    # (-16.8 dB) plus the margin is withheld as its image (here 20 dB down)
    x, w, fs = _plane_wave_ping([(60.0, 3.0, 30.0), (120.0, 3.0, 3.0)])
    arr = LineArray(8, 0.5)
    on = FrontEndSettings(blast_guard_s=None, lobe_margin_db=3.0)
    kept = detect_ping(ping_front_end(x, fs, w, arr, on), detection_threshold(on))
    u = np.cos(np.deg2rad(kept.cone_deg[_near(kept, 3.0)]))
    assert not (np.abs(u + 0.5) < C / (8 * 0.5 * 2200.0)).any()


def test_the_skirt_of_a_notched_echo_is_withheld_with_it():
    # a still point on its own beam's reverberation ridge: notched (s = 0) in beam b0, heard at -3..-10 dB on the
    # skirt of the main lobe in beam b2 (0.15 in u away, inside half the 0.375 main lobe), off that beam's ridge
    cone = cone_grid_deg(61)
    u = np.cos(np.deg2rad(cone))
    b0 = int(np.argmin(np.abs(u - 0.2)))
    b2 = int(np.argmin(np.abs(u - (u[b0] - 0.15))))
    skirt = float(pattern_power(_band(), np.array(u[b2] - u[b0]))[0])
    power = np.ones((61, 40, 3), np.float32)
    power[b0, 20, 1], power[b2, 20, 1] = 1e6, 1e6 * skirt
    stat = power.copy()
    args = (1, 0.0, cone, 1.0 + 0.01 * np.arange(40), np.zeros(3), np.zeros(3))
    det = (np.array([b2]), np.array([20]), np.array([1]), np.array([cone[b2]]))
    # not notched: the detection is the echo in b0 seen from its shoulder (the echo itself): kept
    assert not cell_images(PingCells(*args, stat, True, np.ones_like(stat), _band()), *det)[0]
    stat[b0] = 0.0
    assert cell_images(PingCells(*args, stat, True, np.ones_like(stat), _band(), power), *det)[0]
