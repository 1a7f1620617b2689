"""The passive chain's verdicts: rows whose array side is not decided, scans shared with a neighbour left out,
biased bearings' residuals inflating the ML covariance, and the tables and summary line printing no number for an
undetermined range (ML and IMM-MGEKF rows alike)."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from sonartrack.systems.passive.checks import residual_check
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.tables import target_line, targets_table
from sonartrack.systems.passive.targets import Target, determination_checked, side_checked, without_neighbour_scans
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.tma.settings import TmaSettings
from sonartrack.tma.sides import SideDecision
from sonartrack.tma.solve import TmaResult
from sonartrack.tma.verdict import DIVERGED, SIDE_UNRESOLVED, UNOBSERVABLE, with_reasons

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import _ml, bearings, leg_turn_leg  # noqa: E402


def result_of(n=10, range_m=10_000.0, method="imm-mgekf"):
    """A determined solution: a target range_m north of a still ownship, 300 m position sd."""
    t = np.arange(n, dtype=float) * 10.0
    state = np.tile([0.0, range_m, 3.0, 0.0], (n, 1))
    cov = np.tile(np.diag([300.0**2, 300.0**2, 1.0, 1.0]), (n, 1, 1))
    own = OwnshipTrack(time_s=t, x_m=np.zeros(n), y_m=np.zeros(n))
    sol = TmaSolution(time_s=t, state=state, covariance=cov, method=method)
    return TmaResult(solution=sol, record=BearingRecord(time_s=t, bearing_rad=np.zeros(n)), ownship=own,
                     settings=TmaSettings(method=method))


def side(which="starboard"):
    return SideDecision(which, 8.0 if which != "unresolved" else 0.1, np.deg2rad(0.5), None, None)


# ------------------------------------------------------------------------------------------------ side


def test_an_unresolved_side_leaves_every_row_undetermined():
    res = side_checked(result_of(), side("unresolved"), float("nan"), causal=False)
    assert list(res.solution.reasons()) == [SIDE_UNRESOLVED] * 10


def test_a_filter_is_undetermined_until_its_side_was_decided():
    r = result_of()  # times 0..90 s
    causal = side_checked(r, side("starboard"), 45.0, causal=True)
    np.testing.assert_array_equal(causal.solution.range_flags(), r.solution.time_s >= 45.0)
    assert set(causal.solution.reasons()[:5]) == {SIDE_UNRESOLVED}
    # the batch ML uses the whole record, decided on the whole record: nothing to withhold
    assert side_checked(r, side("starboard"), 45.0, causal=False) is r


def test_a_row_keeps_its_first_reason():
    r = result_of()
    reasons = np.array([UNOBSERVABLE] * 3 + [""] * 7, dtype=object)
    r = TmaResult(**{**{f: getattr(r, f) for f in r.__slots__}, "solution": with_reasons(r.solution, reasons)})
    got = side_checked(r, side("unresolved"), float("nan"), causal=True).solution.reasons()
    assert list(got) == [UNOBSERVABLE] * 3 + [SIDE_UNRESOLVED] * 7


# ------------------------------------------------------------------------------------------------ neighbours


def track(track_id, t, cone):
    t, cone = np.asarray(t, float), np.asarray(cone, float)
    return TrackMeasurements(track_id, t, cone, np.ones(len(t)), t, cone)


def test_scans_where_a_neighbour_shares_the_beam_are_left_out():
    t = np.arange(0.0, 100.0, 1.0)
    me = track(1, t, np.full(100, 60.0))
    crossing = track(2, t[20:90], np.linspace(40.0, 80.0, 70))  # 0.58 deg/s, at 60 deg at t = 54.5 s
    far = track(3, t, np.full(100, 120.0))
    got, note = without_neighbour_scans(me, [me, crossing, far], 3.0)
    near = np.abs(np.interp(t, crossing.track_time_s, crossing.track_cone_deg) - 60.0) < 3.0
    near &= (t >= 20.0) & (t <= 89.0)
    np.testing.assert_array_equal(got.time_s, t[~near])
    assert 0 < near.sum() < 20 and note.startswith(f"{near.sum()} scan(s) left out") and "track(s) 2 " in note
    assert got.track_time_s is me.track_time_s  # the filtered track is kept whole
    same, none = without_neighbour_scans(me, [me, far], 3.0)
    assert same is me and none is None
    # never fewer than 10 scans: a track that lives beside another all along keeps its scans (and its bias)
    beside = track(4, t, np.full(100, 61.0))
    assert without_neighbour_scans(me, [beside], 3.0) == (me, None)


# ------------------------------------------------------------------------------------------------ biased bearings


def _end_nees(result, end_xy):
    e = result.solution.state[-1, :2] - end_xy
    return float(e @ np.linalg.solve(result.solution.covariance[-1, :2, :2], e))


@pytest.mark.parametrize("seed", range(4))
def test_bearings_pulled_for_a_minute_inflate_the_covariance_by_their_measured_scale(seed):
    # a 0.3 deg record of 300 s, pulled by 0.5 deg for 60 s (a louder ship sharing the beam): the white-noise ML
    # claims a covariance its error exceeds; the residuals' measured scale restores it
    t = np.arange(0.0, 300.0, 1.0)
    own = leg_turn_leg(t)
    x0 = np.array([1500.0, 1300.0, -1.0, 2.0])
    z = bearings(t, own, x0[:2], x0[2:], np.deg2rad(0.3), seed)
    pulled = z + np.where((t > 180.0) & (t < 240.0), np.deg2rad(0.5), 0.0)
    plain = _ml(t, pulled, own, 0.3)
    checked = determination_checked(plain)
    # the scale, by hand: residuals of the fit, chi2 / dof and the 30 s block means' chi2 / B
    own_t = plain.ownship.position_at(t)
    e = pulled - np.arctan2(plain.solution.state[:, 0] - own_t[:, 0], plain.solution.state[:, 1] - own_t[:, 1])
    w = e / np.deg2rad(0.3)
    kappa = 1.0  # the fit states no correlation inflation (batch.correlation_inflation off)
    assert not plain.settings.batch.correlation_inflation
    blocks = [w[(t >= a) & (t < a + 30.0)] for a in np.arange(0.0, 300.0, 30.0)]
    s2 = max(1.0, float(w @ w) / 296, sum(len(b) * b.mean() ** 2 for b in blocks) / kappa / len(blocks))
    assert not residual_check(t, e, np.deg2rad(0.3), inflation=kappa).consistent
    assert s2 > 2.0
    np.testing.assert_allclose(checked.solution.covariance, plain.solution.covariance * s2, rtol=1e-9)
    assert any("covariance inflated by" in w for w in checked.warnings)
    assert checked.solution.range_flags()[-1]
    end = x0[:2] + x0[2:] * t[-1]
    assert _end_nees(checked, end) < 13.82  # chi-square(2) 99.9 %


@pytest.mark.parametrize("seed", range(4))
def test_unbiased_bearings_are_left_alone(seed):
    t = np.arange(0.0, 300.0, 1.0)
    own = leg_turn_leg(t)
    res = _ml(t, bearings(t, own, (1500.0, 1300.0), (-1.0, 2.0), np.deg2rad(0.3), seed), own, 0.3)
    assert determination_checked(res) is res


# ------------------------------------------------------------------------------------------------ tables, lines


def target(ml: TmaResult, seq: TmaResult) -> Target:
    t = ml.solution.time_s
    return Target(1, track(7, t, np.full(len(t), 60.0)), side("starboard"), 0.0, ml, None, seq, None)


def diverged(result: TmaResult) -> TmaResult:
    n = len(result.solution.time_s)
    sol = result.solution
    huge = TmaSolution(time_s=sol.time_s, state=np.tile([0.0, 2.52e24, 3.0, 0.0], (n, 1)),
                       covariance=sol.covariance * 1e40, method=sol.method)
    sol = with_reasons(huge, np.full(n, DIVERGED, dtype=object))
    return TmaResult(**{**{f: getattr(result, f) for f in result.__slots__}, "solution": sol})


def test_tables_blank_the_range_of_undetermined_imm_rows_like_ml_rows():
    ml, seq = result_of(method="ml"), diverged(result_of())
    df = targets_table(SimpleNamespace(targets=[target(ml, seq)]))
    imm, mlr = df[df["method"] == "imm-mgekf"], df[df["method"] == "ml"]
    assert imm["range_m"].isna().all() and imm["speed_kn"].isna().all() and imm["x_std_m"].isna().all()
    assert (imm["undetermined_reason"] == DIVERGED).all() and not imm["range_determined"].any()
    assert mlr["range_m"].to_numpy() == pytest.approx(10_000.0) and (mlr["undetermined_reason"] == "").all()
    # and the other way round
    df = targets_table(SimpleNamespace(targets=[target(diverged(result_of(method="ml")), result_of())]))
    assert df[df["method"] == "ml"]["range_m"].isna().all()
    assert df[df["method"] == "imm-mgekf"]["range_m"].to_numpy() == pytest.approx(10_000.0)


def test_the_summary_line_prints_no_number_for_an_undetermined_range():
    line = target_line(target(result_of(method="ml"), diverged(result_of())))
    ml_part, imm_part = line.split("; IMM-MGEKF ")
    assert "range 10.00 ± 0.30 km" in ml_part
    assert imm_part == "range NOT DETERMINED (diverged)"
    line = target_line(target(diverged(result_of(method="ml")), result_of()))
    ml_part, imm_part = line.split("; IMM-MGEKF ")
    assert "range NOT DETERMINED (diverged) by this record (ML)" in ml_part and "km" not in ml_part.split("deg, ")[-1]
    assert imm_part == "range 10.00 ± 0.30 km"


def test_a_filter_that_fails_numerically_gives_a_diverged_answer(monkeypatch):
    from sonartrack.core.errors import InputError
    from sonartrack.systems.passive import targets as tg
    from sonartrack.tma.settings import ImmSettings, SequentialSettings, VerdictSettings

    def failing(record, sensor, settings, **kw):
        raise InputError("the imm-mgekf filter failed numerically at t = 30 s")

    monkeypatch.setattr(tg, "solve_tma", failing)
    stages = SimpleNamespace(settings=SimpleNamespace(ml_correlation_inflation=True, sigma_freq_floor_hz=0.02,
                                                      verdict=VerdictSettings()),
                             imm=ImmSettings(), sequential=SequentialSettings())
    t = np.arange(0.0, 100.0, 10.0)
    sensor = OwnshipTrack(time_s=t, x_m=np.zeros(10), y_m=np.zeros(10))
    res = tg._sequential(t, np.full(10, 0.3), None, sensor, np.deg2rad(0.5), stages)
    assert list(res.solution.reasons()) == [DIVERGED] * 10 and res.warnings[0].endswith("at t = 30 s")
    line = target_line(target(result_of(method="ml"), res))
    assert line.endswith("; IMM-MGEKF range NOT DETERMINED (diverged)")


def test_the_chains_verdict_settings_reach_the_tma():
    """[verdict] of the passive settings tree is the one the targets' TMA runs with (declared once, handed down)."""
    from sonartrack.systems.passive import targets as tg
    from sonartrack.tma.settings import ImmSettings, SequentialSettings, VerdictSettings

    verdict = VerdictSettings(max_range_m=12_345.0, nis_window=7)
    stages = SimpleNamespace(settings=SimpleNamespace(ml_correlation_inflation=True, sigma_freq_floor_hz=0.02,
                                                      verdict=verdict),
                             imm=ImmSettings(), sequential=SequentialSettings())
    tma = tg._tma_settings("imm-mgekf", np.deg2rad(0.5), stages, None)
    assert tma.verdict.max_range_m == 12_345.0 and tma.verdict.nis_window == 7


