"""IPDA existence (association/ipda.py) and the tracker's IMM-IPDA update: hand-worked cases and properties."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.association.gating import gate_probability, gate_threshold
from sonartrack.association.ipda import existence_predict, existence_update
from sonartrack.association.pda import pda_update_batch


def test_markov_prediction_hand_worked():
    assert existence_predict(0.5, 0.98, 0.0) == 0.49
    assert existence_predict(0.2, 0.9, 0.1) == 0.9 * 0.2 + 0.1 * 0.8


def test_no_measurement_in_gate_follows_the_closed_form():
    pd, pg = 0.8, 0.99
    x = np.zeros((3, 1, 4))
    P = np.broadcast_to(np.eye(4) * 100.0, (3, 1, 4, 4))
    res = pda_update_batch(x, P, np.array([[1e5, 1e5]]), np.eye(2), pd=pd, pg=pg, gamma=gate_threshold(pg),
                           clutter_density=1e-6)
    lam = np.exp(res.log_lambda[:, 0])
    np.testing.assert_allclose(lam, 1 - pd * pg)
    for p in (0.05, 0.5, 0.97):
        expected = (1 - pd * pg) * p / (1 - pd * pg * p)
        got = existence_update(p, lam[0])
        assert got == np.float64(expected) or abs(got - expected) < 1e-15


def test_a_measurement_at_the_prediction_raises_existence_when_likelihood_beats_clutter():
    x = np.zeros((1, 1, 4))
    P = np.eye(4)[None, None] * 100.0
    R = np.eye(2) * 100.0
    res = pda_update_batch(x, P, np.zeros((1, 2)), R, pd=0.9, pg=0.99, gamma=9.21, clutter_density=1e-5)
    # p = N(0; 0, 200 I) = 1 / (2 pi 200) = 7.96e-4 >> rho: Lambda = 1 - 0.891 + 0.9 * 79.6
    np.testing.assert_allclose(np.exp(res.log_lambda[0, 0]), 1 - 0.891 + 0.9 / (2 * np.pi * 200) / 1e-5)
    assert existence_update(0.3, np.exp(res.log_lambda[0, 0])) > 0.3


def test_gate_threshold_and_probability_are_inverse():
    for pg in (0.9, 0.95, 0.99, 0.999):
        assert abs(gate_probability(gate_threshold(pg)) - pg) < 1e-12
    assert abs(gate_threshold(0.99, 3) - 11.3449) < 1e-3  # chi-square(3) table value


@settings(max_examples=300, deadline=None)
@given(p=st.floats(0, 1), lam=st.floats(0, 1e6))
def test_existence_stays_a_probability(p, lam):
    e = existence_update(p, lam)
    assert 0.0 <= e <= 1.0


@settings(max_examples=200, deadline=None)
@given(p=st.floats(0.001, 0.999), lam=st.floats(0.001, 1e3))
def test_existence_moves_with_the_likelihood_ratio(p, lam):
    e = existence_update(p, lam)
    if lam > 1:
        assert e >= p - 1e-12
    elif lam < 1:
        assert e <= p + 1e-12
