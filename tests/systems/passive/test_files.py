"""The passive chain on files (systems/passive/files.py), as `passive` and every `survey` recording read them: the
same recording as one float WAV with nav.csv, and as a folder of 24-bit files with its calibration and an NMEA log
of the ship, gives the same targets and the same levels in dB re 1 uPa; a gap is blank in the record and named in
a warning; navigation kinds told apart by suffix or content."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.errors import InputError
from sonartrack.systems.passive.files import navigation_kind, run_passive_recording
from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.recording_layout import make_layout
from sonartrack.systems.simulate.settings import PassiveSceneSettings

SCENE = PassiveSceneSettings(duration_s=180.0, seed=2)
SETTINGS = PassiveSettings(spacing_m=2.5)


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    d = tmp_path_factory.mktemp("passive-files")
    write_scene(SCENE, d / "float", only="passive")
    write_scene(SCENE, d / "parts", only="passive", layout=make_layout("wav24", split_s=60, nmea=True))
    write_scene(SCENE, d / "gap", only="passive", layout=make_layout("wav24", split_s=60, gap_s=10))
    return d


def test_folder_of_24_bit_files_with_nmea_and_calibration_is_the_float_recording(scenes):
    a = run_passive_recording(scenes / "float" / "recording.wav", scenes / "float" / "nav.csv", SETTINGS)
    b = run_passive_recording(scenes / "parts" / "recording", scenes / "parts" / "nav.nmea", SETTINGS,
                              calibration=scenes / "parts" / "calibration.toml",
                              tow_length_m=SCENE.array.tow_length_m)
    assert len(b.recording.files) == 3 and not b.recording.gaps
    assert len(a.result.targets) == len(b.result.targets) >= 1
    # the same peaks: integer samples 80 dB below the noise do not move a beam
    pa, pb = a.result.record.peaks, b.result.record.peaks
    np.testing.assert_allclose(pb.bearing_deg, pa.bearing_deg, atol=0.05)
    # levels in dB re 1 uPa: 73 dB/Hz ambient over 950 Hz is 102.8 dB, the ships add a few
    np.testing.assert_allclose(b.level_db, a.level_db, atol=0.01)
    assert 102.0 < np.median(a.level_db) < 115.0


def test_a_gap_is_blank_and_named(scenes):
    run = run_passive_recording(scenes / "gap" / "recording", scenes / "float" / "nav.csv", SETTINGS,
                                calibration=scenes / "gap" / "calibration.toml")
    window_s = run.result.settings.window_s
    centres = (np.arange(run.level_db.size) + 0.5) * window_s
    in_gap = (centres > 60.0) & (centres < 70.0)
    assert in_gap.any() and np.isnan(run.level_db[in_gap]).all() and np.isfinite(run.level_db[~in_gap]).all()
    t = run.result.record.peaks.time_s
    assert not ((t > 60.0) & (t < 70.0)).any() and (t > 70.0).any()
    assert any("gap of 10.000 s at 60.000..70.000 s" in w for w in run.result.warnings)


def test_the_command_reads_a_folder_an_nmea_log_and_a_calibration(scenes, capsys):
    out = scenes / "cli"
    code = main(["passive", "--wav", str(scenes / "parts" / "recording"), "--nav", str(scenes / "parts" / "nav.nmea"),
                 "--calibration", str(scenes / "parts" / "calibration.toml"), "--spacing", "2.5", "--tow-length",
                 str(SCENE.array.tow_length_m), "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    levels = pd.read_csv(out / "levels.csv")
    assert list(levels.columns) == ["time_s", "level_db_re_1upa"] and levels["level_db_re_1upa"].between(90, 130).all()


def test_navigation_kinds(tmp_path):
    (tmp_path / "log.txt").write_text("12:00:01 $GPRMC,120000.00,A,5000.0,N,00400.0,W,6.0,0.0,170524,,,A*00\n")
    (tmp_path / "nav").write_text("time_s,x_m,y_m,heading_deg\n0,0,0,0\n")
    (tmp_path / "track").write_text('<?xml version="1.0"?>\n<gpx version="1.1"></gpx>\n')
    (tmp_path / "notes.dat").write_text("hello\n")
    assert [navigation_kind(tmp_path / n) for n in ("log.txt", "nav", "track")] == ["nmea", "table", "gpx"]
    with pytest.raises(InputError, match="neither a CSV"):
        navigation_kind(tmp_path / "notes.dat")
    with pytest.raises(InputError, match="navigation file not found"):
        navigation_kind(tmp_path / "none.nmea")


def test_a_gpx_track_of_the_ship_runs_the_chain(scenes, tmp_path):
    """The NMEA log's fixes as GPX (no heading: the direction of motion is the heading): the same recording gives
    the same peaks (the front end does not use the navigation) and the ship's x/y as the NMEA log's."""
    from sonartrack.io.gpx import write_gpx
    from sonartrack.io.nmea import read_nmea

    write_gpx(tmp_path / "ship.gpx", read_nmea(scenes / "parts" / "nav.nmea").track)
    kw = {"calibration": scenes / "parts" / "calibration.toml", "tow_length_m": SCENE.array.tow_length_m}
    g = run_passive_recording(scenes / "parts" / "recording", tmp_path / "ship.gpx", SETTINGS, **kw)
    n = run_passive_recording(scenes / "parts" / "recording", scenes / "parts" / "nav.nmea", SETTINGS, **kw)
    np.testing.assert_array_equal(g.result.record.peaks.bearing_deg, n.result.record.peaks.bearing_deg)
    np.testing.assert_allclose(g.result.nav.x_m, n.result.nav.x_m, atol=0.01)
    np.testing.assert_allclose(g.result.nav.y_m, n.result.nav.y_m, atol=0.01)
    assert len(g.result.targets) >= 1


def test_span_blocks_are_the_recordings_values_in_float32_and_calibrated_in_float64(tmp_path):
    """A float32 recording's windows come as float32 holding the float64 reader's values; scaled to pascals they are
    the float64 product; the level is 10 log10(mean p^2 / (1 uPa)^2) (hand formula, float64; the run sums in the
    block's own precision, within 1e-4 dB of it, far below the 0.01 dB levels.csv prints)."""
    from sonartrack.io.recording_sequence import open_sequence
    from sonartrack.io.recording_writer import recording_writer
    from sonartrack.io.wav_blocks import iter_wav_blocks
    from sonartrack.systems.passive.files import SpanBlocks

    x = np.random.default_rng(1).uniform(-0.5, 0.5, (4, 3000))
    with recording_writer(tmp_path / "r.wav", 4, 1000.0, "float32") as w:
        w.write(x)
    want = list(iter_wav_blocks(tmp_path / "r.wav", 1000))
    seq = open_sequence(tmp_path / "r.wav")
    plain = SpanBlocks(seq, 1000, 3, None)
    scale = np.array([1.0, 2.0, 0.5, 3e-3])
    scaled = SpanBlocks(seq, 1000, 3, scale)
    for a, b, ref in zip(plain(), scaled(), want, strict=True):
        assert a.dtype == np.float32 and b.dtype == np.float64
        np.testing.assert_array_equal(a.astype(float), ref)
        np.testing.assert_array_equal(b, ref * scale[:, None])
    for run, s in ((plain, np.ones(4)), (scaled, scale)):
        hand = [10.0 * np.log10(np.mean((r * s[:, None]) ** 2) / 1e-12) for r in want]
        np.testing.assert_allclose(run.level_db, hand, rtol=0, atol=1e-4)


def test_tables_are_the_dataframes_bytes_and_a_run_imports_no_pandas(scenes, tmp_path):
    """The tables are written without pandas (its import is a tenth of a short run's time): the same bytes as the
    DataFrames of the same columns written by pandas, and a run with its tables imports no pandas."""
    import subprocess
    import sys

    from sonartrack.systems.passive.files import levels_table, lines_table, write_passive_tables
    from sonartrack.systems.passive.tables import peaks_table, targets_table

    folder = scenes / "float"
    run = run_passive_recording(folder / "recording.wav", folder / "nav.csv", SETTINGS)
    res = run.result
    paths = write_passive_tables(res, tmp_path, run.level_db)
    targets = targets_table(res)
    targets.insert(1, "origin", np.where(targets["target_id"].isin(list(res.narrowband_target_ids or ())),
                                         "narrowband", "broadband"))
    frames = {"peaks.csv": (peaks_table(res.record), None), "bearing_tracks.csv": (res.tracks.to_frame(), None),
              "targets.csv": (targets, None), "levels.csv": (levels_table(run.level_db, res.settings.window_s), "%.2f"),
              "lines.csv": (lines_table(res), None)}
    assert sorted(p.name for p in paths) == sorted(frames) and len(targets) > 0
    for p in paths:
        frame, fmt = frames[p.name]
        assert p.read_text() == frame.to_csv(index=False, float_format=fmt), p.name
    code = ("import sys; from sonartrack.systems.passive.files import run_passive_recording, write_passive_tables; "
            "from sonartrack.systems.passive.settings import PassiveSettings; "
            f"run = run_passive_recording({str(folder / 'recording.wav')!r}, {str(folder / 'nav.csv')!r}, "
            "PassiveSettings(spacing_m=2.5)); "
            f"write_passive_tables(run.result, {str(tmp_path / 'again')!r}, run.level_db); "
            "print('pandas' in sys.modules, 'pyarrow' in sys.modules)")
    (tmp_path / "again").mkdir()
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]
    for p in paths:
        assert (tmp_path / "again" / p.name).read_bytes() == p.read_bytes()


def test_window_level_is_the_mean_square_in_db():
    """_level_db against the closed form and against a float64 sum: a constant block of a pascals is
    20 log10(a / 1e-6) dB; a float32 block with a large offset (the hard case for a float32 sum) within 1e-4 dB of
    the float64 mean square, in either memory order; silence is -inf."""
    from sonartrack.systems.passive.files import _level_db

    assert _level_db(np.full((4, 1000), 0.5, np.float32)) == pytest.approx(20.0 * np.log10(0.5 / 1e-6), abs=1e-9)
    rng = np.random.default_rng(3)
    block = (rng.standard_normal((32, 8000)) * 0.01 + 2.0).astype(np.float32)
    exact = 10.0 * np.log10(np.mean(block.astype(np.float64) ** 2) / 1e-12)
    assert _level_db(block) == pytest.approx(exact, abs=1e-4)
    assert _level_db(np.asfortranarray(block)) == pytest.approx(exact, abs=1e-4)
    assert _level_db(np.zeros((2, 10), np.float32)) == -np.inf