def _solution(t, xy_last, v=(0.0, 0.0), pos_sd_m=300.0):
    n = len(t)
    state = np.tile([xy_last[0], xy_last[1], v[0], v[1]], (n, 1))
    cov = np.tile(np.diag([pos_sd_m**2, pos_sd_m**2, 1.0, 1.0]), (n, 1, 1))
    own = OwnshipTrack(time_s=t, x_m=np.zeros(n), y_m=np.zeros(n))
    return TmaResult(solution=TmaSolution(time_s=t, state=state, covariance=cov, method="ml"),
                     record=BearingRecord(time_s=t, bearing_rad=np.zeros(n)), ownship=own,
                     settings=TmaSettings(method="ml"))


def test_the_filter_takes_the_batch_mls_reason_when_the_record_does_not_determine_the_range():
    from sonartrack.systems.passive.targets import batch_held

    t = np.arange(10.0) * 10.0
    ml = _solution(t, (0.0, 10_000.0))
    ml = TmaResult(**{**{f: getattr(ml, f) for f in ml.__slots__},
                      "solution": with_reasons(ml.solution, np.full(10, UNOBSERVABLE, object))})
    seq = _solution(t, (0.0, 10_000.0))
    seq = TmaResult(**{**{f: getattr(seq, f) for f in seq.__slots__},
                       "solution": with_reasons(seq.solution, np.array([DIVERGED] + [""] * 9, object))})
    got = batch_held(seq, ml).solution
    assert got.reasons().tolist() == [DIVERGED] + [UNOBSERVABLE] * 9 and not got.range_flags().any()


