"""A told-apart pair merged after all (tracking/duplicates.py ``reunite_scans``): only after k scans in a row on one
velocity and one shared contact; hand-worked d^2 against the gates."""

import numpy as np

from sonartrack.association.gating import gate_threshold
from sonartrack.tracking.deleters import ExistenceDeleter
from sonartrack.tracking.duplicates import DuplicateMerger
from sonartrack.tracking.tracks import TrackArrays

GAMMA4, GAMMA2 = gate_threshold(0.99, 4), gate_threshold(0.99, 2)  # 13.28, 9.21
HIT = np.ones(2, bool)


def _two(xa, xb, sd_m=30.0):
    x = np.array([xa, xb], float)[:, None]
    P = np.tile(np.diag([sd_m**2, sd_m**2, 0.25, 0.25]), (2, 1, 1, 1))
    return TrackArrays(x, P, np.ones((2, 1)), np.full(2, 0.99), np.ones(2, bool), np.array([1, 2], np.int64),
                       np.array([0.0, 60.0]), P[:, 0], {})


def _merger(k=3):
    m = DuplicateMerger(ExistenceDeleter(0.9, 0.01), GAMMA4, keep_apart=True, reunite_scans=k, velocity_gamma=GAMMA2)
    m.manage(_two([0, 0, 3, 0], [2000, 0, 3, 0]), HIT)  # told apart: 2 km apart while both hold their targets
    assert (1, 2) in m.apart
    return m


def _scan(m, xa, xb, contacts_xy, sd_m=30.0):
    z = np.asarray(contacts_xy, float).reshape(-1, 2)
    m.contacts[:] = [z, np.tile(np.eye(2) * 40.0**2, (len(z), 1, 1))]
    return m.manage(_two(xa, xb, sd_m), HIT).track_id.tolist()


def test_a_told_apart_pair_on_one_contact_and_velocity_is_merged_after_k_scans():
    m = _merger(3)
    for k in range(3):  # both on top of one contact, same velocity: kept on scans 1-2, merged on the 3rd
        ids = _scan(m, [300 + 90 * k, 0, 3, 0], [310 + 90 * k, 5, 3, 0], [[305 + 90 * k, 0]])
        assert ids == ([1, 2] if k < 2 else [1])
    assert m.merged == {2: 1}


def test_a_crossing_pair_with_different_velocities_stays_apart():
    # equal positions, velocities 2.3 m/s apart against var 0.25 + 0.25: d^2 = 2.3^2 / 0.5 = 10.6, inside the whole
    # state's gate (13.28, so the test alone would merge them) but outside the velocity gate (9.21)
    d2 = 2.3**2 / 0.5
    assert GAMMA2 < d2 < GAMMA4
    m = _merger(1)
    for k in range(5):
        assert _scan(m, [300 + 90 * k, 0, 3, 0], [300 + 90 * k, 0, 3, 2.3], [[300 + 90 * k, 0]]) == [1, 2]
    assert m.merged == {}


def test_two_tracks_on_their_own_contacts_stay_apart():
    # 150 m apart (sd 30 each: position d^2 = 150^2 / 1800 = 12.5 < 13.28, the pair passes the test), each on its
    # own contact: contact 0 is 0 m from track 1 and 150 m from track 2 (d^2 = 150^2 / (900 + 1600) = 9.0 < 9.21,
    # in its gate) but track 2's nearest is contact 1
    d2 = 150.0**2 / 1800
    assert d2 < GAMMA4
    m = _merger(1)
    for k in range(4):
        x0 = 300 + 90 * k
        assert _scan(m, [x0, 0, 3, 0], [x0 + 150, 0, 3, 0], [[x0, 0], [x0 + 150, 0]]) == [1, 2]
    assert m.merged == {}


def test_the_streak_must_be_unbroken():
    m = _merger(2)
    assert _scan(m, [300, 0, 3, 0], [305, 0, 3, 0], [[302, 0]]) == [1, 2]
    assert _scan(m, [390, 0, 3, 0], [395, 0, 3, 0], np.zeros((0, 2))) == [1, 2]  # no contact: streak broken
    assert _scan(m, [480, 0, 3, 0], [485, 0, 3, 0], [[482, 0]]) == [1, 2]
    assert _scan(m, [570, 0, 3, 0], [575, 0, 3, 0], [[572, 0]]) == [1]


def test_zero_scans_keeps_told_apart_pairs_apart():
    m = _merger(0)
    for k in range(4):
        assert _scan(m, [300 + 90 * k, 0, 3, 0], [305 + 90 * k, 0, 3, 0], [[302 + 90 * k, 0]]) == [1, 2]
