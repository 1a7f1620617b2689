"""A target that turns stays on one track: the active chain's IMM-IPDA (ContactTracker with P4's two CV modes and the
coordinated-turn modes of ActiveSettings.target_turn_rates_deg_s) on contacts of a target turning 60, 120 and 180 deg
at 0.3-1 deg/s, and on a straight one (no false track, its error no worse than with P4's CV modes alone).

Contacts from a generator written here from the geometry (not the scene simulator): a fixed monostatic receiver at
the origin with its array along north; the target's exact arc (speed v, turn rate w: x += v/w (cos h0 - cos h), y +=
v/w (sin h - sin h0)); a contact per ping with probability 0.8, range sd 50 m and bearing sd 0.9 deg, and its mirror
about the array's axis; 40 clutter echoes a ping (each a mirror pair) over 11.5 x 18 km.

Measured on seeds 0-9 and 9 turns (60, 120, 180 deg at 0.3, 0.6, 1 deg/s): P4's CV modes alone (diagonal 0.99) lag
up to 715 m behind a 180 deg turn at 1 deg/s (median of the runs' largest errors 653 m) and lose the target in 1-3
of the 9 runs confirmed before the turn; with the turn modes the largest error in any held turn is 406 m and only
seed 8 is lost (3 pings missed as its turn begins, 7 of 16 in it: every mode set tried loses it). Seed 9's target
is not confirmed before the turn with either (confirmation, not the turn)."""


import numpy as np
import pytest

from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.run import ContactTracker
from sonartrack.systems.active.settings import ActiveSettings

PING_S, SPEED_MPS, TURN_AT_S, DURATION_S = 30.0, 4.1, 900.0, 1800.0


def arc(turn_deg: float, rate_deg_s: float, t) -> np.ndarray:
    """Positions (n, 2) of a target on 330 deg from (6000, 3000) m turning ``turn_deg`` from TURN_AT_S."""
    h0, out = np.deg2rad(330.0), []
    w = np.deg2rad(rate_deg_s) * np.sign(turn_deg) if turn_deg else 0.0
    span = abs(turn_deg) / rate_deg_s if turn_deg else 0.0
    for tk in np.atleast_1d(t):
        p = np.array([6000.0, 3000.0]) + SPEED_MPS * min(tk, TURN_AT_S) * np.array([np.sin(h0), np.cos(h0)])
        b = float(np.clip(tk - TURN_AT_S, 0.0, span))
        h1 = h0 + w * b
        if b > 0:
            p = p + SPEED_MPS / w * np.array([np.cos(h0) - np.cos(h1), np.sin(h1) - np.sin(h0)])
        p = p + SPEED_MPS * max(tk - TURN_AT_S - span, 0.0) * np.array([np.sin(h1), np.cos(h1)])
        out.append(p)
    return np.array(out)


def cov(xy) -> np.ndarray:
    r = np.hypot(*xy)
    u = xy / r
    n = np.array([-u[1], u[0]])
    return 50.0**2 * np.outer(u, u) + (r * np.deg2rad(0.9)) ** 2 * np.outer(n, n)


