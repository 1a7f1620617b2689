"""TMA records: the ownship coverage check, cutting a record, joining solutions."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution, check_coverage


def test_coverage_errors():
    own = OwnshipTrack(time_s=np.array([0.0, 10, 20, 300, 310]), x_m=np.zeros(5), y_m=np.zeros(5))
    rec = BearingRecord(time_s=np.array([5.0, 15.0, 305.0]), bearing_rad=np.zeros(3))
    check_coverage(rec, own, max_gap_s=300)  # interpolation across the 280 s gap is allowed here
    with pytest.raises(InputError, match="gap"):
        check_coverage(BearingRecord(time_s=np.array([5.0, 150.0]), bearing_rad=np.zeros(2)), own)
    # exactly on samples: fine, whatever the gap
    check_coverage(BearingRecord(time_s=np.array([20.0, 300.0]), bearing_rad=np.zeros(2)), own)
    with pytest.raises(InputError, match="outside the ownship file's span"):
        check_coverage(BearingRecord(time_s=np.array([5.0, 311.0]), bearing_rad=np.zeros(2)), own)
    with pytest.raises(InputError, match="outside"):
        check_coverage(BearingRecord(time_s=np.array([-1.0, 5.0]), bearing_rad=np.zeros(2)), own)


def test_gap_boundary_is_inclusive():
    own = OwnshipTrack(time_s=np.array([0.0, 120.0, 241.0]), x_m=np.zeros(3), y_m=np.zeros(3))
    check_coverage(BearingRecord(time_s=np.array([60.0]), bearing_rad=np.zeros(1)), own)  # a 120 s gap: allowed
    with pytest.raises(InputError, match="121 s gap"):
        check_coverage(BearingRecord(time_s=np.array([180.0]), bearing_rad=np.zeros(1)), own)


def test_until_cuts_every_column():
    rec = BearingRecord(time_s=np.arange(5.0), bearing_rad=np.arange(5.0) / 10, frequency_hz=None,
                        snr_db=np.arange(5.0) + 10)
    head = rec.until(2.0)
    np.testing.assert_array_equal(head.time_s, [0.0, 1.0, 2.0])
    np.testing.assert_array_equal(head.bearing_rad, [0.0, 0.1, 0.2])
    np.testing.assert_array_equal(head.snr_db, [10.0, 11.0, 12.0])
    assert head.frequency_hz is None


def test_followed_by_drops_the_repeated_start_row():
    a = TmaSolution(time_s=np.array([0.0, 1.0]), state=np.zeros((2, 4)), covariance=np.zeros((2, 4, 4)), method="ml")
    b = TmaSolution(time_s=np.array([1.0, 2.0, 3.0]), state=np.ones((3, 4)), covariance=np.ones((3, 4, 4)),
                    method="ml+ekf")
    c = a.followed_by(b)
    np.testing.assert_array_equal(c.time_s, [0.0, 1.0, 2.0, 3.0])
    np.testing.assert_array_equal(c.state[:, 0], [0.0, 0.0, 1.0, 1.0])
    assert c.covariance.shape == (4, 4, 4) and c.method == "ml+ekf"
