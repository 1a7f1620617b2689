"""The passive chain's jackknife verdict (systems/passive/targets.py :func:`jackknife_checked`): a clean
constant-velocity record stays determined with a covariance its error agrees with over a Monte Carlo; a record that
joins two ships, or whose bearings step aside for a stretch, is not determined or gets a covariance that covers its
error."""

from dataclasses import replace

import numpy as np
import pytest

from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.core.gaussian import chi2_quantile
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.passive.targets import determination_checked, jackknife_checked
from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.settings import BatchSettings, TmaSettings
from sonartrack.tma.sides import mirror_bearings_rad, resolve_side
from sonartrack.tma.solve import solve_tma
from sonartrack.tma.verdict import NOT_ONE_TARGET

LN100 = float(np.log(100.0))
BEAMWIDTH_DEG = 3.0
X0 = np.array([-3000.0, 5000.0, 2.0, -1.0])


def scene(step_s=5.0):
    """Array (no tow) north at 3 m/s, 60 deg turn to starboard from 600 s, 1200 s; the CV target X0's bearings."""
    t = np.arange(0.0, 1200.0 + 1e-9, step_s)
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((600.0, 720.0, np.deg2rad(0.5)),)).state(t)
    tgt = X0[:2] + t[:, None] * X0[2:]
    return t, own, heading, bearing_rad(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])


def solved(t, own, heading, b):
    """As the chain solves a track (targets.py :func:`solve_target`): side, ML on its bearings with the residual
    checks, then the jackknife. Returns (side, ML before the jackknife, after it)."""
    cone = np.abs(wrap_angle(b - heading))
    side = resolve_side(t, cone, heading, own, min_log_lr=LN100)
    stbd, port = mirror_bearings_rad(cone, heading)
    chosen, fit = (port, side.port) if side.side == "port" else (stbd, side.starboard)
    settings = TmaSettings(method="ml", sigma_bearing_deg=float(np.rad2deg(side.sigma_bearing_rad)),
                           batch=BatchSettings(correlation_inflation=True))
    sensor = OwnshipTrack(time_s=t, x_m=own[:, 0], y_m=own[:, 1])
    ml = determination_checked(solve_tma(BearingRecord(time_s=t, bearing_rad=chosen), sensor, settings, ml_fit=fit,
                                         unobservable="flag", record_checks=False))  # as the chain calls it
    return side, ml, jackknife_checked(ml, side, (t, stbd, port, own), LN100, BEAMWIDTH_DEG)


def end_nees(result, truth_xy):
    e = result.solution.state[-1, :2] - truth_xy
    return float(e @ np.linalg.solve(result.solution.covariance[-1, :2, :2], e))


def test_a_clean_record_stays_determined_and_consistent():
    # white 0.3 deg noise on one CV target: every run determined; the final position's NEES (2 dof) averaged over
    # the runs lies below the upper 99.9 % limit of chi-square(2N) / N: the stated covariance covers the error. The
    # jackknife errs large (Efron & Stein): widened only where its test at 1e-3 fails, it still widens some clean
    # runs, so the mean can lie below the lower limit (0.85 for 0.97 here), bounded at half of it
    t, own, heading, b = scene()
    truth = X0[:2] + X0[2:] * t[-1]
    nees = []
    for seed in range(24):
        z = b + np.deg2rad(0.3) * np.random.default_rng(seed).standard_normal(len(t))
        side, _, ml = solved(t, own, heading, z)
        assert side.side == "port" and ml.solution.range_flags()[-1]
        nees.append(end_nees(ml, truth))
    n = len(nees)
    assert np.mean(nees) <= chi2_quantile(0.999, 2 * n) / n
    assert np.mean(nees) >= 0.5 * chi2_quantile(0.001, 2 * n) / n


def joined(seed, v_mps, t_join_s):
    """The record of :func:`scene` whose bearings after ``t_join_s`` are another ship's: 300 m east of the first at
    that time, moving at ``v_mps`` (east, north)."""
    t, own, heading, b = scene()
    other = X0[:2] + X0[2:] * t_join_s + np.array([300.0, 0.0]) + (t[:, None] - t_join_s) * np.asarray(v_mps)
    b2 = bearing_rad(other[:, 0] - own[:, 0], other[:, 1] - own[:, 1])
    z = np.where(t > t_join_s, b2, b) + np.deg2rad(0.3) * np.random.default_rng(seed).standard_normal(len(t))
    return t, own, heading, z


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize(("v_mps", "t_join_s"), [((-3.0, 0.0), 900.0), ((4.0, -4.0), 700.0)])
def test_two_ships_joined_are_not_determined(seed, v_mps, t_join_s):
    # the residual checks let the record through, determined and wrong beyond its covariance; the rest of the
    # record predicts the other ship's bearings more than a beamwidth away
    t, own, heading, z = joined(seed, v_mps, t_join_s)
    _, ml, checked = solved(t, own, heading, z)
    truth = X0[:2] + X0[2:] * t[-1]
    assert ml.solution.range_flags()[-1] and end_nees(ml, truth) > chi2_quantile(0.999, 2)
    assert not checked.solution.range_flags()[-1]
    assert checked.solution.reasons()[-1] == NOT_ONE_TARGET


@pytest.mark.xfail(strict=True, reason="known limit: a second ship whose bearings stay within a beamwidth of the "
                   "first's predicted track, joined without a gap, moves the jackknife's replicates too little")
def test_a_join_within_the_beam_is_not_caught():
    t, own, heading, z = joined(0, (0.0, 3.0), 900.0)
    _, _, checked = solved(t, own, heading, z)
    truth = X0[:2] + X0[2:] * t[-1]
    assert not checked.solution.range_flags()[-1] or end_nees(checked, truth) < chi2_quantile(0.999, 2)


@pytest.mark.parametrize("seed", range(4))
def test_bearings_stepping_aside_at_the_end_are_covered(seed):
    # bearings 1 deg off for the last 200 s (a louder ship's pull): the plain ML's error lies outside its 99.9 %
    # ellipse; the checked covariance covers it, or the range is not determined
    t, own, heading, b = scene()
    z = b + np.where(t > 1000.0, np.deg2rad(1.0), 0.0)
    z = z + np.deg2rad(0.3) * np.random.default_rng(10 + seed).standard_normal(len(t))
    _, ml, checked = solved(t, own, heading, z)
    truth = X0[:2] + X0[2:] * t[-1]
    assert ml.solution.range_flags()[-1] and end_nees(ml, truth) > chi2_quantile(0.999, 2)
    if checked.solution.range_flags()[-1]:
        assert end_nees(checked, truth) < chi2_quantile(0.999, 2)


def test_the_jackknife_leaves_undetermined_solutions_alone():
    t, own, heading, b = scene()
    side, ml, _ = solved(t, own, heading, b + np.deg2rad(0.3) * np.random.default_rng(0).standard_normal(len(t)))
    undetermined = replace(ml, solution=replace(ml.solution, range_determined=np.zeros(len(t), bool)))
    stbd, port = mirror_bearings_rad(np.abs(wrap_angle(b - heading)), heading)
    assert jackknife_checked(undetermined, side, (t, stbd, port, own), LN100, BEAMWIDTH_DEG) is undetermined
