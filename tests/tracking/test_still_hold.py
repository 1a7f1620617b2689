"""StillHold (tracking/deleters.py): a track that has just earned its confirmation while slow and on a recurring
world position waits; a fast one, one away from recurring contacts, and one confirmed before keep their flag; a hold,
once taken, lasts until the track moves."""

from dataclasses import replace

import numpy as np

from sonartrack.tracking.deleters import StillHold
from sonartrack.tracking.tracks import TrackArrays


class ConfirmAll:
    def new_track_attrs(self, k):
        return {}

    def manage(self, T, hit):
        return replace(T, confirmed=np.ones(len(T), bool))


def tracks(states, confirmed):
    n = len(states)
    x = np.asarray(states, float)[:, None, :]
    P = np.tile(np.diag([100.0**2, 100.0**2, 1.0, 1.0]), (n, 1, 1, 1))
    return TrackArrays(x, P, np.ones((n, 1)), np.full(n, 0.99), np.asarray(confirmed, bool), np.arange(n),
                       np.zeros(n), P[:, 0])


def test_only_a_new_slow_confirmation_on_a_recurring_contact_waits():
    hold = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21)
    hold.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    T = tracks([[10.0, 0.0, 0.2, 0.0],     # slow, on the contact: waits
                [10.0, 0.0, 3.0, 0.0],     # moving: confirmed
                [5000.0, 0.0, 0.1, 0.0],   # slow, far from any recurring contact: confirmed
                [-20.0, 0.0, 0.0, 0.1]],   # slow, on the contact, confirmed at an earlier scan: stays confirmed
               [False, False, False, True])
    assert hold.manage(T, np.ones(4, bool)).confirmed.tolist() == [False, True, True, True]


def test_no_recurring_contact_no_hold():
    hold = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21)
    assert hold.manage(tracks([[0.0, 0.0, 0.0, 0.0]], [False]), np.ones(1, bool)).confirmed.tolist() == [True]


def test_a_hold_taken_stays_until_the_track_moves():
    # a track held on a recurring position (a still point's mirror twin before the ownship's turn) is not confirmed
    # when the twin moves off it at the turn; it is once its own speed shows it moving
    hold = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21)
    hold.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    assert hold.manage(tracks([[10.0, 0.0, 0.1, 0.0]], [False]), np.ones(1, bool)).confirmed.tolist() == [False]
    hold.recurring(np.array([[3000.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])  # the twin has left
    assert hold.manage(tracks([[10.0, 0.0, 0.1, 0.0]], [False]), np.ones(1, bool)).confirmed.tolist() == [False]
    hold.recurring(np.zeros((0, 2)), np.zeros((0, 2, 2)))  # no recurring contact at all: still held
    assert hold.manage(tracks([[10.0, 0.0, 0.1, 0.0]], [False]), np.ones(1, bool)).confirmed.tolist() == [False]
    assert hold.manage(tracks([[10.0, 0.0, 2.0, 0.0]], [False]), np.ones(1, bool)).confirmed.tolist() == [True]


def test_a_hold_is_forgotten_with_its_track():
    hold = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21)
    hold.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    hold.manage(tracks([[10.0, 0.0, 0.1, 0.0]], [False]), np.ones(1, bool))
    assert hold.held.tolist() == [0]
    T = tracks([[5000.0, 0.0, 0.1, 0.0]], [False])  # another track (id 1), far from any recurring contact
    T = replace(T, track_id=np.array([1]))
    hold.recurring(np.zeros((0, 2)), np.zeros((0, 2, 2)))
    assert hold.manage(T, np.ones(1, bool)).confirmed.tolist() == [True]
    assert hold.held.tolist() == []


def _with_velocity_sd(T, sd_mps):
    P = T.P.copy()
    P[..., 2, 2] = P[..., 3, 3] = np.asarray(sd_mps, float).reshape(-1, 1) ** 2
    return replace(T, P=P)


def test_with_a_moving_test_an_uncertain_speed_does_not_show_a_track_moving():
    # gamma 4.61 (chi2_2 at 0.9): sqrt(4.61) = 2.147 velocity sd. A 2.3 m/s track with sd 1.5 m/s: 2.3 - 3.22 < 1,
    # held; with sd 0.5 m/s: 2.3 - 1.07 = 1.23 > 1, confirmed; at sd 0.7 m/s: 2.3 - 1.50 = 0.80, held
    states = [[10.0, 0.0, 2.3, 0.0]] * 3
    T = _with_velocity_sd(tracks(states, [False] * 3), [1.5, 0.5, 0.7])
    hold = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21, moving_gamma=4.61)
    hold.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    assert hold.manage(T, np.ones(3, bool)).confirmed.tolist() == [False, True, False]
    # the speed estimate alone (no moving test): all three shown moving
    plain = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21)
    plain.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    assert plain.manage(T, np.ones(3, bool)).confirmed.tolist() == [True, True, True]
    # the largest eigenvalue counts: sd 0.3 along x but 1.5 along y is uncertain
    P = T.P.copy()
    P[0, :, 2, 2], P[0, :, 3, 3] = 0.3**2, 1.5**2
    hold2 = StillHold(ConfirmAll(), slow_mps=1.0, gamma=9.21, moving_gamma=4.61)
    hold2.recurring(np.array([[0.0, 0.0]]), np.diag([50.0**2, 50.0**2])[None])
    assert not hold2.manage(replace(T, P=P), np.ones(3, bool)).confirmed[0]
