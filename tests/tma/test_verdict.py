"""The verdict of sequential TMA solutions: diverged, unobservable, inconsistent innovations, each on a case built
for it (and its counterpart that must stay determined); the combined NIS against FilterPy's EKF and against the
IMM's own mode-level prediction; no number printed for an undetermined range."""

import numpy as np
import pytest

from sonartrack.core.units import KNOT_MPS
from sonartrack.filters.ekf import ekf_predict
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing
from sonartrack.models.passive import bf_jacobian, bf_measurement
from sonartrack.models.relative_motion import observer_inputs, relative_process_noise_stack, relative_transition
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma import BearingRecord, OwnshipTrack, TmaSettings, solve_tma
from sonartrack.tma.imm_mgekf import ImmBfModel, combined_nis, imm_bf_step_reference, run_imm_bf, transition_matrix
from sonartrack.tma.records import TmaSolution
from sonartrack.tma.sequential_bf import initial_estimate, observer_kinematics
from sonartrack.tma.settings import VerdictSettings
from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.solve import TmaResult
from sonartrack.tma.verdict import (
    DIVERGED,
    EXCEEDS_STATED_NOISE,
    INCONSISTENT,
    UNOBSERVABLE,
    diverged_rows,
    running_nis_outside,
    sequential_reasons,
    with_reasons,
)

ZIGZAG = ((500.0, 540.0, np.deg2rad(-2.25)), (1100.0, 1140.0, np.deg2rad(2.25)))


def scene(turns, seed, sigma_deg, with_freq=False):
    """A 10 kn target ~10 km away seen from a 5 kn ownship (zig-zag or straight), bearings with noise sigma_deg."""
    t = np.arange(0.0, 1600.0 + 1e-9, 8.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KNOT_MPS, np.deg2rad(45), turns)
    tgt = ManeuveringTrack(-3000.0, 9500.0, 10 * KNOT_MPS, np.deg2rad(100))
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    z = bf_measurement(np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)]))
    z = z + np.random.default_rng(seed).normal(size=z.shape) * [np.deg2rad(sigma_deg), 0.05]
    rec = BearingRecord(time_s=t, bearing_rad=z[:, 0], frequency_hz=z[:, 1] if with_freq else None)
    return rec, OwnshipTrack(time_s=t, x_m=po[:, 0], y_m=po[:, 1])


def reasons_of(turns, seed, true_sigma_deg, stated_sigma_deg=0.5, record_checks=True):
    rec, own = scene(turns, seed, true_sigma_deg)
    res = solve_tma(rec, own, TmaSettings(method="imm-mgekf", sigma_bearing_deg=stated_sigma_deg),
                    record_checks=record_checks)
    return res, res.solution.reasons().astype(str)


# ------------------------------------------------------------------------------------------------ diverged


def _solution(state, cov, t=None):
    n = len(state)
    t = np.arange(n, dtype=float) if t is None else t
    return TmaSolution(time_s=t, state=np.asarray(state, float), covariance=np.asarray(cov, float), method="imm-mgekf")


def _still_ownship(n):
    return OwnshipTrack(time_s=np.arange(n, dtype=float), x_m=np.zeros(n), y_m=np.zeros(n))


def test_each_divergence_is_caught_and_a_sane_row_is_not():
    good_cov = np.diag([300.0**2, 300.0**2, 1.0, 1.0])
    rows = [([0.0, 10_000.0, 3.0, 0.0], good_cov),                              # a target 10 km north: sane
            ([0.0, 2.519718e24, 3.0, 0.0], good_cov * 1e40),                     # the printed 2.5e21 km
            ([np.nan, 10_000.0, 3.0, 0.0], good_cov),                            # not finite
            ([0.0, 10_000.0, 40.0, 0.0], good_cov),                              # 78 kn
            ([0.0, 10_000.0, 3.0, 0.0], np.diag([300.0**2, -1.0, 1.0, 1.0])),    # not positive definite
            ([0.0, 10_000.0, 3.0, 0.0], np.diag([300.0**2, 12_000.0**2, 1.0, 1.0]))]  # range sd > range
    sol = _solution([r[0] for r in rows], [r[1] for r in rows])
    got = diverged_rows(sol, _still_ownship(len(rows)), VerdictSettings())
    np.testing.assert_array_equal(got, [False, True, True, True, True, True])
    # the bounds are the settings': a looser speed bound lets the 78 kn row through
    assert not diverged_rows(sol, _still_ownship(len(rows)), VerdictSettings(max_speed_mps=50.0))[3]


