"""The tonal pass (systems/passive/tonal_pass.py): the live tracks of each window, and float32 windows (a float32
or PCM file's samples, transformed in single precision) giving the lines of the same windows in double."""

from __future__ import annotations

import numpy as np

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.tonal import TonalSettings
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.tonal_pass import live_cones, measure_tonals

FS = 2000.0
N_EL = 16
ARRAY = LineArray(N_EL, 2.5, 1500.0)


def _track(track_id: int, t_s, cone_deg) -> TrackMeasurements:
    t = np.asarray(t_s, dtype=float)
    c = np.broadcast_to(np.asarray(cone_deg, dtype=float), t.shape).copy()
    return TrackMeasurements(track_id, t, c, np.ones(t.size), t, c)


def test_live_cones_by_hand():
    """Window k = floor(t / window): track 0 at 0.5, 1.2, 1.7, 5.0 s (the last outside 4 windows), track 1 at
    -0.5 (outside), 1.0 and 3.9 s; per window the tracks in their order and each track's scans in time order."""
    a = _track(10, [0.5, 1.2, 1.7, 5.0], [10.0, 11.0, 12.0, 13.0])
    b = _track(20, [-0.5, 1.0, 3.9], [50.0, 51.0, 52.0])
    live = live_cones([a, b], 1.0, 4)
    assert [ids.tolist() for ids, _ in live] == [[0], [0, 0, 1], [], [1]]
    assert [c.tolist() for _, c in live] == [[10.0], [11.0, 12.0, 51.0], [], [52.0]]
    assert live[2][0].dtype == np.int64 and live[2][1].dtype == np.float64
    assert live_cones([], 1.0, 2)[1][0].size == 0


def _blocks(dtype, n_windows: int, rng):
    """Two plane-wave tones (150.3 Hz from 60 deg, 310.7 Hz from 120 deg) in white noise, one window a second."""
    s_n = ((N_EL - 1) / 2.0 - np.arange(N_EL)) * ARRAY.spacing_m
    out = []
    for k in range(n_windows):
        t = k + np.arange(int(FS)) / FS
        x = rng.standard_normal((N_EL, t.size)) * 3.0
        for f0, cone in ((150.3, 60.0), (310.7, 120.0)):
            tau = -s_n * np.cos(np.deg2rad(cone)) / ARRAY.sound_speed_mps
            x += np.cos(2.0 * np.pi * f0 * (t[None, :] - tau[:, None]))
        out.append(x.astype(dtype))
    return out


def test_float32_windows_give_the_lines_of_double_windows():
    """The same samples (exact in float32) as float32 and float64 windows: each track's line, and its frequency in
    every window, agree to 1e-3 Hz, the same windows seen; and each track gets its own tone."""
    rng = np.random.default_rng(8)
    blocks32 = _blocks(np.float32, 30, rng)
    tracks = [_track(1, np.arange(30) + 0.5, 60.0), _track(2, np.arange(5, 30) + 0.5, 120.0)]
    s = TonalSettings(band_hz=[50.0, 800.0])
    single = measure_tonals(iter(blocks32), FS, ARRAY, tracks, s, 30)
    double = measure_tonals((b.astype(np.float64) for b in blocks32), FS, ARRAY, tracks, s, 30)
    for one, two, f0 in zip(single, double, (150.3, 310.7), strict=True):
        assert one is not None and two is not None
        assert abs(one.line_hz - f0) < 0.1
        assert abs(one.line_hz - two.line_hz) < 1e-3
        np.testing.assert_array_equal(np.isnan(one.frequency_hz), np.isnan(two.frequency_hz))
        assert np.nanmax(np.abs(one.frequency_hz - two.frequency_hz)) < 1e-3
    assert single[1].time_s[0] == 5.5
