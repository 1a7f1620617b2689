"""The passive chain's track start and confirmation (systems/passive/settings.py, the tracker's M-of-N and the
initiation level) on hand-built peak sequences: when a ship's track starts and is confirmed, when a tentative
track is dropped, and that noise-like peaks at the measured false-peak rate confirm nothing."""

import numpy as np
import pytest

from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.tracking.run import track_peaks


def _tracker(**changes):
    s = PassiveSettings(spacing_m=1.5, elements=16)
    if changes:
        s = s.model_copy(update={"tracker": s.tracker.model_copy(update=changes)})
    return s.stages(4000.0).tracker


def _scans(hits, z, cone0=60.0, rate=0.02):
    """One peak per window where ``hits`` (z statistic ``z``) on a ship moving at ``rate`` deg/s, none elsewhere."""
    k = np.nonzero(np.asarray(hits, bool))[0]
    return k.astype(float), cone0 + rate * k, np.full(len(k), float(z))


def _first_confirmed(tracks):
    c = np.asarray(tracks.confirmed, bool)
    return float(np.asarray(tracks.time_s)[c][0]) if c.any() else None


def test_a_ship_is_confirmed_on_its_mth_consecutive_peak():
    s = _tracker()
    t, b, a = _scans(np.ones(30), 8.0)
    tr = track_peaks(t, b, a, s)
    # the initiating peak is the first hit: M consecutive peaks confirm at window M - 1
    assert _first_confirmed(tr) == s.confirm_m - 1
    assert set(np.asarray(tr.track_id).tolist()) == {1}


def test_one_miss_in_the_first_n_windows_delays_confirmation_by_one_window():
    s = _tracker()
    hits = np.ones(30)
    hits[2] = 0
    tr = track_peaks(*_scans(hits, 8.0), s)
    assert _first_confirmed(tr) == s.confirm_m


def test_a_tentative_track_with_too_many_misses_is_dropped():
    s = _tracker()
    misses = s.confirm_n - s.confirm_m + 1  # one more than M-of-N allows in the first N windows
    hits = np.ones(s.confirm_n)
    hits[1:1 + misses] = 0
    tr = track_peaks(*_scans(hits, 8.0), s)
    assert _first_confirmed(tr) is None
    # dropped at its N-th window: no row of it after that
    assert np.asarray(tr.time_s).max() == s.confirm_n - 1


@pytest.mark.parametrize("z", [4.8, 5.8])
def test_a_weak_ship_below_the_old_start_level_gets_a_track(z):
    # peaks between the new start level and the old one (6): started and confirmed now, never before
    s = _tracker()
    assert s.init_amplitude <= z < 6.0
    tr = track_peaks(*_scans(np.ones(40), z), s)
    assert _first_confirmed(tr) == s.confirm_m - 1
    old = track_peaks(*_scans(np.ones(40), z), _tracker(init_amplitude=6.0))
    assert len(old) == 0


def test_noise_like_peaks_confirm_nothing():
    # an hour of false peaks at the front end's measured noise-only rate (0.043 a window at z >= 4 over 0..180 deg,
    # excess over the threshold exponential at 2 per unit z; settings doc of clutter_density_per_deg), ten times
    # as many: no confirmed track
    s = _tracker()
    rng = np.random.default_rng(7)
    n = rng.poisson(10 * 0.043, 3600)
    t = np.repeat(np.arange(3600.0), n)
    b = rng.uniform(0.0, 180.0, len(t))
    a = s.amplitude_threshold + rng.exponential(1.0 / 2.0, len(t))
    tr = track_peaks(t, b, a, s)
    assert (a >= s.init_amplitude).sum() > 10  # the test does start tentative tracks
    assert not np.asarray(tr.confirmed, bool).any()