def track(turn_deg: float, rate_deg_s: float, seed: int, turns: bool = True):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, DURATION_S, PING_S)
    X = arc(turn_deg, rate_deg_s, t)
    g = ActiveGeometry(np.array([-100.0, DURATION_S + 100.0]), np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))
    s = ActiveSettings()
    if turns:
        trk = ContactTracker(s.tracker_settings(), g, None, 1.0, None, 0.99, turns=s.turn_modes())
    else:  # the chain before the turn modes: P4's CV modes with P4's diagonal
        p4 = s.tracker_settings().model_copy(update={"transition_diagonal": 0.99})
        trk = ContactTracker(p4, g, None, 1.0, None, 0.99)
    det = 0
    for k, tk in enumerate(t):
        echoes = [X[k] + rng.multivariate_normal(np.zeros(2), cov(X[k]))] if rng.random() < 0.8 else []
        echoes += [np.array([rng.uniform(500, 12000), rng.uniform(-6000, 12000)]) for _ in range(rng.poisson(40))]
        xy = np.array([[sg * e[0], e[1]] for e in echoes for sg in (1, -1)]).reshape(-1, 2)
        m = len(xy)
        R = np.array([cov(p) for p in xy]).reshape(-1, 2, 2)
        trk.step(tk, Contacts(np.full(m, k), np.full(m, tk), np.repeat(np.arange(det, det + m // 2), 2),
                              np.tile(np.array([1, -1], np.int8), m // 2), xy, R, np.full(m, np.nan), np.hypot(*xy.T),
                              np.ones(m)))
        det += m // 2
    return t, X, trk.result().tracks


def holding(t, X, tr, gate=800.0):
    """Per ping the confirmed track nearest the target within ``gate`` (-1: none), and its error (m)."""
    held, err = np.full(len(t), -1), np.full(len(t), np.nan)
    for k, tk in enumerate(t):
        r = np.nonzero((tr.time_s == tk) & tr.confirmed)[0]
        d = np.hypot(*(tr.x[r, :2] - X[k]).T)
        if len(r) and d.min() < gate:
            held[k], err[k] = tr.track_id[r[np.argmin(d)]], d.min()
    return held, err


def held_through(turn_deg: float, rate_deg_s: float, seed: int) -> tuple[bool, float]:
    """(one confirmed track, confirmed before the turn, holds the target within 800 m at every ping from its
    confirmation to the end; its largest error (m) in the turn and the 3 pings after it)."""
    t, X, tr = track(turn_deg, rate_deg_s, seed)
    held, err = holding(t, X, tr)
    start = np.argmax(held >= 0)
    turning = (t >= TURN_AT_S) & (t <= TURN_AT_S + abs(turn_deg) / rate_deg_s + 3 * PING_S)
    one = bool(held[start] >= 0 and t[start] < TURN_AT_S and set(held[start:].tolist()) == {held[start]})
    return one, float(np.nanmax(err[turning])) if one else np.inf


SEEDS = range(10)
TURNS = [(60.0, 0.3), (-120.0, 0.6), (180.0, 1.0)]
#: seed 9: the target is not confirmed before its turn; seed 8: lost in its turn (module docstring)
NOT_CONFIRMED, LOST = {9}, {8}


@pytest.fixture(scope="module")
def held():
    return {case: [held_through(*case, seed) for seed in SEEDS] for case in TURNS}


def test_every_turn_held_within_500_m(held):
    ok = [s for s in SEEDS if s not in NOT_CONFIRMED | LOST]
    assert all(held[case][s][0] and held[case][s][1] < 500.0 for case in TURNS for s in ok), held


@pytest.mark.xfail(strict=True, reason="seed 8: 3 pings missed as the turn begins and 7 of 16 in it; the track coasts "
                                       "straight and its contacts leave every mode's gate (any mode set tried)")
def test_a_turn_begun_in_missed_pings_is_held(held):
    assert all(held[case][8][0] for case in TURNS), [held[case][8] for case in TURNS]


def test_a_straight_target_costs_nothing():
    t, X, tr = track(0.0, 1.0, seed=3)
    held, err = holding(t, X, tr)
    start = np.argmax(held >= 0)
    assert (held[start:] >= 0).all()
    # every confirmed track sits on the target or its mirror (the straight array cannot tell them apart)
    mirror = X * np.array([-1.0, 1.0])
    for tid in np.unique(tr.track_id[tr.confirmed]):
        rows = np.nonzero((tr.track_id == tid) & tr.confirmed)[0]
        k = np.searchsorted(t, tr.time_s[rows])
        d = np.minimum(np.hypot(*(tr.x[rows, :2] - X[k]).T), np.hypot(*(tr.x[rows, :2] - mirror[k]).T))
        assert np.median(d) < 300.0, tid
    # the error is below a single contact's cross-range sd (~125 m at 8 km): the track averages contacts
    rms = np.sqrt(np.nanmean(err[start + 5:] ** 2))
    assert rms < 125.0
    # and no worse than with P4's CV modes alone on the same contacts (within 10 %)
    t, X, tr = track(0.0, 1.0, seed=3, turns=False)
    held, err = holding(t, X, tr)
    assert rms < 1.1 * np.sqrt(np.nanmean(err[np.argmax(held >= 0) + 5:] ** 2))
