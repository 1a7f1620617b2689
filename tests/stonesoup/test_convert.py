"""Converters between our arrays / files and Stone Soup types: round trips, state order, errors."""

from __future__ import annotations

import datetime

import numpy as np
import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

from stonesoup.models.transition.linear import (  # noqa: E402
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.types.detection import Clutter  # noqa: E402

from sonartrack.acoustics.xcorr_bearing import PeakRecord  # noqa: E402
from sonartrack.core.errors import InputError  # noqa: E402
from sonartrack.io.contacts import Contacts  # noqa: E402
from sonartrack.stonesoup import EXISTENCE, ExistenceTrack  # noqa: E402
from sonartrack.stonesoup.convert import (  # noqa: E402
    EPOCH,
    detections_from_arrays,
    detections_from_contacts,
    detections_from_peaks,
    detections_to_arrays,
    groundtruth_paths,
    groundtruth_to_arrays,
    snapshot_from_tracks,
    to_seconds,
    to_timestamp,
    tracks_from_snapshots,
)
from sonartrack.tracking.tracks import TrackSnapshot  # noqa: E402


def _contacts(rng, n=12):
    t = np.repeat([0.0, 2.0, 4.5], n // 3)
    z = rng.normal(0, 100, (n, 2))
    A = rng.normal(0, 1, (n, 2, 2))
    R = A @ np.swapaxes(A, -1, -2) + np.eye(2)
    return Contacts(t, z, R)


def _sorted_rows(z, R):
    order = np.lexsort(z.T[::-1])
    return z[order], R[order]


def test_times():
    t = to_timestamp(12.5)
    assert t == EPOCH + datetime.timedelta(seconds=12.5) and to_seconds(t) == 12.5


def test_contacts_round_trip(tmp_path):
    c = _contacts(np.random.default_rng(0))
    scans = detections_from_contacts(c)
    assert [to_seconds(ts) for ts, _ in scans] == [0.0, 2.0, 4.5]
    for (ts, dets), tk in zip(scans, [0.0, 2.0, 4.5], strict=True):
        z, R, amp = detections_to_arrays(dets)
        zs, Rs = _sorted_rows(z, R)
        ze, Re = _sorted_rows(c.z[c.time_s == tk], c.R[c.time_s == tk])
        assert np.array_equal(zs, ze) and np.array_equal(Rs, Re) and np.isnan(amp).all()
        assert all(d.timestamp == ts and d.measurement_model.mapping == (0, 2) for d in dets)
    path = tmp_path / "contacts.csv"
    path.write_text("time_s,x_m,y_m\n0,1,2\n0,3,4\n1,5,6\n")
    from_file = detections_from_contacts(path, default_sigma_m=2.0)
    z, R, _ = detections_to_arrays(from_file[1][1])
    assert np.array_equal(z, [[5.0, 6.0]]) and np.allclose(R, 4.0 * np.eye(2))


def test_peaks_in_radians_with_amplitudes():
    rec = PeakRecord(np.array([0.0, 0.0, 1.0]), np.array([30.0, 120.0, 90.0]), np.array([11.0, 12.0, 13.0]))
    scans = detections_from_peaks(rec, bearing_sigma_deg=1.0)
    z, R, amp = detections_to_arrays(sorted(scans[0][1], key=lambda d: d.metadata["amplitude"]))
    assert np.allclose(z[:, 0], np.deg2rad([30.0, 120.0])) and np.array_equal(amp, [11.0, 12.0])
    assert np.allclose(R[:, 0, 0], np.deg2rad(1.0) ** 2)
    with pytest.raises(InputError, match="bearing_sigma_deg"):
        detections_from_peaks(rec)


def test_clutter_flag_and_missing_covariance():
    scans = detections_from_arrays([0, 0], [[0, 0], [1, 1]], np.eye(2), clutter=[True, False])
    assert sorted(type(d).__name__ for d in scans[0][1]) == ["Clutter", "Detection"]
    assert sum(isinstance(d, Clutter) for d in scans[0][1]) == 1
    with pytest.raises(InputError, match="covariance"):
        detections_from_arrays([0], [[0, 0]])


def _snapshot(time_s, ids, confirmed, existence, x, P, attrs):
    n = len(ids)
    return TrackSnapshot(time_s=time_s, track_id=ids, confirmed=confirmed, existence=existence, x=x, P=P,
                         mu=np.ones((n, 1)), P_init=np.zeros((n, 4, 4)), born_s=np.zeros(n), attrs=attrs)


def _snapshots(rng):
    snaps = []
    for k, ids in enumerate([[1, 2], [1, 2, 5], [2, 5]]):
        n = len(ids)
        A = rng.normal(0, 1, (n, 4, 4))
        snaps.append(_snapshot(float(k), np.array(ids), np.array([k > 0] * n), rng.uniform(0, 1, n),
                               rng.normal(0, 10, (n, 4)), A @ np.swapaxes(A, -1, -2),
                               {"strength": rng.uniform(1, 2, n)}))
    return snaps


def test_snapshots_round_trip():
    snaps = _snapshots(np.random.default_rng(1))
    tracks = tracks_from_snapshots(snaps)
    assert sorted(t.id for t in tracks) == ["1", "2", "5"] and all(isinstance(t, ExistenceTrack) for t in tracks)
    for snap in snaps:
        back = snapshot_from_tracks(tracks, to_timestamp(snap.time_s))
        assert np.array_equal(back.track_id, snap.track_id)
        for name in ("x", "P", "existence", "confirmed"):
            assert np.array_equal(getattr(back, name), getattr(snap, name)), name
        assert np.array_equal(back.attrs["strength"], snap.attrs["strength"])
    track5 = next(t for t in tracks if t.id == "5")
    assert track5.metadatas[0][EXISTENCE] == snaps[1].existence[2]
    assert snapshot_from_tracks(tracks, to_timestamp(2.0)).born_s.tolist() == [0.0, 1.0]


def test_state_order_matches_stone_soup_constant_velocity():
    # our [x, y, vx, vy] moved by our F equals Stone Soup's [x, vx, y, vy] moved by its CV model, converted back
    x = np.array([100.0, -50.0, 3.0, 4.0])
    dt = 2.5
    F_ours = np.eye(4)
    F_ours[0, 2] = F_ours[1, 3] = dt
    snap = _snapshot(0.0, np.array([7]), np.array([True]), np.array([np.nan]), x[None], np.eye(4)[None], {})
    (track,) = tracks_from_snapshots([snap])
    model = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.1), ConstantVelocity(0.1)])
    moved = model.function(track.state, time_interval=datetime.timedelta(seconds=dt))
    track.append(type(track.state)(moved, track.covar, timestamp=to_timestamp(dt)))
    back = snapshot_from_tracks({track}, to_timestamp(dt))
    assert np.allclose(back.x[0], F_ours @ x) and np.isnan(back.existence[0])


def test_groundtruth_round_trip():
    t = np.arange(5.0)
    states = np.random.default_rng(3).normal(0, 1, (2, 5, 4))
    paths = groundtruth_paths(t, states, ids=["a", "b"])
    assert [p.id for p in paths] == ["a", "b"]
    assert float(paths[0][1].state_vector[1, 0]) == states[0, 1, 2]  # Stone Soup's vx is our entry 2
    for p, s in zip(paths, states, strict=True):
        tt, ss = groundtruth_to_arrays(p)
        assert np.array_equal(tt, t) and np.array_equal(ss, s)
    with pytest.raises(InputError, match="targets"):
        groundtruth_paths(t[:3], states)
