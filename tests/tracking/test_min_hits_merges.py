"""Confirmation held back until a track has had enough scans in its gate (tracking/deleters.py MinHits), and the
duplicate merger's record of which track each deleted duplicate followed (tracking/duplicates.py), on hand-made
tracks."""

import numpy as np

from sonartrack.association.gating import gate_threshold
from sonartrack.tracking.deleters import ExistenceDeleter, MinHits
from sonartrack.tracking.duplicates import DuplicateMerger, duplicate_of
from sonartrack.tracking.tracks import TrackArrays

GAMMA = gate_threshold(0.99, 4)


def _tracks(existence, confirmed, hits, x=None, born=None):
    n = len(existence)
    x = np.zeros((n, 4)) if x is None else np.asarray(x, float)
    P = np.stack([np.diag([100.0, 100.0, 1.0, 1.0])] * n)
    return TrackArrays(x[:, None], P[:, None], np.ones((n, 1)), np.asarray(existence, float), np.asarray(confirmed),
                       np.arange(n, dtype=np.int64), np.zeros(n) if born is None else np.asarray(born, float), P,
                       {"hits": np.asarray(hits)})


def test_a_track_is_confirmed_only_with_min_hits_scans_in_its_gate():
    part = MinHits(ExistenceDeleter(0.9, 0.01), 3)
    # both above the existence threshold; track 0 has had 1 + 1 scans with a contact, track 1 2 + 1
    T = part.manage(_tracks([0.95, 0.95], [False, False], [1, 2]), np.array([True, True]))
    assert T.confirmed.tolist() == [False, True] and T.attrs["hits"].tolist() == [2, 3]
    # a miss does not count; the next hit does
    T = part.manage(T, np.array([False, False]))
    assert T.confirmed.tolist() == [False, True] and T.attrs["hits"].tolist() == [2, 3]
    T = part.manage(T, np.array([True, False]))
    assert T.confirmed.tolist() == [True, True]
    # with min_hits 1 the existence alone decides (the wrapper changes nothing)
    T1 = MinHits(ExistenceDeleter(0.9, 0.01), 1).manage(_tracks([0.95, 0.5], [False, False], [1, 1]),
                                                        np.array([True, True]))
    assert T1.confirmed.tolist() == [True, False]
    # a confirmed track stays confirmed, a track below the termination threshold is deleted
    T2 = part.manage(_tracks([0.95, 0.005], [True, False], [1, 5]), np.array([False, True]))
    assert T2.confirmed.tolist() == [True] and T2.track_id.tolist() == [0]
    # new tracks' counter: the initiating scan counts one
    assert part.new_track_attrs(2)["hits"].tolist() == [1, 1]


def test_duplicate_of_names_the_kept_track_and_the_merger_records_confirmed_duplicates():
    # tracks 0 (confirmed, oldest) and 1 (confirmed, younger) 20 m apart: d^2 = 400 / 200 = 2 < 13.3, a duplicate;
    # track 2 far off; track 3 tentative, 10 m from track 0
    x = np.array([[0.0, 0, 2, 0], [20.0, 0, 2, 0], [5000.0, 0, 2, 0], [0.0, 10, 2, 0]])
    P = np.stack([np.diag([100.0, 100.0, 1.0, 1.0])] * 4)
    into = duplicate_of(x, P, np.array([True, True, False, False]), np.array([0.0, 60, 0, 90]), np.full(4, 0.9), GAMMA)
    assert into.tolist() == [-1, 0, -1, 0]
    merger = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA)
    T = merger.manage(_tracks([0.99, 0.99, 0.5, 0.5], [True, True, False, False], [1] * 4, x, [0.0, 60, 0, 90]),
                      np.ones(4, bool))
    assert T.track_id.tolist() == [0, 2]
    assert merger.merged == {1: 0}  # the tentative duplicate was never listed: not recorded


