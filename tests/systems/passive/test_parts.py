"""The chain's own small parts: a track's raw peaks, joining duplicate tracks, leaving out shared beams, and the
one settings tree (each shared quantity declared once and handed to every stage; the chain's tracker defaults;
the old layout refused with the key's new place)."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.systems.passive.measurements import (
    TrackMeasurements,
    confirmed_segments,
    nearest_peaks,
    track_measurements,
)
from sonartrack.systems.passive.settings import PASSIVE_TRACKER_DEFAULTS, PassiveSettings
from sonartrack.systems.passive.shared_scans import drop_unresolved, merge_duplicates
from sonartrack.tracking.run import BearingTracks
from sonartrack.tracking.settings import BearingTrackerSettings


def _track(tid, t, cone):
    t, cone = np.asarray(t, float), np.asarray(cone, float)
    return TrackMeasurements(tid, t, cone, np.ones_like(t), t, cone)


def _tracks(rows):
    """BearingTracks from (time, id, cone, confirmed) rows."""
    t, tid, cone, conf = (np.array(c) for c in zip(*rows, strict=True))
    zeros = np.zeros(len(t))
    return BearingTracks(time_s=t.astype(float), track_id=tid.astype(int), bearing_deg=cone.astype(float),
                         bearing_rate_deg_s=zeros, bearing_std_deg=zeros, strength=zeros, confirmed=conf.astype(bool))


def test_confirmed_segments_start_at_the_first_confirmed_scan():
    tracks = _tracks([(0.5, 2, 40.0, False), (0.5, 1, 70.0, False), (1.5, 2, 41.0, True), (1.5, 1, 71.0, False),
                      (2.5, 2, 42.0, False), (2.5, 3, 10.0, True), (3.5, 2, 43.0, True)])
    seg = confirmed_segments(tracks)
    assert list(seg) == [2, 3]  # track 1 never confirmed; ids in increasing order
    assert seg[2][0].tolist() == [1.5, 2.5, 3.5] and seg[2][1].tolist() == [41.0, 42.0, 43.0]
    assert seg[3][0].tolist() == [2.5] and seg[3][1].tolist() == [10.0]


def test_track_measurements_take_the_nearest_peak_of_each_scan():
    from sonartrack.acoustics.xcorr_bearing import PeakRecord

    tracks = _tracks([(0.5, 1, 40.0, True), (1.5, 1, 41.0, True), (2.5, 1, 42.0, True)])
    peaks = PeakRecord(np.array([0.5, 0.5, 1.5, 2.5]), np.array([39.5, 60.0, 45.0, 42.2]), np.array([5, 6, 7, 8.0]))
    (m,) = track_measurements(tracks, peaks, max_offset_deg=2.0)
    assert m.track_id == 1 and m.time_s.tolist() == [0.5, 2.5] and m.cone_deg.tolist() == [39.5, 42.2]
    assert m.amplitude.tolist() == [5.0, 8.0] and m.track_time_s.tolist() == [0.5, 1.5, 2.5]


def test_nearest_peak_within_the_offset():
    peak_t = np.array([0.5, 0.5, 1.5, 2.5])
    peak_cone = np.array([40.0, 44.0, 60.0, 41.0])
    idx = nearest_peaks(np.array([0.5, 1.5, 2.5]), np.array([43.0, 45.0, 40.5]), peak_t, peak_cone, 2.0)
    assert idx.tolist() == [1, -1, 3]  # 44 is nearer 43 than 40; 60 is 15 deg off; 41 within 0.5


def test_duplicate_tracks_join_and_distinct_ones_do_not():
    a = _track(1, np.arange(0, 20), np.full(20, 50.0))
    b = _track(2, np.arange(15, 40), np.full(25, 50.5))  # same peaks from t = 15: a second track on one target
    c = _track(3, np.arange(15, 40), np.full(25, 70.0))
    out = merge_duplicates([a, b, c], max_offset_deg=2.0)
    assert [m.track_id for m in out] == [1, 3]
    assert out[0].time_s.tolist() == list(range(40)) and out[0].cone_deg[15] == 50.0  # a's value where both


def test_scans_sharing_a_beam_are_left_out():
    a = _track(1, np.arange(10), np.linspace(40, 58, 10))
    b = _track(2, np.arange(10), np.full(10, 60.0))
    out = drop_unresolved([a, b], min_separation_deg=5.0)
    assert out[0].time_s.tolist() == list(range(8)) and out[1].time_s.tolist() == list(range(8))


def test_root_quantities_reach_every_stage():
    s = PassiveSettings(spacing_m=2.5, window_s=2.0, threshold=5.5, sound_speed_mps=1480.0)
    st = s.stages(4000.0, channels=16)
    assert st.front_end.window_s == st.tonal.window_s == 2.0
    assert st.front_end.threshold == st.tracker.amplitude_threshold == 5.5
    assert st.array.sound_speed_mps == st.sequential.sound_speed_mps == 1480.0
    assert (st.array.elements, st.array.spacing_m) == (16, 2.5) and st.settings.elements == 16
    # the automatic band: the ships' 50-1000 Hz (c / (N d) = 37 Hz lies below it); min separation = one beamwidth
    # at its centre 525 Hz
    assert (st.band.low_hz, st.band.high_hz) == (50.0, 1000.0)
    assert st.min_separation_deg == pytest.approx(np.rad2deg(0.89 * (1480.0 / 525.0) / (16 * 2.5)), rel=1e-12)
    # on 8 x 0.5 m the aperture is one wavelength at c / (N d) = 370 Hz: the band starts there
    st8 = PassiveSettings(spacing_m=0.5, sound_speed_mps=1480.0).stages(4000.0, channels=8)
    assert (st8.band.low_hz, st8.band.high_hz) == (370.0, 1000.0)


def test_two_channels_are_two_sensors():
    st = PassiveSettings(spacing_m=20.0).stages(4000.0, channels=2)
    assert st.front_end.method == "split-array" and st.front_end.allow_grating_lobes
    assert (st.band.low_hz, st.band.high_hz) == (50.0, 1000.0) and st.settings.front_end.method == "split-array"


@pytest.mark.parametrize(("channels", "words"), [(8, "8 channels but --elements is 16"), (1, "at least two")])
def test_recording_must_match_the_array(channels, words):
    with pytest.raises(InputError, match=words):
        PassiveSettings(spacing_m=2.5, elements=None if channels == 1 else 16).stages(4000.0, channels=channels)


def test_a_changed_window_moves_the_tonal_times_with_it():
    """The tonal pass stamps window k at its centre (k + 0.5) window_s, with the root's window: at 2 s windows the
    times are 1, 3, 5, ... s, not the 1 s windows' 0.5, 1.5, ... (a tonal window of its own would mislabel them)."""
    from sonartrack.systems.passive.tonal_pass import measure_tonals

    fs, f0, cone = 1000.0, 120.0, 70.0
    for window_s in (1.0, 2.0):
        st = PassiveSettings(spacing_m=2.5, window_s=window_s).stages(fs, channels=8)
        n = int(window_s * fs)
        s_n = ((8 - 1) / 2.0 - np.arange(8)) * 2.5
        tau = -s_n * np.cos(np.deg2rad(cone)) / 1500.0
        rng = np.random.default_rng(4)

        def blocks(n=n, tau=tau, rng=rng):
            for k in range(12):
                t = k * n / fs + np.arange(n) / fs
                yield np.cos(2 * np.pi * f0 * (t[None, :] - tau[:, None])) + 0.3 * rng.standard_normal((8, n))

        t_track = (np.arange(12) + 0.5) * window_s
        m = TrackMeasurements(1, t_track, np.full(12, cone), np.ones(12), t_track, np.full(12, cone))
        (tonal,) = measure_tonals(blocks(), fs, st.array, [m], st.tonal, 12)
        assert tonal is not None and tonal.line_hz == pytest.approx(f0, abs=0.05)
        np.testing.assert_array_equal(tonal.time_s, (np.arange(12) + 0.5) * window_s)