def test_the_filter_agrees_with_the_batch_ml_carried_to_its_last_time_or_is_not_determined():
    from sonartrack.systems.passive.targets import batch_held
    from sonartrack.tma.verdict import DISAGREES_WITH_BATCH

    # ML: last row at 90 s, 100 m/s east; the filter's last row at 100 s, where the ML is at x = 1000 m.
    # Var of the x difference: 300^2 (ML, + 10^2 * 1 from its velocity) + 300^2 (filter) = 180100 m^2, sd 424.4 m;
    # the 99.9 % point of chi-square(2) is 13.82, so up to 3.717 sd = 1577 m apart is agreement
    ml = _solution(np.arange(10.0) * 10.0, (0.0, 10_000.0), v=(100.0, 0.0))
    t = np.arange(11.0) * 10.0
    # 1500 m past the carried ML agrees (without carrying it, 2500 m from the ML's last row would not)
    assert batch_held(_solution(t, (1000.0 + 1500.0, 10_000.0)), ml).solution.range_flags().all()
    far = batch_held(_solution(t, (1000.0 + 1650.0, 10_000.0)), ml)
    assert far.solution.reasons().tolist() == [""] * 10 + [DISAGREES_WITH_BATCH]
    assert "1650 m from the batch ML's" in far.warnings[-1]
    assert not batch_held(_solution(t, (1000.0 - 1650.0, 10_000.0)), ml).solution.range_flags()[-1]
    assert batch_held(_solution(t, (1000.0 - 1500.0, 10_000.0)), ml).solution.range_flags().all()
