"""solve_tma: the one entry point, called with arrays as a notebook would, against the solvers it wires."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.core.units import KNOT_MPS
from sonartrack.models.passive import bf_measurement
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma import BearingRecord, OwnshipTrack, TmaSettings, solve_tma
from sonartrack.tma.batch import ekf_from_batch, solve_batch
from sonartrack.tma.batch_ml import ml_bearings_only
from sonartrack.tma.settings import BatchSettings


@pytest.fixture(scope="module")
def scene():
    """Noisy bearings + frequencies of a 10 kn target 10 km away, from a zig-zagging 5 kn ownship."""
    t = np.arange(0.0, 1600.0 + 1e-9, 8.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KNOT_MPS, np.deg2rad(45), ((500.0, 540.0, np.deg2rad(-2.25)),
                                                                     (1100.0, 1140.0, np.deg2rad(2.25))))
    tgt = ManeuveringTrack(-3000.0, 9500.0, 10 * KNOT_MPS, np.deg2rad(100))
    po, vo, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    z = bf_measurement(np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)]))
    z = z + np.random.default_rng(3).normal(size=z.shape) * [np.deg2rad(0.5), 0.05]
    record = BearingRecord(time_s=t, bearing_rad=z[:, 0], frequency_hz=z[:, 1])
    return record, OwnshipTrack(time_s=t, x_m=po[:, 0], y_m=po[:, 1]), np.column_stack([pt, vt])


def test_sequential_with_frequency_tracks_the_target(scene):
    record, own, truth = scene
    res = solve_tma(record, own, TmaSettings(method="imm-mgekf", frequency=True, sigma_bearing_deg=0.5,
                                             sigma_freq_hz=0.05))
    assert res.solution.state.shape == (len(record.time_s), 4) and res.solution.method == "imm-mgekf"
    assert np.hypot(*(res.solution.state[-1, :2] - truth[-1, :2])) < 0.03 * 10_000
    assert res.f0_hz == pytest.approx(300.0, abs=0.1) and res.f0_std_hz > 0
    assert len(res.mode_probabilities) == 3 and sum(res.mode_probabilities) == pytest.approx(1.0)
    line = res.summary()
    assert line.startswith("tma imm-mgekf: ") and "f0 300." in line and "\n" not in line


def test_batch_window_then_ekf_is_the_composition_of_its_parts(scene):
    """solve_tma with batch.window_s = ML on the first window, then the EKF from its last state."""
    record, own, _ = scene
    s = TmaSettings(method="ml", sigma_bearing_deg=0.5, batch=BatchSettings(window_s=1200.0, ekf_q_m2_s3=1e-6))
    res = solve_tma(record, own, s)
    sb = np.deg2rad(0.5)
    head = record.until(1200.0)
    first = solve_batch(head, own, "ml", sigma_bearing_rad=sb)
    est = ml_bearings_only(head.bearing_rad, head.time_s, own.position_at(head.time_s), sb)
    later = ekf_from_batch(record, own, est, start_s=float(head.time_s[-1]), sigma_bearing_rad=sb, q_m2_s3=1e-6)
    np.testing.assert_array_equal(res.solution.time_s, record.time_s)
    np.testing.assert_allclose(res.solution.state[: len(head.time_s)], first.state, rtol=1e-12)
    np.testing.assert_allclose(res.solution.state[len(head.time_s):], later.state[1:], rtol=1e-9)
    assert res.solution.method == "ml+ekf" and "then a sequential EKF" in res.summary()


def test_settings_of_the_other_family_are_refused(scene):
    record, own, _ = scene
    with pytest.raises(InputError, match="--env and --sl"):
        solve_tma(record, own, TmaSettings(method="ekf", batch=BatchSettings(env="east-summer")))
    with pytest.raises(InputError, match="--frequency applies"):
        solve_tma(record, own, TmaSettings(method="ml", frequency=True))
    with pytest.raises(InputError, match="must leave bearings for both"):
        solve_tma(record, own, TmaSettings(method="ml", batch=BatchSettings(window_s=5000.0)))


def test_the_ownship_must_cover_the_record(scene):
    record, own, _ = scene
    short = OwnshipTrack(time_s=own.time_s[:50], x_m=own.x_m[:50], y_m=own.y_m[:50])
    with pytest.raises(InputError, match="outside the ownship file's span"):
        solve_tma(record, short)


def test_a_failing_filter_is_an_input_error(scene, monkeypatch):
    """A numerical failure of the filter (reported by run_imm_bf as its step index) becomes a one-line
    InputError naming the time and what to change."""
    import sonartrack.tma.sequential_bf as seq

    record, own, _ = scene
    real = seq.run_imm_bf

    def failing(*args, **kw):
        x, P, mu, _ = real(*args, **kw)
        return x, P, mu, 5

    monkeypatch.setattr(seq, "run_imm_bf", failing)
    with pytest.raises(InputError, match=r"failed numerically at t = 40 s .*initial_range_m") as e:
        solve_tma(record, own, TmaSettings(method="ekf"))
    assert "\n" not in str(e.value)


def test_observable_range_limit_is_the_maneuver_over_the_bearing_standard_error():
    from sonartrack.tma.batch_ml import observable_range_limit_m

    # ownship on a straight line except one sample 100 m off it: deviation ~ 100 m (less the fit's share)
    tau = np.arange(0.0, 100.0, 1.0)
    own = np.column_stack([np.zeros(100), 3.0 * tau])
    own[50, 0] = 100.0
    lim = observable_range_limit_m(tau, own, np.deg2rad(1.0))
    assert lim == pytest.approx(99.0 * 10.0 / np.deg2rad(1.0), rel=0.02)  # dev * sqrt(100) / sigma


def test_ml_flags_a_range_the_record_cannot_resolve(scene):
    record, own, _ = scene
    good = solve_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.5))
    assert good.solution.range_flags().all() and "NOT DETERMINED" not in good.summary()
    # a 5 m/s target 1000 km away: the ownship's zig-zag turns the bearings by ~1e-4 deg, far below the noise
    t = record.time_s
    po = own.position_at(t)
    b_far = np.arctan2(5.0 * t - po[:, 0], 1e6 - po[:, 1])
    b_far = b_far + np.random.default_rng(5).normal(0, np.deg2rad(0.5), len(t))
    res = solve_tma(BearingRecord(time_s=t, bearing_rad=b_far), own, TmaSettings(method="ml", sigma_bearing_deg=0.5))
    flags = res.solution.range_flags()
    if flags.all():  # the noise happened to give a range inside the resolvable limit: then it must be honest
        pytest.fail(f"a target ~1e7 m away was given a determined range: {res.summary()}")
    assert any("range not determined" in w for w in res.warnings)
    assert "NOT DETERMINED" in res.summary() and "range 1" not in res.summary()


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_correlation_inflation_matches_ar1(rho):
    """An AR(1) series e_k = rho e_(k-1) + w_k: n / n_eff = (1 + rho) / (1 - rho) (Bretherton et al. 1999)."""
    from sonartrack.tma.solve import correlation_inflation

    rng = np.random.default_rng(3)
    e = np.zeros(20000)
    w = rng.normal(size=e.size)
    for k in range(1, e.size):
        e[k] = rho * e[k - 1] + w[k]
    assert correlation_inflation(e) == pytest.approx((1 + rho) / (1 - rho), rel=0.05)
    assert correlation_inflation(e[:2]) == 1.0 and correlation_inflation(np.zeros(10)) == 1.0


def test_ml_fit_is_the_solution_and_the_inflation_scales_its_covariance(scene):
    """A given ML estimate of the record (e.g. a multi-start search's) is the solution, as computed here by hand:
    the CV propagation of its X0 and covariance, the covariance times (1 + rho) / (1 - rho) of its own residuals."""
    from sonartrack.core.angles import wrap_angle
    from sonartrack.tma.batch_ml import bearing_model
    from sonartrack.tma.solve import correlation_inflation

    record, own, _ = scene
    t = record.time_s
    sb = np.deg2rad(0.5)
    start = np.array([-2000.0, 9000.0, 4.0, -1.0])  # off the pseudo-linear start: the fit must be used as given
    fit = ml_bearings_only(record.bearing_rad, t, own.position_at(t), sb, x_init=start)
    plain = solve_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.5), ml_fit=fit)
    tau = t - t[0]
    np.testing.assert_allclose(plain.solution.state[:, 0], fit.x0[0] + fit.x0[2] * tau, rtol=1e-12)
    np.testing.assert_allclose(plain.solution.covariance[0], fit.covariance, rtol=1e-12)
    s = TmaSettings(method="ml", sigma_bearing_deg=0.5, batch=BatchSettings(correlation_inflation=True))
    inflated = solve_tma(record, own, s, ml_fit=fit)
    h, _, _ = bearing_model(fit.x0, tau, own.position_at(t))
    factor = correlation_inflation(wrap_angle(record.bearing_rad - h))
    np.testing.assert_allclose(inflated.solution.covariance, plain.solution.covariance * factor, rtol=1e-12)
    np.testing.assert_array_equal(inflated.solution.state, plain.solution.state)
    with pytest.raises(InputError, match="ml_fit must be an ML estimate of this record"):
        solve_tma(BearingRecord(time_s=t[1:], bearing_rad=record.bearing_rad[1:]), own, TmaSettings(method="ml"),
                  ml_fit=fit)


def test_unobservable_record_is_flagged_on_request_and_refused_otherwise():
    """Ownship on a straight line at constant speed: range is unobservable from bearings (Nardone & Aidala 1981)."""
    t = np.arange(0.0, 600.0, 10.0)
    own = OwnshipTrack(time_s=t, x_m=np.zeros_like(t), y_m=3.0 * t)
    b = np.arctan2(5000.0 + 2.0 * t, 8000.0 - 3.0 * t)
    b = b + np.random.default_rng(1).normal(0, np.deg2rad(0.3), len(t))
    record = BearingRecord(time_s=t, bearing_rad=b)
    with pytest.raises(InputError, match="ownship has not maneuvered"):
        solve_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.3))
    res = solve_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.3), unobservable="flag")
    assert not res.solution.range_flags().any()
    assert any("ownship has not maneuvered" in w for w in res.warnings)
    assert "NOT DETERMINED" in res.summary()
    # the bearing is still a measurement: the solution's bearing follows the bearings
    own_xy = own.position_at(t)
    sol_b = np.arctan2(res.solution.state[:, 0] - own_xy[:, 0], res.solution.state[:, 1] - own_xy[:, 1])
    assert np.rad2deg(np.max(np.abs(np.angle(np.exp(1j * (sol_b - b)))))) < 1.5
    with pytest.raises(InputError, match="apply to method ml over the whole record"):
        solve_tma(record, own, TmaSettings(method="ekf"), unobservable="flag")
