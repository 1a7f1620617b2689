"""The track system from Python: typed records in and out, and the same tables as ``sonartrack track`` writes."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.cli import main
from sonartrack.io.contacts import Contacts
from sonartrack.systems.track.run import ContactTrackResult, PeakTrackResult, run_contacts, run_peaks
from sonartrack.systems.track.settings import ContactsTrackSettings, PeaksTrackSettings
from sonartrack.tracking.run import CONTACT_TRACK_COLUMNS, PEAK_TRACK_COLUMNS, BearingTracks, PositionTracks

SIGMA_M = 20.0
#: two targets at constant velocity, 7 km apart: start (x, y) m and velocity (vx, vy) m/s
TARGETS = np.array([[0.0, 0.0, 5.0, 0.0], [5000.0, 5000.0, -3.0, 2.0]])
SCAN_S = 10.0
N_SCANS = 30


def _truth(t):
    return TARGETS[:, :2] + t * TARGETS[:, 2:]


@pytest.fixture(scope="module")
def two_targets():
    """Both targets detected every scan with 20 m errors per axis, no clutter, as Contacts and as a CSV table."""
    rng = np.random.default_rng(7)
    t = np.repeat(np.arange(N_SCANS) * SCAN_S, 2)
    z = np.concatenate([_truth(tk) for tk in np.arange(N_SCANS) * SCAN_S]) + rng.normal(0, SIGMA_M, (len(t), 2))
    R = np.tile(np.eye(2) * SIGMA_M**2, (len(t), 1, 1))
    table = pd.DataFrame({"time_s": t, "x_m": z[:, 0], "y_m": z[:, 1], "var_x_m2": R[:, 0, 0], "var_y_m2": R[:, 1, 1],
                          "cov_xy_m2": R[:, 0, 1]})
    return Contacts(t, z, R), table


def test_contacts_give_typed_tracks_on_both_targets(two_targets):
    data, _ = two_targets
    result = run_contacts(data, ContactsTrackSettings())
    assert isinstance(result, ContactTrackResult) and isinstance(result.tracks, PositionTracks)
    tr = result.tracks
    n = len(tr)
    assert n > 0 and tr.x.shape == (n, 4) and tr.mode_prob.shape == (n, 2)  # default: two IMM modes
    for name in ("time_s", "track_id", "confirmed", "existence", "sd_x_m", "sd_y_m"):
        assert getattr(tr, name).shape == (n,), name
    assert tr.confirmed.dtype == bool and np.allclose(tr.mode_prob.sum(axis=1), 1.0)
    last = tr.time_s == tr.time_s.max()
    ends = tr.x[last & tr.confirmed, :2]
    truth = _truth(tr.time_s.max())
    # each target has a confirmed track within 5 sigma at the last scan, and there are exactly two
    assert len(ends) == 2 and all(np.min(np.hypot(*(ends - p).T)) < 5 * SIGMA_M for p in truth)
    assert result.n_confirmed == 2
    assert result.summary() == f"{N_SCANS} scans, {2 * N_SCANS} contacts -> 2 confirmed track(s)"
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.time_s = tr.time_s  # the record is frozen


def test_position_frame_is_the_record(two_targets):
    tr = run_contacts(two_targets[0]).tracks
    frame = tr.to_frame()
    assert list(frame.columns) == CONTACT_TRACK_COLUMNS + ["mode_prob_0", "mode_prob_1"]
    np.testing.assert_array_equal(frame[["x_m", "y_m", "vx_mps", "vy_mps"]].to_numpy(), tr.x)
    assert (frame["status"] == "confirmed").to_numpy().tolist() == tr.confirmed.tolist()
    assert set(frame["status"]) == {"confirmed", "tentative"}
    np.testing.assert_array_equal(frame["mode_prob_1"].to_numpy(), tr.mode_prob[:, 1])


def test_confirmed_only_keeps_the_confirmed_rows(two_targets):
    everything = run_contacts(two_targets[0]).tracks
    confirmed = run_contacts(two_targets[0], confirmed_only=True).tracks
    np.testing.assert_array_equal(confirmed.x, everything.x[everything.confirmed])
    assert confirmed.confirmed.all()


def test_cli_writes_the_systems_table(two_targets, tmp_path, capsys):
    data, table = two_targets
    table.to_csv(tmp_path / "contacts.csv", index=False)
    assert main(["track", "--contacts", str(tmp_path / "contacts.csv"), "--out", str(tmp_path / "o")]) == 0
    assert "2 confirmed track(s)" in capsys.readouterr().out
    written = pd.read_csv(tmp_path / "o" / "tracks.csv")
    pd.testing.assert_frame_equal(written, run_contacts(data).tracks.to_frame(), check_dtype=False)


@pytest.fixture(scope="module")
def two_bearings():
    """Two strong peaks per scan (40 and 120 deg, drifting 0.05 deg/s) and one weak one at a random angle."""
    rng = np.random.default_rng(3)
    rows = []
    for t in np.arange(60.0):
        for b in (40.0 + 0.05 * t, 120.0 - 0.05 * t):
            rows.append((t, b + rng.normal(0, 0.5), 20000.0 * rng.uniform(0.8, 1.2)))
        rows.append((t, rng.uniform(0, 180), 3000.0))
    t, b, a = np.array(rows).T
    return PeakRecord(t, b, a)


@pytest.mark.parametrize("associator", ["jpda_a", "jpda"])
def test_peaks_give_typed_tracks_on_both_bearings(two_bearings, associator):
    result = run_peaks(two_bearings, PeaksTrackSettings(associator=associator))
    assert isinstance(result, PeakTrackResult) and isinstance(result.tracks, BearingTracks)
    tr = result.tracks
    assert all(getattr(tr, c).shape == (len(tr),) for c in PEAK_TRACK_COLUMNS)
    last = tr.time_s == tr.time_s.max()
    ends = np.sort(tr.bearing_deg[last & tr.confirmed])
    np.testing.assert_allclose(ends, [40.0 + 0.05 * 59, 120.0 - 0.05 * 59], atol=1.5)
    assert result.name == associator.upper().replace("_", "-")
    assert result.summary().startswith(f"track {result.name.lower()}: 60 scans, 180 peaks, 2 confirmed track(s)")


def test_cli_writes_the_systems_peak_table(two_bearings, tmp_path, capsys):
    r = two_bearings
    pd.DataFrame({"time_s": r.time_s, "bearing_deg": r.bearing_deg, "amplitude": r.amplitude}).to_csv(
        tmp_path / "peaks.csv", index=False)
    assert main(["track", "--peaks", str(tmp_path / "peaks.csv"), "--out", str(tmp_path / "o")]) == 0
    capsys.readouterr()
    written = pd.read_csv(tmp_path / "o" / "bearing_tracks.csv")
    frame = run_peaks(r).tracks.to_frame()
    assert list(written.columns) == PEAK_TRACK_COLUMNS and len(written) == len(frame)
    pd.testing.assert_frame_equal(written, frame, check_dtype=False, rtol=1e-5)  # written to 6 digits


def test_an_empty_record_gives_empty_typed_tables():
    """No scans: zero-length arrays of the right types, and a table with the columns (a header-only CSV)."""
    empty = np.zeros(0)
    peaks = run_peaks(PeakRecord(empty, empty, empty)).tracks
    assert len(peaks) == 0 and peaks.confirmed.dtype == bool and peaks.track_id.dtype == np.int64
    assert list(peaks.to_frame().columns) == PEAK_TRACK_COLUMNS
    contacts = run_contacts(Contacts(empty, np.zeros((0, 2)), np.zeros((0, 2, 2)))).tracks
    assert contacts.x.shape == (0, 4) and contacts.mode_prob.shape == (0, 2)
    assert list(contacts.to_frame().columns) == CONTACT_TRACK_COLUMNS + ["mode_prob_0", "mode_prob_1"]