def test_two_confirmed_tracks_are_merged_only_after_confirmed_scans_in_a_row():
    # tracks 0 and 1 confirmed, 20 m apart (d^2 = 2, duplicates); track 2 tentative 10 m from track 0; with
    # confirmed_scans 3 the tentative duplicate goes at once, the confirmed one after its third scan in a row
    x = np.array([[0.0, 0, 2, 0], [20.0, 0, 2, 0], [0.0, 10, 2, 0]])
    far = x.copy()
    far[1, 0] = 500.0  # d^2 = 2500 > 13.3: not a duplicate on this scan
    merger = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA, confirmed_scans=3)

    def scan(xs, n=2):
        return merger.manage(_tracks([0.99] * n, [True] * n, [1] * n, xs[:n], [0.0, 60.0, 90.0][:n]),
                             np.ones(n, bool)).track_id.tolist()

    assert merger.manage(_tracks([0.99, 0.99, 0.5], [True, True, False], [1] * 3, x, [0.0, 60, 90]),
                         np.ones(3, bool)).track_id.tolist() == [0, 1]  # scan 1 of the pair; the tentative one gone
    assert scan(x) == [0, 1]  # scan 2
    assert scan(far) == [0, 1]  # apart: the count starts again
    assert scan(x) == [0, 1] and scan(x) == [0, 1]
    assert merger.merged == {}
    assert scan(x) == [0]  # the third scan in a row
    assert merger.merged == {1: 0}


def _two(x, existence, sd_m):
    """Tracks 0 (born 0 s) and 1 (born 60 s), both confirmed, at states ``x`` with position sds ``sd_m``."""
    P = np.stack([np.diag([s**2, s**2, 1.0, 1.0]) for s in sd_m])
    return TrackArrays(np.asarray(x, float)[:, None], P[:, None], np.ones((2, 1)), np.asarray(existence, float),
                       np.array([True, True]), np.arange(2, dtype=np.int64), np.array([0.0, 60.0]), P,
                       {"hits": np.ones(2)})


def test_a_coasting_track_that_reaches_another_target_is_dropped_as_lost_not_merged():
    # two targets 3 km apart, velocities 3 m/s apart (d^2 >> 13.3 with 50 m sds: not duplicates); then the older
    # track 0 coasts (existence 0.3, sd 900 m) and lies 1.2 km from track 1: d^2 = 1.2e6 / (8.1e5 + 2.5e3) + 9 / 2 + 0
    # ~ 6 < 13.3, the test passes. The coaster ranks below the held track (track 1 kept) and, the pair having failed
    # the test when track 0 last held its target, is not recorded as the same target.
    merger = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA)
    apart = [[0.0, 0, -3, 0], [3000.0, 0, 0, -3]]
    assert merger.manage(_two(apart, [1.0, 1.0], [50, 50]), np.ones(2, bool)).track_id.tolist() == [0, 1]
    met = [[1800.0, 0, -3, 0], [3000.0, 0, 0, -3]]
    assert merger.manage(_two(met, [0.3, 1.0], [900, 50]), np.ones(2, bool)).track_id.tolist() == [1]
    assert merger.merged == {}
    # the same pair when track 0 had held its target 20 m from track 1 (one target, two tracks; confirmed_scans 2
    # so that the pair outlives that scan): recorded, track 1 (holding the target) kept
    merger = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA, confirmed_scans=2)
    near = [[3020.0, 0, 0, -3], [3000.0, 0, 0, -3]]
    assert merger.manage(_two(near, [0.95, 0.95], [50, 50]), np.ones(2, bool)).track_id.tolist() == [0, 1]
    assert merger.manage(_two(met, [0.3, 1.0], [900, 50]), np.ones(2, bool)).track_id.tolist() == [1]
    assert merger.merged == {0: 1}
    # without the coasting rule (lost_existence None: P4's merger) the older coaster is kept and the merge recorded
    merger = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA, lost_existence=None)
    merger.manage(_two(apart, [1.0, 1.0], [50, 50]), np.ones(2, bool))
    assert merger.manage(_two(met, [0.3, 1.0], [900, 50]), np.ones(2, bool)).track_id.tolist() == [0]
    assert merger.merged == {1: 0}
