"""The chain's own small parts: a track's raw peaks, joining duplicate tracks, leaving out shared beams,
the correlation inflation of the ML covariance, and settings that keep the chain's defaults."""

import numpy as np
import pytest

from sonartrack.passive.measurements import TrackMeasurements, drop_unresolved, merge_duplicates, nearest_peaks
from sonartrack.passive.settings import PassiveSettings, passive_tracker_settings
from sonartrack.passive.targets import correlation_inflation


def _track(tid, t, cone):
    t, cone = np.asarray(t, float), np.asarray(cone, float)
    return TrackMeasurements(tid, t, cone, np.ones_like(t), t, cone)


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


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_correlation_inflation_matches_ar1(rho):
    rng = np.random.default_rng(3)
    e = np.zeros(20000)
    w = rng.normal(size=e.size)
    for k in range(1, e.size):
        e[k] = rho * e[k - 1] + w[k]
    assert correlation_inflation(e) == pytest.approx((1 + rho) / (1 - rho), rel=0.05)


def test_partial_tracker_table_keeps_the_chains_defaults(tmp_path):
    from sonartrack.cli._settings import resolve

    cfg = tmp_path / "p.toml"
    cfg.write_text("[tracker]\nq = 0.05\n")
    s = resolve(PassiveSettings, cfg)
    ours = passive_tracker_settings()
    assert s.tracker.q == 0.05
    # not the class's own (paper P0) defaults: the chain's
    assert s.tracker.amplitude_threshold == ours.amplitude_threshold != 5000.0