def test_a_diverged_solution_prints_no_number():
    n = 5
    state = np.tile([0.0, 2.519718e24, 3.0, 0.0], (n, 1))
    cov = np.tile(np.diag([2.3e41, 2.3e41, 1.0, 1.0]), (n, 1, 1))
    sol = _solution(state, cov)
    own = _still_ownship(n)
    nis = np.ones(n)
    reasons = sequential_reasons(sol, own, nis, np.ones(n, int), 5000.0, VerdictSettings())
    assert list(reasons) == [DIVERGED] * n
    rec = BearingRecord(time_s=sol.time_s, bearing_rad=np.zeros(n))
    res = TmaResult(solution=with_reasons(sol, reasons), record=rec, ownship=own,
                    settings=TmaSettings(method="imm-mgekf"))
    line = res.summary()
    assert "range NOT DETERMINED (diverged)" in line and " km" not in line and "e+" not in line
    cols = solution_columns(res.solution, own)
    assert not cols["range_determined"].any() and set(cols["undetermined_reason"]) == {DIVERGED}


# ------------------------------------------------------------------------------------------------ unobservable


@pytest.mark.parametrize("seed", [3, 4])
def test_without_a_maneuver_the_range_is_unobservable(seed):
    res, reasons = reasons_of((), seed, 0.5)
    assert set(reasons) == {UNOBSERVABLE}
    assert "range NOT DETERMINED (unobservable)" in res.summary() and " km" not in res.summary()


@pytest.mark.parametrize("seed", [3, 4])
def test_after_the_maneuver_the_range_is_determined(seed):
    res, reasons = reasons_of(ZIGZAG, seed, 0.5)
    t = res.solution.time_s
    # before the first turn the prior speaks; after both legs the bearings do
    assert set(reasons[t < 500.0]) == {UNOBSERVABLE}
    assert set(reasons[t > 1200.0]) == {""}
    assert "range NOT DETERMINED" not in res.summary() and " km" in res.summary()


# ------------------------------------------------------------------------------------------------ inconsistent


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_bearings_noisier_than_stated_are_inconsistent(seed):
    # noise twice what the filter is told: the running NIS ~ 4 per measurement, far above its chi-square(20) limit
    # (the filter's own verdict, as the passive chain runs it: without the record's checks)
    res, reasons = reasons_of(ZIGZAG, seed, 1.0, 0.5, record_checks=False)
    t = res.solution.time_s
    assert np.mean(reasons[t > 300.0] == INCONSISTENT) > 0.5
    assert reasons[-1] != ""
    # `sonartrack tma` judges the record first: the CV fit's chi-square against the stated 0.5 deg rejects it
    _, reasons = reasons_of(ZIGZAG, seed, 1.0, 0.5)
    assert all(r.startswith(EXCEEDS_STATED_NOISE) for r in reasons)


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_bearings_as_noisy_as_stated_are_consistent(seed):
    _, reasons = reasons_of(ZIGZAG, seed, 0.5, 0.5)
    assert INCONSISTENT not in set(reasons)


def test_running_nis_limits_are_the_chi_square_quantiles():
    from scipy.stats import chi2

    window, alpha = 4, 1e-3
    hi = chi2.ppf(1 - alpha / 2, window)
    nis = np.array([np.nan, 1, 1, 1, 1, 1, 1, 1, 1.0])
    nis_hi = nis.copy()
    nis_hi[5:9] = hi / 4 * 1.01  # the last window of 4 sums to 1.01 x the limit
    dof = np.array([0, 1, 1, 1, 1, 1, 1, 1, 1])
    assert not running_nis_outside(nis, dof, window, alpha).any()
    got = running_nis_outside(nis_hi, dof, window, alpha)
    assert got[-1] and not got[:5].any()
    nis_hi[5:9] = hi / 4 * 0.99
    assert not running_nis_outside(nis_hi, dof, window, alpha)[-1]


# ------------------------------------------------------------------------------------------------ combined NIS


def _record_inputs(turns, seed, with_freq=False):
    rec, own = scene(turns, seed, 0.5, with_freq)
    t = rec.time_s
    pos, vel = observer_kinematics(own, t)
    u = observer_inputs(t, pos, vel)
    x0, P0 = initial_estimate(float(rec.bearing_rad[0]), 300.0 if with_freq else None, vel[0], range_m=10_000.0,
                              sigma_range_m=5_000.0, sigma_bearing_rad=np.deg2rad(0.5))
    return rec, u, x0, P0


