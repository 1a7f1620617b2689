"""The IMM-MGEKF responds to a target's turn: mode columns in the solution table, the manoeuvre modes' probability
rising after a turn, and NEES before, during and after it (Monte Carlo over a numpy truth, not the project's
simulator).

Scenario (bearings-only, the paper's bank of tma/settings.py ImmSettings): ownship at 5 m/s on legs of 900 s
(course changes of 90 deg at 1 deg/s), target 10 km away at 3..7 m/s, a 90 deg turn at 1 deg/s at t = 2100 s,
bearings every 10 s with a 1 deg sd. Measured over 40 runs (see ImmSettings' docstring for the other cases).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from sonartrack.models.relative_motion import observer_inputs
from sonartrack.tma.imm_mgekf import ImmBfModel, mode_probabilities, run_imm_bf, transition_matrix
from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.sequential_bf import initial_estimate, solve_sequential
from sonartrack.tma.settings import ImmSettings
from sonartrack.tma.solution_table import solution_columns

T_TURN_S, DURATION_S, DT_S, SIGMA_B = 2100.0, 4200.0, 10.0, np.deg2rad(1.0)


def _paths(rng, n_runs: int, turn_deg: float, speed_change_mps: float = 0.0):
    """Ownship and target [x, y, vx, vy] (n_runs, n_t, 4) at 1 s, by integrating course and speed; at T_TURN_S the
    target turns by ``turn_deg`` at 1 deg/s and changes speed by ``speed_change_mps`` at 0.05 m/s^2."""
    t = np.arange(0.0, DURATION_S + 1.0)
    base = rng.uniform(0, 360, n_runs)
    own_course = base[:, None] + np.select([t < 900, t < 1800, t < 2700, t < 3600], [0, 60, -30, 60], -30)[None]
    own = _integrate(np.zeros((n_runs, 2)), _slew(own_course), np.full(n_runs, 5.0))
    b0 = np.deg2rad(base + rng.uniform(-60, 60, n_runs))
    sign = rng.choice([-1.0, 1.0], n_runs)
    course0 = rng.uniform(0, 360, n_runs)
    turned = np.clip(t - T_TURN_S, 0.0, abs(turn_deg))  # 1 deg/s
    tgt_course = course0[:, None] + sign[:, None] * turned[None]
    speed = rng.uniform(3, 7, n_runs)[:, None] + np.sign(speed_change_mps) * np.clip(
        0.05 * (t - T_TURN_S), 0.0, abs(speed_change_mps))[None]
    tgt = _integrate(10e3 * np.stack([np.sin(b0), np.cos(b0)], -1), tgt_course, speed)
    return t, own, tgt


def _slew(course_deg):
    """Course steps turned at 1 deg/s (the ownship's legs)."""
    out = course_deg.astype(float).copy()
    for k in range(1, out.shape[1]):
        out[:, k] = out[:, k - 1] + np.clip((course_deg[:, k] - out[:, k - 1] + 180) % 360 - 180, -1.0, 1.0)
    return out


def _integrate(p0, course_deg, speed):
    """Positions and velocities from the initial positions p0 (n_runs, 2), course (deg) and speed (m/s) per second:
    speed (n_runs,) constant or (n_runs, n_t)."""
    c = np.deg2rad(course_deg)
    v = np.broadcast_to(np.reshape(speed, (len(speed), -1)), c.shape)[..., None] * np.stack([np.sin(c), np.cos(c)], -1)
    p = p0[:, None, :] + np.concatenate([np.zeros_like(v[:, :1]), np.cumsum(v[:, :-1], axis=1)], axis=1)
    return np.concatenate([p, v], -1)


def _monte_carlo(n_runs: int, turn_deg: float, seed: int = 1, model: ImmBfModel | None = None):
    """Manoeuvre probabilities and 4-state NEES of one IMM-MGEKF (default: the default bank) over ``n_runs`` runs."""
    rng = np.random.default_rng(seed)
    t1, own, tgt = _paths(rng, n_runs, turn_deg)
    t = np.arange(0.0, DURATION_S + 1e-9, DT_S)
    k = np.searchsorted(t1, t)
    imm = ImmSettings()
    if model is None:
        model = ImmBfModel(qs=np.asarray(imm.q_values), Pi=transition_matrix(len(imm.q_values),
                                                                             imm.transition_diagonal),
                           sigma_bearing_rad=SIGMA_B, q_f0=imm.q_f0)
    man, nees = [], []
    for i in range(n_runs):
        o, rel = own[i, k], tgt[i, k] - own[i, k]
        zb = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
        x0, P0 = initial_estimate(float(zb[0]), None, o[0, 2:], range_m=10e3, sigma_range_m=3e3,
                                  sigma_bearing_rad=SIGMA_B, target_velocity_mps=tgt[i, 0, 2:],
                                  sigma_target_velocity_mps=3.0)
        x0 = np.r_[rel[0], 0.0] + np.linalg.cholesky(P0) @ rng.standard_normal(5)  # truth - x0 ~ N(0, P0)
        x, P, mu, failed = run_imm_bf(t, zb, None, observer_inputs(t, o[:, :2], o[:, 2:]), x0, P0, model)
        assert failed < 0
        modes = mode_probabilities(model.qs, mu, manoeuvre_q_min=imm.manoeuvre_q_min, level=imm.manoeuvre_level)
        man.append(modes.manoeuvre_prob())
        e = rel - x[:, :4]
        nees.append(np.einsum("ni,ni->n", e, np.linalg.solve(P[:, :4, :4], e[..., None])[..., 0]))
    return t, np.array(man), np.array(nees), imm.manoeuvre_level


@pytest.fixture(scope="module")
def turn90():
    return _monte_carlo(40, 90.0)


def test_manoeuvre_probability_rises_within_300_s_of_a_90_deg_turn(turn90):
    t, man, _, level = turn90
    after = t >= T_TURN_S
    first = [t[after][np.argmax(m[after] > level)] - T_TURN_S if np.any(m[after] > level) else np.inf for m in man]
    assert np.mean(np.asarray(first) <= 300.0) >= 0.8  # measured: 0.9, median 130 s


def test_no_manoeuvre_flagged_on_the_straight_leg(turn90):
    t, man, _, level = turn90
    straight = (t > 600) & (t < T_TURN_S)  # after the first ownship turn, before the target's
    assert np.mean(man[:, straight] > level) <= 0.05  # measured: 0.0


def test_nees_before_during_after_the_turn(turn90):
    """NEES (4 states) per run and time against chi2(4): the share of samples above its 99 % point (1 % if consistent).

    Measured (40 runs): 1.8 % / 13.5 % / 2.5 % before / in the first 600 s of / after the turn; the median NEES is
    0.95 / 2.15 / 0.97 against chi2(4)'s 3.36. So the filter is NOT inside its interval: conservative on the
    straight legs (the mixture with the manoeuvre modes widens P), overconfident in one sample in seven during a
    90 deg turn. This test guards those levels (a regression that doubles them fails); it does not claim consistency.
    """
    t, _, nees, _ = turn90
    above = chi2.ppf(0.99, 4)
    for (lo_s, hi_s), most in [((600, T_TURN_S), 0.05), ((T_TURN_S, T_TURN_S + 600), 0.25),
                               ((T_TURN_S + 600, DURATION_S + 1), 0.05)]:
        window = (t >= lo_s) & (t < hi_s)
        assert np.mean(nees[:, window] > above) <= most, (lo_s, hi_s)
        assert np.median(nees[:, window]) < chi2.ppf(0.5, 4), (lo_s, hi_s)  # never overconfident on the whole


def test_imm_solution_table_has_mode_and_manoeuvre_columns_appended():
    rng = np.random.default_rng(7)
    t1, own, tgt = _paths(rng, 1, 90.0)
    t = np.arange(0.0, DURATION_S + 1e-9, DT_S)
    k = np.searchsorted(t1, t)
    rel = tgt[0, k] - own[0, k]
    bearing = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
    record = BearingRecord(time_s=t, bearing_rad=bearing)
    ownship = OwnshipTrack(time_s=t1, x_m=own[0, :, 0], y_m=own[0, :, 1])
    imm_sol, _ = solve_sequential(record, ownship, "imm-mgekf", sigma_bearing_rad=SIGMA_B)
    cols = list(solution_columns(imm_sol, ownship))
    plain = list(solution_columns(solve_sequential(record, ownship, "mgekf", sigma_bearing_rad=SIGMA_B)[0], ownship))
    assert plain[-1] == "undetermined_reason"
    assert cols == plain + ["mode_prob_cv", "mode_prob_q0.001", "mode_prob_q0.1", "manoeuvre_prob", "manoeuvre"]
    table = solution_columns(imm_sol, ownship)
    probs = np.stack([table["mode_prob_cv"], table["mode_prob_q0.001"], table["mode_prob_q0.1"]], -1)
    assert np.allclose(probs.sum(axis=1), 1.0)
    assert table["manoeuvre"].dtype == bool
    np.testing.assert_array_equal(table["manoeuvre"], table["mode_prob_q0.1"] > 0.5)
