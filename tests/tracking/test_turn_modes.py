"""Turn modes in the position tracker's IMM (tracking/motion.py, configurations.py ``position_motion``): P4's modes
unchanged without them; each turn mode predicts with its own coordinated-turn F and Q; on a noise-free turning
target the mode turning its way takes the probability, and on a straight leg a constant-velocity mode does."""

import numpy as np
import pytest

from sonartrack.filters.coordinated_turn import ct_process_noise, ct_transition
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.tracking.configurations import position_motion, position_tracker
from sonartrack.tracking.motion import ImmConstantVelocity, TurnModes
from sonartrack.tracking.settings import PositionTrackerSettings


def test_without_turns_the_modes_are_p4s():
    s = PositionTrackerSettings()
    for turns in (None, TurnModes(())):
        m = position_motion(s, turns)
        assert m.q == (1e-4, 0.05) and m.turn_rate_rad_s is None
        np.testing.assert_array_equal(m.transition, s.transition_matrix())


def test_turn_modes_and_their_chain():
    m = position_motion(PositionTrackerSettings(transition_diagonal=0.98), TurnModes((0.5, 1.0), 1e-3))
    np.testing.assert_allclose(np.rad2deg(m.turn_rate_rad_s), [0, 0, 0.5, -0.5, 1.0, -1.0])
    assert m.q == (1e-4, 0.05, 1e-3, 1e-3, 1e-3, 1e-3)
    np.testing.assert_allclose(m.transition.sum(1), 1.0)
    np.testing.assert_allclose(np.diag(m.transition), 0.98)
    np.testing.assert_allclose(m.transition[0, 1:], 0.02 / 5)


def test_each_mode_predicts_with_its_own_turn():
    rng = np.random.default_rng(0)
    w = (0.0, 0.02, -0.01)
    m = ImmConstantVelocity((1e-4, 1e-3, 0.05), transition=np.full((3, 3), 1 / 3), turn_rate_rad_s=w)
    x = rng.normal(size=(5, 3, 4))
    A = rng.normal(size=(5, 3, 4, 4))
    P = A @ A.swapaxes(-1, -2)
    xp, Pp = m.predict(x, P, 30.0)
    for r, (q, wr) in enumerate(zip(m.q, w, strict=True)):
        F = ct_transition(30.0, wr)
        np.testing.assert_allclose(xp[:, r], x[:, r] @ F.T)
        np.testing.assert_allclose(Pp[:, r], F @ P[:, r] @ F.T + ct_process_noise(30.0, q, wr))
    # all rates 0: exactly the constant-velocity path
    cv = ImmConstantVelocity((1e-4, 0.05), transition=np.eye(2))
    zero = ImmConstantVelocity((1e-4, 0.05), transition=np.eye(2), turn_rate_rad_s=(0.0, 0.0))
    for a, b in zip(cv.predict(x[:, :2], P[:, :2], 30.0), zero.predict(x[:, :2], P[:, :2], 30.0), strict=True):
        np.testing.assert_array_equal(a, b)


def test_bad_turn_modes_are_refused():
    with pytest.raises(ValueError, match="turn rates"):
        TurnModes((-1.0,))
    with pytest.raises(ValueError, match="one rate per mode"):
        ImmConstantVelocity((1e-4, 0.05), turn_rate_rad_s=(0.01,))
    with pytest.raises(ValueError):
        ActiveSettings(target_turn_rates_deg_s=[0.0])


def test_the_mode_turning_the_targets_way_takes_the_probability():
    # 4 m/s north for 20 pings, then a clockwise turn at 1 deg/s for 6 pings (180 deg), contacts every 30 s with
    # 30 m errors and no clutter
    s = PositionTrackerSettings(transition_diagonal=0.98, clutter_density_per_m2=1e-9)
    trk = position_tracker(s, turns=TurnModes((1.0,), 1e-3))
    rng = np.random.default_rng(1)
    v, w = 4.0, -np.deg2rad(1.0)  # clockwise: negative counter-clockwise rate
    x, mu = np.array([0.0, 0.0, 0.0, v]), []
    for k in range(26):
        trk.step(30.0 * k, (x[:2] + rng.normal(0.0, 30.0, 2))[None], np.diag([30.0**2, 30.0**2])[None])
        T = trk.tracks
        mu.append(T.mu[np.argmax(T.existence)].copy())
        x = (ct_transition(30.0, w) if k >= 19 else ct_transition(30.0, 0.0)) @ x
    mu = np.array(mu)
    assert mu[15:20, :2].sum(1).min() > 0.8  # straight: the CV modes
    assert mu[22:26, 3].min() > 0.5  # turning clockwise: the -1 deg/s mode