def test_single_model_nis_equals_filterpy_ekf():
    from filterpy.kalman import ExtendedKalmanFilter

    rec, u, x0, P0 = _record_inputs(ZIGZAG, 7)
    model = ImmBfModel(qs=np.array([1e-3]), Pi=None, sigma_bearing_rad=np.deg2rad(0.5), modified=False)
    x, P, mu, failed = run_imm_bf(rec.time_s, rec.bearing_rad, None, u, x0, P0, model)
    assert failed == -1
    nis, dof = combined_nis(rec.time_s, rec.bearing_rad, None, u, x, P, mu, model)
    ekf = ExtendedKalmanFilter(dim_x=5, dim_z=1)
    ekf.x, ekf.P, ekf.R, ekf.B = x0.copy(), P0.copy(), model.R[:1, :1], -np.eye(5)
    expected = [np.nan]
    for k in range(1, len(rec.time_s)):
        dt = rec.time_s[k] - rec.time_s[k - 1]
        ekf.F, ekf.Q = relative_transition(dt), relative_process_noise_stack(dt, [1e-3])[0]
        ekf.predict(u[k - 1])
        ekf.update(np.array([rec.bearing_rad[k]]), lambda s: bf_jacobian(s)[:1], lambda s: bf_measurement(s)[:1])
        expected.append(float(ekf.y @ np.linalg.solve(ekf.S, ekf.y)))
    np.testing.assert_allclose(nis[1:], expected[1:], rtol=1e-6)
    assert np.isnan(nis[0]) and dof[0] == 0 and set(dof[1:]) == {1}


def test_imm_nis_is_that_of_the_mixture_of_the_mode_predictions():
    # the combined prediction F x - u, F P F^T + Q(sum c_j q_j) against the mixture of the modes' own predictions
    rec, u, x0, P0 = _record_inputs(ZIGZAG, 8, with_freq=True)
    qs = np.array([1e-5, 1e-3, 1e-1])
    Pi = transition_matrix(3, 0.95)
    model = ImmBfModel(qs=qs, Pi=Pi, sigma_bearing_rad=np.deg2rad(0.5), sigma_freq_hz=0.05, q_f0=1e-8)
    t, z = rec.time_s[:40], np.column_stack([rec.bearing_rad, rec.frequency_hz])[:40]
    xs, Ps, mu = np.tile(x0, (3, 1)), np.tile(P0, (3, 1, 1)), np.full(3, 1 / 3)
    xh, Ph, mh, expected = [x0], [P0], [mu], [np.nan]
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        c, w = imm_mixing(mu, Pi)
        xm, Pm = imm_mix(xs, Ps, w)
        xp, Pp = ekf_predict(xm, Pm, relative_transition(dt), relative_process_noise_stack(dt, qs, 1e-8), b=-u[k - 1])
        xc, Pc = imm_combine(c, xp, Pp)
        H = bf_jacobian(xc)
        nu = z[k] - bf_measurement(xc)
        expected.append(float(nu @ np.linalg.solve(H @ Pc @ H.T + model.R, nu)))
        xs, Ps, mu, xk, Pk, _ = imm_bf_step_reference(xs, Ps, mu, z[k], u[k - 1], dt, qs, Pi, model.R,
                                                      modified=True, q_f0=1e-8)
        xh.append(xk), Ph.append(Pk), mh.append(mu)
    nis, dof = combined_nis(t, z[:, 0], z[:, 1], u, np.array(xh), np.array(Ph), np.array(mh), model)
    np.testing.assert_allclose(nis[1:], expected[1:], rtol=1e-8)
    assert set(dof[1:]) == {2}


def test_bearing_text_prints_no_number_once_the_sd_spans_half_the_circle():
    from sonartrack.tma.verdict import bearing_text

    assert bearing_text(260.44, 1.26) == "bearing 260.4 ± 1.3 deg"
    assert bearing_text(260.4, 89.9) == "bearing 260.4 ± 89.9 deg"
    # the glitch seen on a narrow band: "bearing 260.4 ± 44855.8 deg"
    assert bearing_text(260.4, 44855.8) == "bearing NOT DETERMINED"
    assert bearing_text(260.4, 90.0) == "bearing NOT DETERMINED"
    assert bearing_text(float("nan"), 1.0) == bearing_text(10.0, float("inf")) == "bearing NOT DETERMINED"
