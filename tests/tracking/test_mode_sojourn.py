"""The IMM mode chain from mean sojourn times (tracking/motion.py ``sojourn_transition``, ``ImmConstantVelocity``
``sojourn_s``; configurations.py ``position_motion`` with ``TurnModes.turn_deg``), checked against hand-worked
matrices, the exponential sojourn's closed forms and a simulated continuous-time chain."""

import numpy as np
import pytest

from sonartrack.tracking.configurations import position_motion
from sonartrack.tracking.motion import ImmConstantVelocity, TurnModes, sojourn_transition
from sonartrack.tracking.settings import PositionTrackerSettings


def test_a_mode_with_a_sojourn_keeps_its_exit_proportions():
    Pi = np.array([[0.9, 0.06, 0.04], [0.1, 0.8, 0.1], [0.25, 0.25, 0.5]])
    out = sojourn_transition(Pi, (None, 60.0, None), 30.0)
    stay = np.exp(-0.5)  # 30 s of a 60 s mean sojourn
    np.testing.assert_allclose(out[1], [(1 - stay) / 2, stay, (1 - stay) / 2])
    np.testing.assert_array_equal(out[[0, 2]], Pi[[0, 2]])  # rows without a sojourn as given
    np.testing.assert_allclose(out.sum(1), 1.0)
    # a mode whose row has no exit stays whatever its sojourn (nowhere to go)
    np.testing.assert_array_equal(sojourn_transition(np.eye(2), (10.0, 10.0), 30.0), np.eye(2))


def test_the_stay_is_the_exponential_sojourn():
    Pi = np.array([[0.5, 0.5], [0.5, 0.5]])
    tau, dt = 120.0, 30.0
    p = sojourn_transition(Pi, (tau, tau), dt)[0, 0]
    # staying over two intervals of dt is staying over 2 dt (memoryless), and the mean run of scans is ~tau / dt
    assert p**2 == pytest.approx(sojourn_transition(Pi, (tau, tau), 2 * dt)[0, 0])
    assert 1.0 / (1.0 - p) == pytest.approx(tau / dt + 0.5, rel=0.02)  # 1 / (1 - e^-x) = 1/x + 1/2 + O(x)
    # against a simulated continuous-time mode: exponential durations of mean tau, sampled every dt
    rng = np.random.default_rng(4)
    ends = np.cumsum(rng.exponential(tau, 20_000))
    k = np.searchsorted(ends, np.arange(0.0, ends[-1] - dt, dt))
    stayed = np.mean(k[1:] == k[:-1])
    assert stayed == pytest.approx(p, abs=0.01)


def test_turn_modes_leave_for_straight_running_or_their_own_sense():
    s = PositionTrackerSettings(transition_diagonal=0.98)
    m = position_motion(s, TurnModes((0.5, 1.0), 1e-3, turn_deg=90.0))  # modes: cv, cv, +0.5, -0.5, +1, -1
    np.testing.assert_allclose(m.sojourn_s[2:], [180.0, 180.0, 90.0, 90.0])
    assert m.sojourn_s[:2] == (None, None)
    Pi = m.transition_at(30.0)
    np.testing.assert_allclose(Pi.sum(1), 1.0)
    np.testing.assert_allclose(np.diag(Pi)[2:], np.exp(-30.0 / np.array([180.0, 180.0, 90.0, 90.0])))
    np.testing.assert_allclose(Pi[:2], m.transition[:2])  # the CV rows as P4's rule gives them
    np.testing.assert_allclose(Pi[0, 1:], 0.02 / 5)
    leave = 1.0 - np.exp(-30.0 / 180.0)
    np.testing.assert_allclose(Pi[2], [leave / 3, leave / 3, 1.0 - leave, 0.0, leave / 3, 0.0])  # +0.5: cv, cv, +1
    np.testing.assert_allclose(Pi[5, [0, 1, 3]], (1.0 - np.exp(-30.0 / 90.0)) / 3)  # -1: cv, cv, -0.5
    assert Pi[5, 2] == Pi[5, 4] == 0.0
    # over a longer interval a turn is more likely over
    assert m.transition_at(60.0)[4, 4] < Pi[4, 4]


def test_without_a_turn_size_the_chain_is_the_fixed_one():
    s = PositionTrackerSettings(transition_diagonal=0.98)
    m = position_motion(s, TurnModes((0.5, 1.0), 1e-3))
    assert m.sojourn_s is None
    for dt in (None, 30.0, 90.0):
        np.testing.assert_array_equal(m.transition_at(dt), m.transition)
    np.testing.assert_allclose(np.diag(m.transition), 0.98)


def test_interaction_uses_the_chain_over_the_interval():
    rng = np.random.default_rng(0)
    m = ImmConstantVelocity((1e-4, 1e-3), transition=np.array([[0.9, 0.1], [0.3, 0.7]]),
                            turn_rate_rad_s=(0.0, 0.01), sojourn_s=(None, 50.0))
    mu = rng.dirichlet([1.0, 1.0], size=4)
    x = rng.normal(size=(4, 2, 4))
    P = np.broadcast_to(np.eye(4), (4, 2, 4, 4)).copy()
    c, _, _ = m.interact(mu, x, P, 30.0)
    np.testing.assert_allclose(c, mu @ np.array([[0.9, 0.1], [1 - np.exp(-0.6), np.exp(-0.6)]]))
    c_fixed, _, _ = m.interact(mu, x, P)
    np.testing.assert_allclose(c_fixed, mu @ m.transition)


def test_bad_sojourns_are_refused():
    with pytest.raises(ValueError, match="mean course change"):
        TurnModes((1.0,), 1e-3, turn_deg=0.0)
    with pytest.raises(ValueError, match="sojourn"):
        ImmConstantVelocity((1e-4, 1e-3), transition=np.full((2, 2), 0.5), sojourn_s=(None, -5.0))
    with pytest.raises(ValueError, match="sojourn"):
        ImmConstantVelocity((1e-4, 1e-3), transition=np.full((2, 2), 0.5), sojourn_s=(10.0,))
