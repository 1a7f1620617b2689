"""Line tracks in frequency and bearing (tracking/line_tracks.py): the Kalman filter against FilterPy, tracks and
sources on synthetic line detections with misses and false lines, and the harmonic ratios."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.tracking.line_tracks import (
    LineTrackerSettings,
    _models,
    group_sources,
    harmonic_ratio,
    track_lines,
)

T = 16.0  # integration period (s)


def _detections(rng, lines, n_periods, pd=0.85, false_per_period=3.0):
    """lines: (f0 Hz, fdot Hz/s, theta0 deg, thetadot deg/s); detections with noise 0.2 Hz / 1.5 deg, probability
    pd, plus uniform false lines over 50-600 Hz x 0-180 deg."""
    rows = []
    for k in range(n_periods):
        t = (k + 0.5) * T
        for f0, fd, th0, thd in lines:
            if rng.random() < pd:
                rows.append((t, f0 + fd * t + 0.2 * rng.standard_normal(), th0 + thd * t + 1.5 * rng.standard_normal(),
                             5.0))
        for _ in range(rng.poisson(false_per_period)):
            rows.append((t, rng.uniform(50, 600), rng.uniform(0, 180), 1.0))
    return np.array(rows).T


def test_filter_equals_filterpy():
    filterpy = pytest.importorskip("filterpy.kalman")
    s = LineTrackerSettings()
    rng = np.random.default_rng(2)
    t, f, th, snr = _detections(rng, [(200.0, 0.01, 60.0, 0.1)], 30, pd=1.0, false_per_period=0.0)
    (track,) = track_lines(t, f, th, snr, s)
    F, Q, H, R = _models(T, s)
    kf = filterpy.KalmanFilter(dim_x=4, dim_z=2)
    kf.F, kf.Q, kf.H, kf.R = F, Q, H, R
    kf.x = np.array([f[0], 0.0, th[0], 0.0])
    kf.P = np.diag([s.sigma_freq_hz**2, s.max_freq_rate_hz_s**2, s.sigma_bearing_deg**2, s.max_bearing_rate_deg_s**2])
    for k in range(1, len(t)):
        kf.predict()
        kf.update(np.array([f[k], th[k]]))
    assert track.frequency_hz[-1] == pytest.approx(kf.x[0], rel=1e-12)
    assert track.cone_deg[-1] == pytest.approx(kf.x[2], rel=1e-12)
    assert track.frequency_rate_hz_s[-1] == pytest.approx(kf.x[1], rel=1e-9)
    assert track.cone_rate_deg_s[-1] == pytest.approx(kf.x[3], rel=1e-9)


def test_tracks_and_sources_with_misses_and_false_lines():
    rng = np.random.default_rng(11)
    truth = [(200.0, 0.002, 60.0, 0.05), (400.0, 0.004, 60.0, 0.05), (300.0, 0.003, 60.0, 0.05),
             (170.0, -0.001, 120.0, -0.04)]
    t, f, th, snr = _detections(rng, truth, 40)
    tracks = track_lines(t, f, th, snr)
    long = [tr for tr in tracks if len(tr.time_s) >= 20]
    assert len(long) == 4
    assert len(tracks) - len(long) <= 2  # false lines rarely confirm (3 of 4 periods inside the gate)
    for tr in long:
        f0, fd, th0, thd = min(truth, key=lambda x: abs(x[0] - tr.mean_frequency_hz))
        tt = tr.time_s[-1]
        assert tr.frequency_hz[-1] == pytest.approx(f0 + fd * tt, abs=0.3)
        assert tr.cone_deg[-1] == pytest.approx(th0 + thd * tt, abs=2.0)
        assert tr.cone_rate_deg_s[-1] == pytest.approx(thd, abs=0.03)
    sources = group_sources(long)
    assert len(sources) == 2
    three = next(src for src in sources if len(src.track_ids) == 3)
    assert len(three.harmonics) == 3  # 200:400 = 1:2, 200:300 = 2:3, 300:400 = 3:4
    # the lines drift by 1e-5 of their frequency per second: over ~320 s of mean track time, f0 ~ 100.3 Hz
    assert three.fundamental_hz == pytest.approx(100.0 * (1 + 1e-5 * 320), abs=0.3)


@pytest.mark.parametrize("f_low,f_high,expected", [(100.0, 200.2, (1, 2)), (200.0, 300.0, (2, 3)),
                                                   (123.0, 200.0, None), (150.0, 150.3, (1, 1))])
def test_harmonic_ratio(f_low, f_high, expected):
    assert harmonic_ratio(f_low, f_high, 6, 0.005) == expected
