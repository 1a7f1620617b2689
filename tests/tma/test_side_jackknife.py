"""The delete-a-block jackknife of the side decision and the final state (tma/sides.py :func:`side_jackknife`),
checked against replicates refitted independently (scipy's least squares) and the jackknife formula by hand."""

import numpy as np
import pytest

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.side_jackknife import side_jackknife, time_blocks
from sonartrack.tma.sides import mirror_bearings_rad, resolve_side

LN100 = float(np.log(100.0))


def record(seed=0, sigma_deg=0.3, step_s=5.0, x0=(-3000.0, 5000.0, 2.0, -1.0)):
    """Array (no tow) north at 3 m/s from the origin, turning 60 deg to starboard at 0.5 deg/s from 600 s, 1200 s;
    a CV target starting at ``x0`` (m, m/s); noisy cone angles. Returns (t, cone, heading, xy, true bearings)."""
    t = np.arange(0.0, 1200.0 + 1e-9, step_s)
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((600.0, 720.0, np.deg2rad(0.5)),)).state(t)
    x0 = np.asarray(x0, float)
    tgt = x0[:2] + t[:, None] * x0[2:]
    b = bearing_rad(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])
    rel = wrap_angle(b - heading)
    noise = np.deg2rad(sigma_deg) * np.random.default_rng(seed).standard_normal(len(t))
    return t, np.clip(np.abs(rel) + noise, 0.0, np.pi), heading, own, b


def test_time_blocks_by_hand():
    # 100 bearings a second apart, 10 blocks: cuts at 9.9, 19.8, ... -> the first bearing at or after each
    np.testing.assert_array_equal(time_blocks(np.arange(100.0), 10), np.arange(0, 101, 10))
    # 0..59 s and 200..239 s: a block is 23.9 s; the cuts at 47.8 (11.2 s before the gap, within half a block)
    # and inside the gap move to the gap's end (index 60); 23.9 -> 24, 215.1 (15.1 s after it) -> 216 s = index 76
    t = np.concatenate([np.arange(60.0), np.arange(200.0, 240.0)])
    np.testing.assert_array_equal(time_blocks(t, 10), [0, 24, 60, 76, 100])


def _refit_by_hand(z, t, xy, x_start, keep):
    """The CV least-squares fit of the kept bearings by scipy (an independent optimiser), state at t[-1]."""
    from scipy.optimize import least_squares

    tk = t[keep]

    def res(p):
        x = p[0] + p[2] * (tk - t[-1]) - xy[keep, 0]
        y = p[1] + p[3] * (tk - t[-1]) - xy[keep, 1]
        return wrap_angle(z[keep] - np.arctan2(x, y))

    fit = least_squares(res, x_start, method="lm", xtol=1e-14, ftol=1e-14)
    return fit.x, 2.0 * fit.cost


def test_replicates_and_covariance_match_an_independent_refit():
    t, cone, heading, xy, _ = record(seed=1)
    side = resolve_side(t, cone, heading, xy, min_log_lr=LN100)
    assert side.side == "port"  # the target starts 31 deg to port of the northbound array and stays there
    stbd, port = mirror_bearings_rad(cone, heading)
    jk = side_jackknife(t, stbd, port, xy, side)
    edges = time_blocks(t, 10)
    g = len(edges) - 1
    states, log_lr = [], []
    for j in range(g):
        keep = np.ones(len(t), bool)
        keep[edges[j]:edges[j + 1]] = False
        _, js = _refit_by_hand(stbd, t, xy, side.starboard.state_at(t[-1])[0][0], keep)
        xp, jp = _refit_by_hand(port, t, xy, side.port.state_at(t[-1])[0][0], keep)
        states.append(xp)
        log_lr.append(-(js - jp) / (2.0 * side.sigma_bearing_rad**2))
    states = np.array(states)
    d = states - states.mean(axis=0)
    np.testing.assert_allclose(jk.state, states, rtol=0, atol=0.5)  # m, m/s: the two optimisers agree
    np.testing.assert_allclose(jk.covariance[:2, :2], (g - 1) / g * d[:, :2].T @ d[:, :2], rtol=2e-2)
    np.testing.assert_allclose(jk.log_lr, log_lr, rtol=1e-3)
    assert jk.stable("port", LN100) and not jk.stable("starboard", LN100)
    assert jk.foreign_block(np.deg2rad(3.0)) is None


def test_a_block_of_another_ships_bearings_is_found():
    # the last 200 s carry a ship 8 deg away: the rest of the record predicts them that far off
    t, cone, heading, xy, _ = record(seed=2)
    cone = np.where(t > 1000.0, np.clip(cone + np.deg2rad(8.0), 0.0, np.pi), cone)
    side = resolve_side(t, cone, heading, xy, min_log_lr=LN100)
    stbd, port = mirror_bearings_rad(cone, heading)
    jk = side_jackknife(t, stbd, port, xy, side)
    j = jk.foreign_block(np.deg2rad(3.0))
    assert j is not None and t[time_blocks(t, 10)[j]] > 950.0
    assert jk.foreign_block(np.deg2rad(30.0)) is None  # the width matters: 8 deg is within a 30 deg beam


@pytest.mark.parametrize("seed", range(3))
def test_a_side_resting_on_one_block_is_unstable(seed):
    # the turn is the only evidence for the side; leaving out the block of it leaves the side open
    t, cone, heading, xy, _ = record(seed=seed)
    keep = (t < 560.0) | ((t >= 600.0) & (t < 700.0))  # legs before the turn and the turn itself, nothing after
    t, cone, heading, xy = t[keep], cone[keep], heading[keep], xy[keep]
    side = resolve_side(t, cone, heading, xy, min_log_lr=LN100)
    stbd, port = mirror_bearings_rad(cone, heading)
    jk = side_jackknife(t, stbd, port, xy, side)
    turn_block = int(np.searchsorted(time_blocks(t, 10), int(np.searchsorted(t, 650.0)), side="right")) - 1
    assert abs(jk.log_lr[turn_block]) < abs(side.log_likelihood_ratio) / 3
