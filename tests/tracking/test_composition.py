"""The composable tracker: the paper trackers are configurations of the same parts, and the parts swap."""

import numpy as np
import pytest

from sonartrack.association.gating import gate_threshold
from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.association.pda import pda_update
from sonartrack.core.errors import InputError
from sonartrack.filters.kalman import kf_predict
from sonartrack.models.motion import cv_process_noise, cv_transition
from sonartrack.tracking.associators import JPDA, PDA
from sonartrack.tracking.configurations import bearing_tracker, bearing_tracks, position_tracker
from sonartrack.tracking.initiators import OnePointInitiator
from sonartrack.tracking.measurements import PositionMeasurements
from sonartrack.tracking.motion import ImmConstantVelocity
from sonartrack.tracking.multi_target import MultiTargetTracker
from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings


def test_both_paper_trackers_are_the_same_class_of_parts():
    pos = position_tracker(PositionTrackerSettings(q=[1e-4, 0.05]))
    brg = bearing_tracker(BearingTrackerSettings(), amplitude_aided=True)
    assert type(pos) is type(brg) is MultiTargetTracker
    assert isinstance(pos.associator, PDA) and isinstance(brg.associator, JPDA)
    assert (pos.motion.n_modes, pos.motion.state_dim) == (2, 4) and (brg.motion.n_modes, brg.motion.state_dim) == (1, 2)
    a = pos.step(0.0, [[100.0, 200.0]], np.eye(2) * 400.0)
    b = brg.step(0.0, [60.0, 120.0], amplitude=[20_000.0, 3_000.0])  # the weak peak starts no track
    assert a.x.shape == (1, 4) and b.x.shape == (1, 2) and b.x[0, 0] == 60.0


def _two_bearing_tracks(associator):
    """Two tracks 4 deg apart at rest, one peak between them (and nothing else)."""
    init = bearing_tracks([88.0, 92.0], 0.0, 1.0, 20_000.0, 2_500.0, time_s=0.0)
    trk = bearing_tracker(BearingTrackerSettings(), amplitude_aided=False, initial=init, time_s=0.0,
                          associator=associator)
    return trk.step(1.0, [90.0], amplitude=[20_000.0]).x[:, 0]


def test_swapping_pda_for_jpda_shares_a_measurement_instead_of_both_tracks_taking_it():
    # PDA lets each track take the peak on its own (its weights for the one peak sum to more than 1 over the
    # two tracks), so both are pulled to it; JPDA's joint events give the peak to at most one track at a time
    pda, jpda = _two_bearing_tracks(PDA()), _two_bearing_tracks(JPDA())
    pull_pda, pull_jpda = np.abs(pda - [88.0, 92.0]), np.abs(jpda - [88.0, 92.0])
    assert np.all(pull_jpda < pull_pda) and np.all(pull_jpda > 0)
    assert np.allclose(pda, 180.0 - pda[::-1]) and np.allclose(jpda, 180.0 - jpda[::-1])  # symmetric setup
    assert jpda[1] - jpda[0] > pda[1] - pda[0]  # JPDA keeps them further apart: less coalescence


def test_jpda_needs_one_mode_and_no_existence():
    with pytest.raises(InputError, match="single motion mode"):
        MultiTargetTracker(ImmConstantVelocity((1e-4, 0.05), transition=np.full((2, 2), 0.5)),
                           PositionMeasurements(0.8, 0.99, 1e-6), JPDA())
    with pytest.raises(InputError, match="existence"):
        position_tracker(PositionTrackerSettings(q=[1e-4]), associator=JPDA())


def test_position_tracks_with_jpda_by_hand_composition():
    # the position parts with JPDA (one mode, no existence): two tracks and one contact between them
    def run(associator):
        trk = MultiTargetTracker(ImmConstantVelocity((0.01,)), PositionMeasurements(0.9, 0.99, 1e-6), associator,
                                 initiator=OnePointInitiator(1.0, 0.5, 100))
        trk.step(0.0, [[0.0, 0.0], [60.0, 0.0]], np.eye(2) * 100.0)
        return trk.step(1.0, [[30.0, 0.0]], np.eye(2) * 100.0).x[:2, 0]

    pda, jpda = run(PDA()), run(JPDA())
    assert pda[0] > jpda[0] > 0.0 and pda[1] < jpda[1] < 60.0


def test_single_mode_tracker_equals_a_plain_ipda_filter_written_out():
    """The composed tracker with one mode against KF predict + single-track PDA + IPDA existence, by hand."""
    s = PositionTrackerSettings(q=[0.5], clutter_density_per_m2=2e-5)
    rng = np.random.default_rng(7)
    R = np.array([[400.0, 60.0], [60.0, 250.0]])
    truth = np.array([[1000.0 + 20.0 * k, 500.0 - 10.0 * k] for k in range(25)])
    scans = []
    for k, p in enumerate(truth):
        z = [p + rng.multivariate_normal([0, 0], R)] if k == 0 or rng.random() < 0.85 else []
        z += list(p + rng.uniform(-150.0, 150.0, (rng.poisson(3), 2)))  # clutter in and around the gate
        scans.append((2.0 * k, np.array(z).reshape(-1, 2)))
    trk = position_tracker(s)
    gamma = gate_threshold(s.gate_probability, 2)
    x = P = e = None
    for k, (t, z) in enumerate(scans):
        snap = trk.step(t, z, np.broadcast_to(R, (len(z), 2, 2)))
        if k == 0:
            x, P, e = np.r_[z[0], 0.0, 0.0], np.diag([R[0, 0], R[1, 1], 25.0, 25.0]), s.initial_existence
            P[:2, :2] = R
        else:
            F, Q = cv_transition(2.0), cv_process_noise(2.0, s.q[0])
            xp, Pp = kf_predict(x, P, F, Q)
            x, P, beta0, _ = pda_update(xp, Pp, z, R, pd=s.pd, pg=s.gate_probability, gamma=gamma,
                                        clutter_density=s.clutter_density_per_m2)
            lam = (1.0 - s.pd * s.gate_probability) / beta0  # beta0 = (1 - P_D P_G) / Lambda
            e = existence_update(existence_predict(e, s.p_survive, s.p_birth), lam)
        i = int(np.nonzero(snap.track_id == 1)[0][0])
        np.testing.assert_allclose(snap.x[i], x, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(snap.P[i], P, rtol=1e-12, atol=1e-9)
        assert snap.existence[i] == pytest.approx(e, rel=1e-12)
    assert snap.confirmed[i] and e > 0.9  # the hand-written filter followed a real, confirmed track