def test_partial_tracker_table_keeps_the_chains_defaults(tmp_path):
    from sonartrack.cli._settings import resolve

    cfg = tmp_path / "p.toml"
    cfg.write_text("spacing_m = 2.5\nthreshold = 3.5\n[tracker]\nq = 0.05\n")
    s = resolve(PassiveSettings, cfg)
    tracker = s.stages(4000.0, channels=16).tracker
    assert isinstance(tracker, BearingTrackerSettings) and tracker.q == 0.05
    # not the class's own (paper P0) defaults: the chain's, and the root's threshold
    assert tracker.gate_deg == PASSIVE_TRACKER_DEFAULTS["gate_deg"][0] != BearingTrackerSettings().gate_deg
    assert tracker.amplitude_threshold == 3.5


def test_the_chains_tracker_values_carry_their_own_docs():
    ours, p0 = type(PassiveSettings().tracker), BearingTrackerSettings
    for name, (value, doc) in PASSIVE_TRACKER_DEFAULTS.items():
        assert ours.model_fields[name].default == value != p0.model_fields[name].default
        assert ours.model_fields[name].description == doc != p0.model_fields[name].description
        assert "P0's" not in doc  # the docs of P0's values stay with P0's defaults
    assert "amplitude_threshold" not in ours.model_fields


@pytest.mark.parametrize(("toml", "words"), [
    ("[front_end]\nwindow_s = 2.0\n", r"window_s under \[front_end\].*move it out of \[front_end\]"),
    ("[tonal]\nsound_speed_mps = 1480.0\n", r"move it out of \[tonal\] as sound_speed_mps"),
    ("[tracker]\namplitude_threshold = 3.0\n", r"move it out of \[tracker\] as threshold"),
    ("min_line_snr_db = 3.0\n", "now tma_min_tonal_snr_db"),
])
def test_the_old_layout_is_refused_with_the_new_place(tmp_path, toml, words):
    from sonartrack.cli._settings import resolve

    cfg = tmp_path / "old.toml"
    cfg.write_text(toml)
    with pytest.raises(InputError, match=words):
        resolve(PassiveSettings, cfg)


def test_no_tracks_no_segments():
    empty = np.zeros(0)
    tracks = BearingTracks(time_s=empty, track_id=empty.astype(int), bearing_deg=empty, bearing_rate_deg_s=empty,
                           bearing_std_deg=empty, strength=empty, confirmed=empty.astype(bool))
    assert confirmed_segments(tracks) == {}
