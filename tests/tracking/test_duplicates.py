"""Duplicate tracks: the track-to-track test against hand-worked cases, and the merger inside the IMM-IPDA."""

import numpy as np
import pytest

from sonartrack.association.gating import gate_threshold
from sonartrack.tracking.configurations import position_tracker
from sonartrack.tracking.deleters import ExistenceDeleter
from sonartrack.tracking.duplicates import DuplicateMerger, duplicate_mask
from sonartrack.tracking.settings import PositionTrackerSettings

GAMMA = gate_threshold(0.99, 4)


def _pair(delta, p_var=(100.0, 100.0, 1.0, 1.0), confirmed=(True, False), born=(0.0, 10.0), existence=(0.9, 0.9)):
    x = np.array([[0.0, 0.0, 2.0, 0.0], np.asarray(delta, float) + [0.0, 0.0, 2.0, 0.0]])
    P = np.stack([np.diag(p_var)] * 2)
    return duplicate_mask(x, P, np.array(confirmed), np.array(born), np.array(existence), GAMMA)


def test_the_statistic_is_the_chi_square_of_the_difference():
    # P_i + P_j = diag(200, 200, 2, 2): a 20 m offset in x gives d^2 = 400 / 200 = 2 (same), and an offset whose
    # d^2 is just above / below gamma (13.28 for 4 dof at 0.99) decides it
    assert _pair([20.0, 0, 0, 0]).tolist() == [True, False]
    below, above = np.sqrt(200.0 * GAMMA * 0.99), np.sqrt(200.0 * GAMMA * 1.01)
    assert _pair([below, 0, 0, 0]).tolist() == [True, False]
    assert _pair([above, 0, 0, 0]).tolist() == [True, True]
    # two crossing targets at one point: velocities 4 m/s apart against 2 (m/s)^2 give d^2 = 8 ... with 6 m/s: 18
    assert _pair([0, 0, 0, 4.0]).tolist() == [True, False]
    assert _pair([0, 0, 0, 6.0]).tolist() == [True, True]


def test_the_kept_track_is_confirmed_then_older_then_more_likely():
    assert _pair([5.0, 0, 0, 0], confirmed=(False, True)).tolist() == [False, True]
    assert _pair([5.0, 0, 0, 0], confirmed=(True, True), born=(50.0, 10.0)).tolist() == [False, True]
    assert _pair([5.0, 0, 0, 0], confirmed=(True, True), born=(10.0, 10.0), existence=(0.5, 0.99)).tolist() == \
        [False, True]
    # two tentative tracks are not tested
    assert _pair([5.0, 0, 0, 0], confirmed=(False, False)).tolist() == [True, True]


def test_a_chain_of_duplicates_keeps_one():
    x = np.array([[0.0, 0, 1, 0], [10.0, 0, 1, 0], [20.0, 0, 1, 0], [5000.0, 0, 1, 0]])
    P = np.stack([np.diag([100.0, 100.0, 1.0, 1.0])] * 4)
    keep = duplicate_mask(x, P, np.ones(4, bool), np.arange(4.0), np.full(4, 0.9), GAMMA)
    assert keep.tolist() == [True, False, False, True]


def _scans(n=30, T=30.0, sigma=40.0, seed=1):
    rng = np.random.default_rng(seed)
    truth = np.array([[1000.0 + 3.0 * T * k, 8000.0 - 2.0 * T * k] for k in range(n)])
    R = np.eye(2) * sigma**2
    # the first scan holds the target's contact and a stray one 60 m off: both start tracks (no track yet
    # gates them), and from then on both tracks see the same contacts
    first = np.array([truth[0], truth[0] + [60.0, 0.0]])
    return truth, [(0.0, first, np.stack([R, R]))] + [(T * k, truth[k][None] + rng.normal(0, sigma, (1, 2)), R[None])
                                                      for k in range(1, n)]


@pytest.mark.parametrize("merge", [False, True])
def test_coalesced_tracks_are_merged_in_the_tracker(merge):
    s = PositionTrackerSettings(q=[1e-4, 0.05], clutter_density_per_m2=1e-7)
    trk = position_tracker(s)
    if merge:
        trk.deleter = DuplicateMerger(trk.deleter, GAMMA)
    truth, scans = _scans()
    for t, z, R in scans:
        snap = trk.step(t, z, R)
    confirmed = snap.track_id[snap.confirmed]
    assert len(confirmed) == (1 if merge else 2)
    x = snap.x[snap.confirmed]
    assert np.all(np.hypot(*(x[:, :2] - truth[-1]).T) < 150)


def test_the_merger_passes_the_inner_deleters_counters():
    inner = ExistenceDeleter(0.9, 0.01)
    assert DuplicateMerger(inner, GAMMA).new_track_attrs(3) == inner.new_track_attrs(3)
