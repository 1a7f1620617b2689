"""The block jackknife of the bearings + frequency ML (systems/passive/targets.py :func:`bf_jackknife_checked`,
tma/batch_bf.py :func:`bf_jackknife`): a clean simulated record stays determined with its error inside its
covariance over a Monte Carlo; a record that joins two sources is not determined; a frequency bias over a tenth or
two of the record is covered by the widened covariance; a record the jackknife cannot check is not determined."""

import sys
from pathlib import Path

import numpy as np
import pytest

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.systems.passive import targets as tg
from sonartrack.tma.sides import time_blocks
from sonartrack.tma.verdict import DIVERGED, NOT_ONE_TARGET

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import _ml  # noqa: E402
from test_targets_bf import F0, STAGES, _scene  # noqa: E402

X0, V = np.array([3000.0, 4000.0]), np.array([1.5, -1.0])
CHI2_2_999 = chi2_quantile(0.999, 2)


def both(t, own, z, tonal, monkeypatch):
    """(the bearings + frequency ML without the jackknife, with it) of one record."""
    bo = _ml(t, z, own, 1.0)
    with monkeypatch.context() as m:
        m.setattr(tg, "bf_jackknife_checked", lambda result, *args: result)
        plain = tg.frequency_ml(bo, t, z, tonal, STAGES)
    return plain, tg.frequency_ml(bo, t, z, tonal, STAGES)


def end_nees(result, truth_xy):
    e = result.solution.state[-1, :2] - truth_xy
    return float(e @ np.linalg.solve(result.solution.covariance[-1, :2, :2], e))


def with_frequency(tonal, f):
    return TonalTrack(line_hz=F0, line_snr_db=3.0, time_s=tonal.time_s, frequency_hz=f, sigma_hz=tonal.sigma_hz)


def test_a_clean_record_stays_determined_and_consistent(monkeypatch):
    # white noise, one CV target on one straight leg: every run determined; the mean NEES (2 dof) of the final
    # position over N runs below the upper 99.9 % point of chi-square(2N) / N, and above half its lower point (the
    # jackknife errs large, Efron & Stein 1981: a clean run is sometimes widened)
    nees = []
    for seed in range(10):
        t, own, z, tonal = _scene(X0, V, 20 + seed)
        _, checked = both(t, own, z, tonal, monkeypatch)
        assert checked.solution.range_flags().all()
        nees.append(end_nees(checked, X0 + V * t[-1]))
    n = len(nees)
    assert np.mean(nees) <= chi2_quantile(0.999, 2 * n) / n
    assert np.mean(nees) >= 0.5 * chi2_quantile(0.001, 2 * n) / n


def joined(seed, v2, t_join_s, df_hz):
    """The record of a target whose bearings and frequencies after ``t_join_s`` are another ship's: 300 m east of
    the first then, moving at ``v2`` (m/s), its line ``df_hz`` above."""
    t, own, z, tonal = _scene(X0, V, seed)
    v2 = np.asarray(v2, float)
    x2 = X0 + V * t_join_s + np.array([300.0, 0.0]) - v2 * t_join_s
    _, _, z2, tonal2 = _scene(x2, v2, seed + 100)
    after = t > t_join_s
    f = np.where(after, tonal2.frequency_hz + df_hz, tonal.frequency_hz)
    return t, own, np.where(after, z2, z), with_frequency(tonal, f)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize(("v2", "t_join_s", "df_hz"), [((0.0, 3.0), 900.0, 0.0), ((2.0, 2.0), 600.0, 0.3)])
def test_two_sources_joined_are_not_determined(seed, v2, t_join_s, df_hz, monkeypatch):
    # without the jackknife the fit is determined and its final position lies outside its 99.9 % ellipse about
    # the first ship's; the rest of the record predicts one stretch's bearings more than a beamwidth away
    t, own, z, tonal = joined(seed, v2, t_join_s, df_hz)
    plain, checked = both(t, own, z, tonal, monkeypatch)
    assert plain.solution.range_flags()[-1] and end_nees(plain, X0 + V * t[-1]) > CHI2_2_999
    assert not checked.solution.range_flags().any()
    assert checked.solution.reasons()[-1] == NOT_ONE_TARGET


@pytest.mark.parametrize("seed", range(4))
def test_a_frequency_step_over_the_last_stretches_is_covered(seed, monkeypatch):
    # the line 0.3 Hz (3 of its sds) high over the last 240 s (two tenths): the plain fit's error lies outside its
    # 99.9 % ellipse; the jackknife's covariance covers it, or the range is not determined
    t, own, z, tonal = _scene(X0, V, seed)
    biased = with_frequency(tonal, tonal.frequency_hz + np.where(t > 960.0, 0.3, 0.0))
    plain, checked = both(t, own, z, biased, monkeypatch)
    truth = X0 + V * t[-1]
    assert plain.solution.range_flags()[-1] and end_nees(plain, truth) > CHI2_2_999
    if checked.solution.range_flags()[-1]:
        assert end_nees(checked, truth) < CHI2_2_999
        assert any(w.startswith("block jackknife: covariance widened") for w in checked.warnings)


@pytest.mark.xfail(strict=True, reason="known limit: a frequency step over half the record moves no single "
                   "block's replicate; the residual checks inflate the covariance too little to cover it")
def test_a_frequency_step_at_mid_record_is_not_caught(monkeypatch):
    t, own, z, tonal = _scene(X0, V, 0)
    biased = with_frequency(tonal, tonal.frequency_hz + np.where(t > 600.0, 0.3, 0.0))
    _, checked = both(t, own, z, biased, monkeypatch)
    assert not checked.solution.range_flags()[-1] or end_nees(checked, X0 + V * t[-1]) < CHI2_2_999


def test_a_record_of_two_pieces_is_not_determined(monkeypatch):
    # frequencies over the first 100 s and the last 40 s only (the line lost between): two blocks; without the
    # first the 4 last measurements cannot fit the 5 parameters, the jackknife cannot check the fit
    t, own, z, tonal = _scene(X0, V, 0, sigma_deg=0.3, sigma_hz=0.05)
    keep = (t <= 100.0) | (t > 1150.0)
    pieces = TonalTrack(line_hz=F0, line_snr_db=3.0, time_s=t[keep], frequency_hz=tonal.frequency_hz[keep],
                        sigma_hz=0.05)
    assert len(time_blocks(t[keep], 10)) - 1 == 2
    plain, checked = both(t, own, z, pieces, monkeypatch)
    assert plain.solution.range_flags()[-1]
    assert not checked.solution.range_flags().any() and checked.solution.reasons()[-1] == DIVERGED


def test_undetermined_solutions_are_left_alone(monkeypatch):
    # a target on a constant bearing: undetermined before the jackknife, returned as it is
    t, own, z, tonal = _scene(np.array([0.0, 6000.0]), np.array([0.0, 1.0]), 0)
    plain, checked = both(t, own, z, tonal, monkeypatch)
    assert not plain.solution.range_flags()[-1]
    assert checked is plain or (list(checked.solution.reasons()) == list(plain.solution.reasons())
                                and checked.warnings == plain.warnings)
