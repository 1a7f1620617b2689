"""The IMM-MGEKF held to the batch ML of its record: the noise it runs with, and the covariance floor
(systems/passive/targets.py :func:`batch_reference`, :func:`batch_held`; core/linalg.py :func:`covariance_max`)."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from sonartrack.core.linalg import covariance_max
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.tma.settings import ImmSettings, SequentialSettings, TmaSettings, VerdictSettings
from sonartrack.tma.solve import TmaResult

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import _ml, bearings, leg_turn_leg  # noqa: E402

SIGMA_DEG = 0.2
STAGES = SimpleNamespace(settings=SimpleNamespace(ml_correlation_inflation=True, sigma_freq_floor_hz=0.02,
                                                  verdict=VerdictSettings(), max_sigma_freq_hz=0.4,
                                                  tma_min_tonal_snr_db=4.0),
                         imm=ImmSettings(), sequential=SequentialSettings(), min_separation_deg=3.0)


def _psd(M) -> bool:
    w = np.linalg.eigvalsh(0.5 * (M + M.T))
    return bool(w.min() >= -1e-9 * max(1.0, abs(w).max()))


def test_covariance_max_is_the_element_wise_maximum_of_diagonal_matrices():
    got = covariance_max(np.diag([4.0, 1.0, 9.0]), np.diag([1.0, 3.0, 9.0]))
    assert np.allclose(got, np.diag([4.0, 3.0, 9.0]))


def test_covariance_max_returns_the_larger_matrix_when_one_dominates():
    rng = np.random.default_rng(1)
    A = rng.standard_normal((4, 4))
    Q = A @ A.T + np.eye(4)
    P = Q + np.outer([1.0, 2.0, 0.0, -1.0], [1.0, 2.0, 0.0, -1.0])  # P >= Q
    assert np.allclose(covariance_max(P, Q), P)
    assert np.allclose(covariance_max(Q, P), P)


@pytest.mark.parametrize("seed", range(5))
def test_covariance_max_bounds_both_and_is_tight_along_the_joint_eigenbasis(seed):
    rng = np.random.default_rng(seed)
    A, B = rng.standard_normal((2, 4, 4))
    P, Q = A @ A.T + 0.1 * np.eye(4), B @ B.T + 0.1 * np.eye(4)
    R = covariance_max(P, Q)
    assert _psd(R - P) and _psd(R - Q)
    # along each joint eigenvector b (b^T P b = 1), R gives the larger of the two variances, no more
    L = np.linalg.cholesky(P)
    Li = np.linalg.inv(L)
    _, V = np.linalg.eigh(Li @ Q @ Li.T)
    for b in (Li.T @ V).T:
        assert b @ R @ b == pytest.approx(max(b @ P @ b, b @ Q @ b), rel=1e-9)


def _result(t, state_last, cov_last, method="imm-mgekf"):
    n = len(t)
    state = np.tile(state_last, (n, 1))
    cov = np.tile(np.diag([300.0**2, 300.0**2, 1.0, 1.0]), (n, 1, 1))
    cov[-1] = cov_last
    own = OwnshipTrack(time_s=t, x_m=np.zeros(n), y_m=np.zeros(n))
    return TmaResult(solution=TmaSolution(time_s=t, state=state, covariance=cov, method=method),
                     record=BearingRecord(time_s=t, bearing_rad=np.zeros(n)), ownship=own,
                     settings=TmaSettings(method=method))


def test_an_agreeing_filter_claims_no_less_than_the_batch_at_its_last_row():
    from sonartrack.systems.passive.targets import batch_held

    t = np.arange(10.0) * 10.0
    x = np.array([2000.0, 10_000.0, 3.0, 0.0])
    ml = _result(t, x, np.diag([600.0**2, 200.0**2, 0.5, 0.5]), method="ml")
    seq = _result(t, x, np.diag([300.0**2, 300.0**2, 1.0, 1.0]))
    got = batch_held(seq, ml)
    assert got.solution.range_flags().all()
    assert np.allclose(got.solution.covariance[-1], np.diag([600.0**2, 300.0**2, 1.0, 1.0]))
    assert np.array_equal(got.solution.covariance[:-1], seq.solution.covariance[:-1])
    assert "position sd x 2" in got.warnings[-1]
    # a filter that already claims more keeps its covariance, with no warning
    wide = _result(t, x, np.diag([700.0**2, 700.0**2, 1.0, 1.0]))
    kept = batch_held(wide, ml)
    assert np.array_equal(kept.solution.covariance, wide.solution.covariance) and kept.warnings == ()


def _held_and_plain(z_error, seeds=range(8)):
    """Final NEES of the IMM-MGEKF on bearings + a tonal's frequency as run and as held to its batch reference, and
    whether each is determined, over records of one CV target (3 km east, 4 km north, moving (-2, 1) m/s, a 200 Hz
    line) seen from the leg-turn-leg ownship every 2 s for 900 s: bearing errors white of the stated sd plus
    ``z_error(t)``, frequency errors white of 0.1 Hz (the received frequency from the range rate by central
    differences, independent of the code's Doppler model)."""
    from sonartrack.acoustics.tonal import TonalTrack
    from sonartrack.systems.passive.targets import _sequential, batch_held, batch_reference, determination_checked

    t = np.arange(0.0, 900.0, 2.0)
    own = leg_turn_leg(t)
    sensor = OwnshipTrack(time_s=t, x_m=own[:, 0], y_m=own[:, 1])
    sigma = np.deg2rad(SIGMA_DEG)
    x0, v = np.array([3000.0, 4000.0]), np.array([-2.0, 1.0])
    truth = np.concatenate([x0 + v * t[-1], v])

    def range_at(tt):
        o = leg_turn_leg(tt)
        return np.hypot(x0[0] + v[0] * tt - o[:, 0], x0[1] + v[1] * tt - o[:, 1])

    f_true = 200.0 * (1.0 - (range_at(t + 1e-3) - range_at(t - 1e-3)) / 2e-3 / STAGES.sequential.sound_speed_mps)
    out = {"plain": [], "held": [], "plain_det": [], "held_det": []}
    for seed in seeds:
        g = np.random.default_rng(seed)
        z = bearings(t, own, x0, v, 0.0, 0) + sigma * g.standard_normal(t.size) + z_error(t)
        tonal = TonalTrack(line_hz=200.0, line_snr_db=10.0, time_s=t,
                           frequency_hz=f_true + 0.1 * g.standard_normal(t.size), sigma_hz=0.1)
        ml = determination_checked(_ml(t, z, own, SIGMA_DEG))
        raw = _sequential(t, z, tonal, sensor, sigma, STAGES)
        held = batch_held(raw, batch_reference(ml, t, z, tonal, sigma, STAGES))
        for name, res in (("plain", raw), ("held", held)):
            e = res.solution.state[-1] - truth
            out[name].append(float(e @ np.linalg.solve(res.solution.covariance[-1], e)))
            out[name + "_det"].append(bool(res.solution.range_flags()[-1]))
    return {k: np.array(v) for k, v in out.items()}


def test_held_filter_covers_a_bias_of_the_last_minutes_bearings():
    """An independent world (not our simulator): over the last 90 s a bearing bias growing to 0.6 deg (a louder ship
    closing in). The filter follows the last bearings with the cross-range sd of hundreds of averaged scans, so its
    final NEES is far beyond chi-square(4); held to the bearings + frequency ML, whose block jackknife sees the bias,
    its ANEES lies below the 99.9 % point of chi-square(4 n) / n and every row stays determined."""
    from scipy.stats import chi2

    r = _held_and_plain(lambda t: np.deg2rad(0.6) * np.clip((t - (t[-1] - 90.0)) / 90.0, 0.0, 1.0))
    limit = chi2.ppf(0.999, 4 * len(r["held"])) / len(r["held"])
    assert r["plain_det"].all() and np.mean(r["plain"]) > limit  # the failure the floor is for
    assert r["held_det"].all() and np.mean(r["held"]) < limit


def test_the_floor_leaves_a_consistent_filter_determined():
    """White bearing errors of the stated sd: the filter's covariance already covers its error; held to the batch it
    stays determined, consistent, and (a floor only widens) no NEES grows."""
    from scipy.stats import chi2

    r = _held_and_plain(lambda t: 0.0)
    n = len(r["held"])
    assert r["held_det"].all() and r["plain_det"].all()
    assert np.all(r["held"] <= r["plain"] + 1e-9)
    assert np.mean(r["held"]) < chi2.ppf(0.999, 4 * n) / n
