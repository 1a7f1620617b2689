"""Time to confirm, track segments and identity switches per target (metrics/track_quality.py) on hand-made
tracks whose answers are counted by hand."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.metrics.track_quality import associate_tracks, identity_switches, time_to_confirm, track_segments

T = np.arange(10) * 30.0  # ten scans, 30 s apart


def table(rows):
    """(time, id, x, y) rows -> time (N,), id (N,), pos (N, 2)."""
    a = np.array(rows, float).reshape(-1, 4)
    return a[:, 0], a[:, 1].astype(int), a[:, 2:]


def truths():
    """Target 0 along y = 0 at every scan; target 1 along y = 1000 from scan 2 on."""
    rows = [(t, 0, 10.0 * k, 0.0) for k, t in enumerate(T)]
    rows += [(t, 1, 10.0 * k, 1000.0) for k, t in enumerate(T) if k >= 2]
    return table(rows)


def tracks():
    """Target 0: track 5 at scans 2-4, nothing at 5, track 5 again at 6, track 8 at 7-9 (two segments of 5, one
    of 8: 3 segments, 1 switch). Target 1: track 6 from scan 4 on (confirmed from 5), a clutter track 9 far away."""
    rows, confirmed = [], []
    for k, t in enumerate(T):
        if k in (2, 3, 4, 6):
            rows.append((t, 5, 10.0 * k + 3, 4.0)), confirmed.append(True)
        if k >= 7:
            rows.append((t, 8, 10.0 * k - 6, -8.0)), confirmed.append(True)
        if k >= 4:
            rows.append((t, 6, 10.0 * k, 1010.0)), confirmed.append(k >= 5)
        rows.append((t, 9, 5000.0, 5000.0)), confirmed.append(True)
    return (*table(rows), np.array(confirmed))


def test_hand_made_tracks():
    tt, ti, tx = truths()
    et, ei, ex, conf = tracks()
    a = associate_tracks(tt, ti, tx, et, ei, ex, gate=100.0, confirmed=conf)
    assert list(a.truth_ids) == [0, 1]
    np.testing.assert_array_equal(a.track_of[:, 0], [-1, -1, 5, 5, 5, -1, 5, 8, 8, 8])
    np.testing.assert_array_equal(a.track_of[:, 1], [-1, -1, -1, -1, -1, 6, 6, 6, 6, 6])  # 6 confirmed at scan 5
    np.testing.assert_allclose(time_to_confirm(a), [60.0, 90.0])  # scan 2 - scan 0; scan 5 - scan 2
    np.testing.assert_array_equal(track_segments(a), [3, 1])
    np.testing.assert_array_equal(identity_switches(a), [1, 0])


def test_unconfirmed_rows_count_once_confirmed():
    tt, ti, tx = truths()
    et, ei, ex, _ = tracks()
    a = associate_tracks(tt, ti, tx, et, ei, ex, gate=100.0)  # every row confirmed: track 6 holds from scan 4
    np.testing.assert_allclose(time_to_confirm(a), [60.0, 60.0])


def test_a_target_never_held_and_a_gate_too_small():
    tt, ti, tx = truths()
    et, ei, ex, conf = tracks()
    a = associate_tracks(tt, ti, tx, et, ei, ex, gate=1.0, confirmed=conf)  # every track > 1 m away
    assert np.isnan(time_to_confirm(a)).all()
    np.testing.assert_array_equal(track_segments(a), [0, 0])
    np.testing.assert_array_equal(identity_switches(a), [0, 0])


def test_switch_back_and_forth_counts_each_change():
    """Held by 1, 2, 1, 2 with no gap: 4 segments, 3 switches."""
    tt, ti, tx = table([(t, 0, 0.0, 0.0) for t in T[:4]])
    et, ei, ex = table([(t, i, 1.0, 0.0) for t, i in zip(T[:4], [1, 2, 1, 2], strict=True)])
    a = associate_tracks(tt, ti, tx, et, ei, ex, gate=10.0)
    np.testing.assert_array_equal(track_segments(a), [4])
    np.testing.assert_array_equal(identity_switches(a), [3])
    np.testing.assert_allclose(time_to_confirm(a), [0.0])


def test_two_tracks_on_one_target_hold_it_by_the_nearer():
    tt, ti, tx = table([(0.0, 0, 0.0, 0.0)])
    et, ei, ex = table([(0.0, 3, 6.0, 0.0), (0.0, 4, 2.0, 0.0)])
    assert associate_tracks(tt, ti, tx, et, ei, ex, gate=10.0).track_of[0, 0] == 4


def test_track_ids_must_be_non_negative_integers():
    tt, ti, tx = truths()
    with pytest.raises(InputError, match="track ids"):
        associate_tracks(tt, ti, tx, [0.0], [-2], [[0.0, 0.0]], gate=10.0)
