"""The active chain end to end on a small simulated scene, the files it writes, and its bad-input messages."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.sim.active_scene import ActiveOwnshipSettings, ActiveSceneSettings, TargetSettings
from sonartrack.systems.active.settings import ActiveSettings

STRONG = TargetSettings(name="strong", x_m=-3000.0, y_m=5500.0, course_deg=80.0, speed_kn=5.0,
                        target_strength_db=15.0)


def small_scene(targets=(STRONG,), seed=2) -> ActiveSceneSettings:
    """10 minutes of 15 s pings; the ownship turns 60 deg to port between 200 and 320 s, so the mirror of a
    target on the port side stops moving like a target."""
    return ActiveSceneSettings(duration_s=600.0, ping_interval_s=15.0, seed=seed, targets=list(targets),
                               ownship=ActiveOwnshipSettings(turn_start_s=200.0, turn_rate_deg_s=0.5))


@pytest.fixture(scope="module")
def scene_folder(tmp_path_factory):
    from sonartrack.systems.simulate.active_files import write_active_scene

    folder = tmp_path_factory.mktemp("active-scene")
    write_active_scene(small_scene(), folder)
    return folder


@pytest.fixture(scope="module")
def result(scene_folder):
    from sonartrack.systems.active.files import run_active_files

    return run_active_files(scene_folder, scene_folder / "nav.csv", ActiveSettings(spacing_m=0.5))


def _mirror(result, t, xy):
    g = result.geometry
    rx, h = g.rx_at(t), float(g.heading_at(t))
    a = np.array([np.sin(h), np.cos(h)])
    return rx + (2.0 * np.outer(a, a) - np.eye(2)) @ (np.asarray(xy) - rx)


def test_strong_target_confirmed_on_its_true_side_after_the_turn(result, scene_folder):
    from sonartrack.systems.active.scene_files import read_truth

    truth = read_truth(scene_folder / "truth.csv")
    tr = result.tracks.tracks
    late = result.ping_time_s[-5:]
    for t in late:
        true_xy = truth[np.isclose(truth.time_s, t)][["x_m", "y_m"]].to_numpy()[0]
        rows = (tr.time_s == t) & tr.confirmed
        d_true = np.hypot(*(tr.x[rows, :2] - true_xy).T)
        d_mirror = np.hypot(*(tr.x[rows, :2] - _mirror(result, t, true_xy)).T)
        assert d_true.size and d_true.min() < 1000.0, (t, d_true)
        assert not np.any(d_mirror < 1000.0), (t, d_mirror)  # the mirror track has died


def _contacts(t, xy, sigma=40.0):
    from sonartrack.systems.active.contacts import Contacts

    n = len(xy)
    return Contacts(np.zeros(n, np.int64), np.full(n, t), np.arange(n), np.ones(n, np.int8), np.asarray(xy, float),
                    np.broadcast_to(np.eye(2) * sigma**2, (n, 2, 2)).copy(), np.full(n, np.nan), np.full(n, 5000.0),
                    np.ones(n))


@pytest.mark.parametrize("merge", [None, 0.99])
def test_the_chains_tracker_merges_duplicate_tracks(merge):
    # a stray contact 60 m off the target's first contact starts a second track that then sees the same contacts:
    # without merging both are confirmed (one target, two tracks), with it one is
    from sonartrack.systems.active.contacts import ActiveGeometry
    from sonartrack.systems.active.run import ContactTracker

    geo = ActiveGeometry(np.array([-100.0, 1e4]), np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))
    trk = ContactTracker(ActiveSettings().tracker_settings(), geo, None, 1.0, None, merge)
    rng = np.random.default_rng(1)
    truth = np.array([[1000.0 + 90.0 * k, 8000.0 - 60.0 * k] for k in range(30)])
    trk.step(0.0, _contacts(0.0, [truth[0], truth[0] + [60.0, 0.0]]))
    for k in range(1, 30):
        trk.step(30.0 * k, _contacts(30.0 * k, truth[k][None] + rng.normal(0, 40.0, (1, 2))))
    tr = trk.result().tracks
    last = (tr.time_s == tr.time_s.max()) & tr.confirmed
    assert last.sum() == (2 if merge is None else 1)
    assert ActiveSettings().merge_probability == 0.99


def test_records_are_consistent(result):
    d, c = result.detections, result.contacts
    assert len(result.ping_time_s) == 40 and result.bscan.level.shape[0] == 40
    assert set(np.unique(c.side)) <= {-1, 1}
    np.testing.assert_array_equal(np.bincount(c.detection, minlength=len(d)) <= 2, True)
    assert len(result.gated_out) == len(c)
    assert set(result.stage_seconds) >= {"front end", "mftd", "tracking"}


def test_files_written_all_or_nothing(result, tmp_path):
    import pandas as pd

    from sonartrack.systems.active.files import summary_lines, write_active_tables

    files = write_active_tables(result, tmp_path / "out")
    assert sorted(p.name for p in files) == ["contacts.csv", "detections.csv", "sides.csv", "tracks.csv"]
    tracks = pd.read_csv(tmp_path / "out" / "tracks.csv")
    assert {"time_s", "track_id", "status", "existence", "x_m", "sd_x_m", "mode_prob_0", "mode_prob_1",
            "sd_vx_mps"} <= set(tracks.columns)
    contacts = pd.read_csv(tmp_path / "out" / "contacts.csv")
    assert set(contacts.side) <= {"port", "starboard"} and (contacts.var_x_m2 > 0).all()

    class Broken:  # a table that cannot be rendered: nothing may be written
        def to_csv(self, index=False):
            raise RuntimeError("cannot render")

    import sonartrack.systems.active.files as files_mod

    real = files_mod.tracks_table
    files_mod.tracks_table = lambda r: Broken()
    try:
        with pytest.raises(RuntimeError):
            write_active_tables(result, tmp_path / "out2")
    finally:
        files_mod.tracks_table = real
    assert not (tmp_path / "out2").exists() or list((tmp_path / "out2").iterdir()) == []
    lines = summary_lines(result)
    # a count line, then one line per target (a mirror pair is one target, not two tracks: targets.py)
    assert lines[0].startswith("active: ") and len(lines) > 1 and all(line.startswith("target ") for line in lines[1:])


def test_cli_runs_and_writes_the_page(scene_folder, tmp_path):
    from sonartrack.cli import main

    out = tmp_path / "cli-out"
    assert main(["active", "--pings", str(scene_folder / "pings"), "--nav", str(scene_folder / "nav.csv"),
                 "--spacing", "0.5", "--out", str(out)]) == 0
    assert {"detections.csv", "contacts.csv", "tracks.csv", "bscan.png", "tactical.png", "index.html"} <= \
        {p.name for p in out.iterdir()}


def test_bad_inputs(scene_folder, tmp_path):
    from sonartrack.systems.active.files import run_active_files

    with pytest.raises(InputError, match="spacing"):
        run_active_files(scene_folder, scene_folder / "nav.csv", ActiveSettings())
    with pytest.raises(InputError, match="channels"):
        run_active_files(scene_folder, scene_folder / "nav.csv", ActiveSettings(spacing_m=0.5, elements=8))
    with pytest.raises(InputError, match="ping_table.csv"):
        run_active_files(tmp_path, scene_folder / "nav.csv", ActiveSettings(spacing_m=0.5))
    short = tmp_path / "nav.csv"
    import pandas as pd

    pd.read_csv(scene_folder / "nav.csv").iloc[:100].to_csv(short, index=False)
    with pytest.raises(InputError, match="cover"):
        run_active_files(scene_folder, short, ActiveSettings(spacing_m=0.5))


def test_scene_without_target_gives_empty_tables_and_says_so(tmp_path):
    from sonartrack.systems.active.files import run_active_files, summary_lines, write_active_tables
    from sonartrack.systems.simulate.active_files import write_active_scene

    scene = small_scene(targets=()).model_copy(update={"duration_s": 90.0})
    write_active_scene(scene, tmp_path / "scene")
    res = run_active_files(tmp_path / "scene", tmp_path / "scene" / "nav.csv", ActiveSettings(spacing_m=0.5))
    assert not res.tracks.tracks.confirmed.any()
    assert summary_lines(res)[0].startswith("active: no confirmed track in 6 pings")
    write_active_tables(res, tmp_path / "out")


def test_contacts_point_at_their_rows_of_detections_csv(result, tmp_path):
    """contacts.csv's ``detection`` is a row of detections.csv: the row's ping and travel time are the contact's
    (the strong single-ping rows the MFTD missed are among the tracked rows; before, the index counted them but
    detections.csv listed only the MFTD's, so every contact after the first strong one pointed at another row)."""
    import pandas as pd

    from sonartrack.systems.active.files import write_active_tables

    write_active_tables(result, tmp_path)
    det = pd.read_csv(tmp_path / "detections.csv")
    con = pd.read_csv(tmp_path / "contacts.csv")
    assert set(det.detector) >= {"mftd", "single"}
    assert (det.detector == "strong").any()  # the scene has strong single-ping rows: the case that went wrong
    rows = det.iloc[con.detection.to_numpy()]
    np.testing.assert_array_equal(rows.ping.to_numpy(), con.ping.to_numpy())
    assert set(rows.detector) <= {"mftd", "strong"}
    tracked = det[det.detector != "single"]
    assert len(tracked) == len(result.detections)
