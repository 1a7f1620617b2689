"""No ghosts in the picture: a target tracked on both sides of the array is one target with two hypotheses until the
array's turn decides its side, then its mirror track is dropped (systems/active/targets.py, sides.py twins).

The contacts come from a generator written here from the geometry (not the scene simulator): a monostatic sonar on
a ship steaming north that turns 60 deg to port; each echo of a constant-velocity target gives its position and
its reflection about the ship's axis, each with a range / cross-range covariance (range sd 40 m, bearing sd 0.9
deg), plus a few uniform clutter echoes (each also a mirror pair)."""

from dataclasses import dataclass

import numpy as np
import pytest

from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.run import ContactTracker
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.active.targets import mirror_targets, track_hypotheses, truth_scores

PING_S = 30.0
SPEED_MPS = 2.5
TURN = (600.0, 720.0, -np.deg2rad(0.5))  # start, end (s), rate (rad/s): 60 deg to port


def ship(t):
    """Ship position (n, 2) and heading (n,) at times t: north, then the turn, then straight (exact arcs)."""
    t = np.atleast_1d(np.asarray(t, float))
    t0, t1, w = TURN
    a, b = np.minimum(t, t0), np.clip(t - t0, 0.0, t1 - t0)
    h = w * b
    x = SPEED_MPS / w * (1.0 - np.cos(h))
    y = SPEED_MPS * a + SPEED_MPS / w * np.sin(h)
    c = np.maximum(t - t1, 0.0)
    return np.stack([x + SPEED_MPS * c * np.sin(h), y + SPEED_MPS * c * np.cos(h)], -1), h


def target(t):
    """A CV target east of the ship: starboard before and after the turn."""
    t = np.atleast_1d(np.asarray(t, float))
    return np.stack([4000.0 + 3.0 * t, 6000.0 - 1.0 * t], -1)


def reflect(xy, rx, h):
    a = np.array([np.sin(h), np.cos(h)])
    d = xy - rx
    return rx + 2.0 * (d @ a) * a - d


def cov(xy, rx):
    d = xy - rx
    r = np.hypot(*d)
    u = d / r
    n = np.array([-u[1], u[0]])
    return 40.0**2 * np.outer(u, u) + (r * np.deg2rad(0.9)) ** 2 * np.outer(n, n)


@dataclass
class Run:
    tracks: object
    geometry: ActiveGeometry
    times: np.ndarray


def run(pings: int, seed: int = 1, pd: float = 0.9, clutter: float = 3.0) -> Run:
    rng = np.random.default_rng(seed)
    nav_t = np.arange(-60.0, PING_S * pings + 60.0, 10.0)
    rx, h = ship(nav_t)
    geometry = ActiveGeometry(nav_t, rx, rx, h)
    trk = ContactTracker(ActiveSettings().tracker_settings(), geometry, None, 1.0, side_turn_deg=20.0,
                         merge_probability=0.99)
    times = PING_S * np.arange(pings)
    det = 0
    for k, tk in enumerate(times):
        r, hk = ship(tk)[0][0], float(ship(tk)[1][0])
        echoes = [target(tk)[0]] if rng.random() < pd else []
        echoes += [r + rng.uniform(-12000, 12000, 2) for _ in range(rng.poisson(clutter))]
        xy, R, side, dets = [], [], [], []
        for e in echoes:
            z = e + rng.multivariate_normal(np.zeros(2), cov(e, r))
            for p, s in ((z, 1), (reflect(z, r, hk), -1)):
                xy.append(p)
                R.append(cov(p, r))
                side.append(s)
                dets.append(det)
            det += 1
        m = len(xy)
        xy = np.array(xy).reshape(-1, 2)
        trk.step(tk, Contacts(np.full(m, k), np.full(m, tk), np.array(dets, np.int64), np.array(side, np.int8), xy,
                              np.array(R).reshape(-1, 2, 2), np.full(m, np.nan), np.hypot(*(xy - r).T), np.ones(m)))
    return Run(trk.result(), geometry, times)


@pytest.fixture(scope="module")
def before_turn():
    return run(20)  # 0..570 s: the array has run straight


@pytest.fixture(scope="module")
def through_turn():
    return run(50)  # the turn at 600..720 s, then 17 min straight


def _confirmed_near(r, xy_of, gate=1000.0):
    """Ids of the confirmed tracks within ``gate`` of xy_of(t, rx, h) at some ping."""
    tr, out = r.tracks.tracks, set()
    for k in np.nonzero(tr.confirmed)[0]:
        rx, h = ship(tr.time_s[k])
        if np.hypot(*(tr.x[k, :2] - xy_of(tr.time_s[k], rx[0], float(h[0])))) < gate:
            out.add(int(tr.track_id[k]))
    return out


def test_a_mirror_pair_before_the_turn_is_one_undecided_target(before_turn):
    r = before_turn
    real = _confirmed_near(r, lambda t, rx, h: target(t)[0])
    ghost = _confirmed_near(r, lambda t, rx, h: reflect(target(t)[0], rx, h))
    assert len(real) == 1 and len(ghost) == 1  # both sides tracked and confirmed: the ghost the issue saw
    m = mirror_targets(r.tracks, r.geometry)
    assert len(m) == 1  # ... but one target
    assert m.decision[0] == "undecided" and m.side[0] == ""
    assert {int(m.track_id[0]), int(m.mirror_track_id[0])} == real | ghost
    # both positions in the one row: each its track's last estimate, on either side of the ship's axis
    last = r.times[-1]
    rx, h = ship(last)
    pos = {"starboard": target(last)[0], "port": reflect(target(last)[0], rx[0], float(h[0]))}
    assert np.hypot(*(m.xy[0] - pos[m.track_side[0]])) < 500.0
    other = "port" if m.track_side[0] == "starboard" else "starboard"
    assert np.hypot(*(m.mirror_xy[0] - pos[other])) < 500.0
    target_of, hyp = track_hypotheses(r.tracks, m, r.geometry)
    tr = r.tracks.tracks
    rows = np.isin(tr.track_id, list(real | ghost)) & tr.confirmed
    assert set(target_of[rows]) == {1} and set(hyp[rows]) == {"starboard", "port"}
    assert set(hyp[np.isin(tr.track_id, list(real))]) == {"starboard"}


def test_the_turn_decides_the_side_and_drops_the_mirror(through_turn):
    r = through_turn
    m = mirror_targets(r.tracks, r.geometry)
    real = _confirmed_near(r, lambda t, rx, h: target(t)[0])
    assert len(m) == 1 and m.decision[0] == "decided" and m.side[0] == "starboard"
    assert int(m.track_id[0]) in real and m.log_lr[0] > 0
    assert TURN[0] < m.resolved_s[0] <= r.times[-1]
    tr = r.tracks.tracks
    ghost = int(m.mirror_track_id[0])
    if ghost >= 0:  # the mirror is dropped: no row of it after the ping after the decision
        assert tr.time_s[tr.track_id == ghost].max() <= m.resolved_s[0] + PING_S
    target_of, hyp = track_hypotheses(r.tracks, m, r.geometry)
    late = (tr.time_s > m.resolved_s[0]) & tr.confirmed
    assert set(hyp[late]) == {"decided"} and set(target_of[late]) == {1}
    # against the truth: held after confirmation, and no false target (the ghost is a hypothesis, not a target)
    t = r.times
    truth = {"time_s": t, "target": np.full(len(t), "a"), "x_m": target(t)[:, 0], "y_m": target(t)[:, 1]}
    scores = truth_scores(r.tracks, m, truth, r.geometry)
    assert scores["false_targets"] == 0 and scores["held"]["a"] > 0.7
