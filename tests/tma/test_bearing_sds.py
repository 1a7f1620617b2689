"""Each bearing's own noise sd, end to end (``BearingRecord.bearing_sd_rad``): the reference sd by hand, the ML and
the record's verdict weighing each bearing by its own sd, the legs, the file column and the CLI. Records made here
with plain numpy (not the project's simulator): a constant-velocity target seen from an ownship on three legs, with
the noise sd of each bearing drawn from a wide spread (as a line array's towards endfire)."""

import warnings

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.tma import BearingRecord, OwnshipTrack, TmaSettings, solve_tma
from sonartrack.tma.batch_ml import ml_bearings_only
from sonartrack.tma.verdict import EXCEEDS_STATED_NOISE


def _world(seed: int, sd_scale: float = 1.0):
    """(record with per-bearing sds, ownship, the target's true final position); the stated sds are the true ones
    times ``sd_scale``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3600.0 + 1e-9, 20.0)
    course = np.deg2rad(np.select([t < 1200, t < 2400], [40.0, 130.0], 20.0))
    own_v = 4.0 * np.stack([np.sin(course), np.cos(course)], -1)
    own = np.concatenate([[[0.0, 0.0]], np.cumsum(own_v[:-1] * 20.0, axis=0)])
    target = np.array([6000.0, 9000.0]) + np.outer(t, [-3.0, 1.5])
    d = target - own
    sd = np.deg2rad(np.where(rng.random(len(t)) < 0.2, rng.uniform(2.0, 6.0, len(t)), rng.uniform(0.2, 0.5, len(t))))
    z = np.arctan2(d[:, 0], d[:, 1]) + sd * rng.standard_normal(len(t))
    record = BearingRecord(time_s=t, bearing_rad=z, bearing_sd_rad=sd * sd_scale)
    return record, OwnshipTrack(time_s=t, x_m=own[:, 0], y_m=own[:, 1]), target[-1]


def test_reference_sd_by_hand():
    """sds 1 and 1/2 rad carry the information 1 + 4 = 5 of two bearings of sd sqrt(2/5)."""
    rec = BearingRecord(time_s=np.array([0.0, 1.0]), bearing_rad=np.zeros(2), bearing_sd_rad=np.array([1.0, 0.5]))
    assert rec.reference_sd_rad() == pytest.approx(np.sqrt(2.0 / 5.0))
    np.testing.assert_allclose(rec.relative_sd(), np.array([1.0, 0.5]) / np.sqrt(2.0 / 5.0))
    assert rec.until(0.5).bearing_sd_rad.tolist() == [1.0]
    assert BearingRecord(time_s=np.zeros(1), bearing_rad=np.zeros(1)).reference_sd_rad() is None


def test_ml_weighs_each_bearing_and_the_record_keeps_constant_velocity():
    """The ML is the per-bearing-weighted fit (not the equal-weight one); the record's chi-square against the stated
    sds keeps constant velocity, and the final position lies within 4 of its own sds."""
    record, own, truth = _world(1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solve_tma(record, own, TmaSettings(method="ml"))
    t = np.asarray(record.time_s)
    weighted = ml_bearings_only(record.bearing_rad, t, own.position_at(t), record.bearing_sd_rad)
    equal = ml_bearings_only(record.bearing_rad, t, own.position_at(t), record.reference_sd_rad())
    np.testing.assert_allclose(res.solution.state[0], weighted.x0, rtol=1e-6, atol=1e-3)
    assert np.hypot(*(weighted.x0[:2] - equal.x0[:2])) > 1.0  # the weights matter on this record
    assert res.solution.range_flags()[-1], res.notes
    e = res.solution.state[-1, :2] - truth
    assert e @ np.linalg.solve(res.solution.covariance[-1][:2, :2], e) < 16.0


def test_sds_stated_too_small_are_rejected():
    """The same kind of record with its sds stated 3 times too small: the residuals exceed them, nothing determined,
    and the reason says so."""
    record, own, _ = _world(2, sd_scale=1.0 / 3.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solve_tma(record, own, TmaSettings(method="ml"))
    assert not res.solution.range_flags().any()
    assert EXCEEDS_STATED_NOISE in res.solution.reasons()[-1]
    assert "times the stated bearing sds" in res.solution.reasons()[-1]


def test_a_second_sd_is_refused_and_bad_sds_too():
    record, own, _ = _world(3)
    with pytest.raises(InputError, match="leave out one of the two"):
        solve_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=1.0))
    bad = BearingRecord(time_s=record.time_s, bearing_rad=record.bearing_rad,
                        bearing_sd_rad=np.where(np.arange(len(record.time_s)) == 5, 0.0, record.bearing_sd_rad))
    with pytest.raises(InputError, match="not a positive number"):
        solve_tma(bad, own, TmaSettings(method="ml"))
    short = BearingRecord(time_s=record.time_s, bearing_rad=record.bearing_rad,
                          bearing_sd_rad=record.bearing_sd_rad[:3])
    with pytest.raises(InputError, match="one per bearing"):
        solve_tma(short, own, TmaSettings(method="ml"))


def test_legs_use_the_sds_given():
    """The leg solution runs on the record's own sds (given: no estimate), and says so."""
    from sonartrack.tma.leg_solution import solve_legs

    record, own, _ = _world(4)
    legs = solve_legs(record, own, 1.0, given=False)
    assert legs.per_bearing and legs.sigma_estimate is None
    assert legs.sigma_rad == pytest.approx(record.reference_sd_rad())
    assert "each bearing's own given" in legs.lines()[0]
