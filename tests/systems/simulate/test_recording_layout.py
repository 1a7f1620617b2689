"""simulate's recording layouts (systems/simulate/recording_layout.py): the default recording.wav byte for byte
what io/wav_writer.py writes of the same blocks; 24-bit files in a folder with a gap, read back by
io/recording_sequence.py with their calibration as the float samples; the NMEA log back to the scene's x/y;
FLAC of 16 channels, a gap without a second file and clipped integer samples refused with nothing written."""

from __future__ import annotations

from contextlib import ExitStack
from datetime import UTC, datetime

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.errors import InputError
from sonartrack.io.calibration import read_calibration
from sonartrack.io.nmea import navigation_from_track, read_nmea
from sonartrack.io.recording_sequence import iter_sequence_blocks, open_sequence
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info
from sonartrack.io.wav_writer import wav_block_writer
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.recording_layout import (
    FULL_SCALE_PA,
    LayoutWriter,
    check_layout,
    file_spans,
    make_layout,
)
from sonartrack.systems.simulate.run import simulate_passive
from sonartrack.systems.simulate.settings import PassiveSceneSettings

SCENE = PassiveSceneSettings(duration_s=25.0, sample_rate_hz=2000.0, seed=3)
START = datetime(2025, 2, 3, 4, 5, 6, tzinfo=UTC)


def test_default_recording_is_the_plain_wav_writers_bytes(tmp_path):
    write_scene(SCENE, tmp_path / "a", only="passive")
    with wav_block_writer(tmp_path / "direct.wav", SCENE.array.elements, SCENE.sample_rate_hz) as w:
        for block in simulate_passive(SCENE).recording_blocks():
            w.write(block)
    assert (tmp_path / "a" / "recording.wav").read_bytes() == (tmp_path / "direct.wav").read_bytes()
    assert not (tmp_path / "a" / "recording").exists() and not (tmp_path / "a" / "calibration.toml").exists()


@pytest.fixture(scope="module")
def split(tmp_path_factory):
    d = tmp_path_factory.mktemp("layout")
    write_scene(SCENE, d / "float", only="passive")
    layout = make_layout("wav24", split_s=10, gap_s=3, nmea=True, start_utc="2025-02-03T04:05:06Z", manifest=True)
    write_scene(SCENE, d / "split", only="passive", layout=layout)
    return d


def test_split_files_are_named_by_start_and_leave_the_gap(split):
    names = sorted(p.name for p in (split / "split" / "recording").iterdir())
    # 0..10 s, 13..20 s (the first 3 s of the second file left out), 20..25 s
    assert names == ["rec_20250203_040506.wav", "rec_20250203_040519.wav", "rec_20250203_040526.wav"]
    seq = open_sequence(split / "split" / "recording")
    assert seq.start_utc == START and seq.time_source == "names" and seq.frames == 25 * 2000
    assert [(g.start_s, g.end_s) for g in seq.gaps] == [(10.0, 13.0)] and not seq.overlaps
    assert all(f.info.sample_format == "int24" for f in seq.files)


def test_24_bit_files_with_their_calibration_are_the_float_pascals(split):
    """Step 100 Pa / 2^23: the calibrated samples are within half a step of the float recording's."""
    seq = open_sequence(split / "split" / "recording")
    pa = read_calibration(split / "split" / "calibration.toml").pa_per_unit(seq.channels)
    np.testing.assert_allclose(pa, FULL_SCALE_PA, rtol=1e-12)
    floats = np.concatenate(list(iter_wav_blocks(read_wav_info(split / "float" / "recording.wav"), 2000)), axis=1)
    seen = 0
    for t, block in iter_sequence_blocks(seq, 2000):
        k = int(round(t * 2000))
        assert not 10 * 2000 <= k < 13 * 2000  # nothing from the gap
        np.testing.assert_allclose(block * pa[:, None], floats[:, k:k + 2000], rtol=0,
                                   atol=FULL_SCALE_PA * 2.0**-24 * 1.0001)
        seen += 1
    assert seen == 22


def test_nmea_log_is_the_ship_track_in_utc(split):
    log = read_nmea(split / "split" / "nav.nmea")
    assert log.counts.bad_checksum == 0 and log.track.heading_source == "HDT"
    nav, _ = navigation_from_track(log.track, START)
    want = pd.read_csv(split / "split" / "nav.csv")
    np.testing.assert_allclose(nav.time_s, want["time_s"], atol=0.005)
    np.testing.assert_allclose(nav.x_m, want["x_m"] - want["x_m"][0], atol=0.01)  # projected about the first fix
    np.testing.assert_allclose(nav.y_m, want["y_m"] - want["y_m"][0], atol=0.01)
    np.testing.assert_allclose(np.rad2deg(nav.heading_rad) % 360, want["heading_deg"] % 360, atol=0.01)


def test_manifest_line_names_the_files(split):
    row = pd.read_csv(split / "split" / "manifest.csv").iloc[0]
    assert (row["name"], row["recording"], row["navigation"], row["calibration"]) == \
        ("split", "recording/", "nav.nmea", "calibration.toml")
    assert row["spacing_m"] == SCENE.spacing_m and row["tow_length_m"] == SCENE.array.tow_length_m


def test_file_spans_and_layout_checks():
    lay = make_layout("flac", split_s=60, gap_s=10)
    assert file_spans(lay, 150 * 4, 4.0) == [(0, 240), (280, 480), (480, 600)]
    with pytest.raises(InputError, match="at most 8 channels"):
        check_layout(lay, 16, 150.0)
    check_layout(lay, 8, 150.0)
    with pytest.raises(InputError, match="nothing of the second file"):
        check_layout(make_layout("wav", split_s=60, gap_s=60), 8, 300.0)
    with pytest.raises(InputError, match="needs --split-s"):
        make_layout("wav", gap_s=5)
    with pytest.raises(InputError, match="whole number of seconds"):
        make_layout("wav", split_s=0.5)
    with pytest.raises(InputError, match="unknown --format"):
        make_layout("mp3")


def test_flac_of_sixteen_channels_is_refused_before_anything_is_written(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["simulate", "--duration-s", "5", "--format", "flac", "--out", str(out)]) == 2
    assert "at most 8 channels" in capsys.readouterr().err and not out.exists()


def test_a_clipped_integer_sample_is_refused_and_no_file_is_left(tmp_path):
    layout = make_layout("wav24", split_s=1)
    with pytest.raises(InputError, match="full scale"), ExitStack() as stack:
        w = LayoutWriter(tmp_path, layout, 2, 100.0, 300)
        stack.push(lambda *exc: w.close(exc[1]))
        w.write(np.zeros((2, 150)))
        w.write(np.full((2, 150), 2 * FULL_SCALE_PA))
    assert [p.name for p in (tmp_path / "recording").iterdir()] == ["rec_20240517_120000.wav"]  # the first, whole
    assert not list(tmp_path.rglob(".*"))  # no hidden half-written file
