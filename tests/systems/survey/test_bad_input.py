"""A survey with bad lines: a missing, an unreadable and a truncated recording, a navigation CSV that stops half-way,
files of one recording with different channel counts or sample rates, an NMEA log whose every checksum is wrong, and
one logged an hour after the recording.
Each is reported failed with its one-line reason in survey.csv, status.json and the page; the good recording
runs; the exit status is the number that failed; a failed recording's folder holds its status alone, and no
hidden half-written file is left anywhere."""

from __future__ import annotations

import json
import shutil
from datetime import timedelta

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.io.recording_writer import recording_writer
from sonartrack.systems.simulate.files import write_scene
from sonartrack.systems.simulate.recording_layout import make_layout, write_ship_nmea
from sonartrack.systems.simulate.settings import PassiveSceneSettings

SCENE = PassiveSceneSettings(duration_s=90.0, seed=7)
#: name -> (recording, navigation, the reason's distinctive words)
BAD = {
    "missing": ("nothing/here.wav", "sim/nav.csv", "recording not found"),
    "unreadable": ("junk.wav", "sim/nav.csv", "is not a RIFF/WAVE"),
    "truncated": ("cut.wav", "sim/nav.csv", "is truncated"),
    "short-nav": ("sim/recording/", "short.csv", "covers 0..40 s"),
    "channels": ("mixed_channels/", "sim/nav.csv", "has 4 channels at 4000 Hz but"),
    "rates": ("mixed_rates/", "sim/nav.csv", "at 2000 Hz but"),
    "bad-nmea": ("sim/recording/", "bad.nmea", "holds no valid position"),
    "nmea-an-hour-late": ("sim/recording/", "late.nmea", "covers 3600..3690 s but the recording runs 0..90 s"),
}


def _noise_file(path, channels, rate, seconds):
    x = 0.1 * np.random.default_rng(channels + rate).standard_normal((channels, int(rate * seconds)))
    with recording_writer(path, channels, rate, "float32") as w:
        w.write(x)


def _corrupt_checksums(src, dst):
    lines = []
    for line in src.read_text().splitlines():
        body, check = line.split("*")
        lines.append(f"{body}*{(int(check, 16) ^ 0x01):02X}")
    dst.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad-survey")
    write_scene(SCENE, d / "sim", only="passive", layout=make_layout("wav", nmea=True))
    (rec,) = (d / "sim" / "recording").iterdir()
    (d / "junk.wav").write_text("these are notes, not a recording\n")
    data = rec.read_bytes()
    (d / "cut.wav").write_bytes(data[: len(data) // 2])
    pd.read_csv(d / "sim" / "nav.csv").iloc[:41].to_csv(d / "short.csv", index=False)
    for folder, (c2, r2) in (("mixed_channels", (4, 4000)), ("mixed_rates", (16, 2000))):
        (d / folder).mkdir()
        _noise_file(d / folder / "rec_20240517_120000.wav", 16, 4000, 5)
        _noise_file(d / folder / "rec_20240517_120005.wav", c2, r2, 5)
    _corrupt_checksums(d / "sim" / "nav.nmea", d / "bad.nmea")
    nav = pd.read_csv(d / "sim" / "nav.csv").to_dict("series")
    write_ship_nmea(d / "late.nmea", nav, make_layout().start_utc + timedelta(hours=1))
    rows = ["name,recording,navigation,spacing_m,tow_length_m",
            f"good,sim/recording/,sim/nav.nmea,2.5,{SCENE.array.tow_length_m}"]
    rows += [f"{name},{rec_},{nav},2.5,{SCENE.array.tow_length_m}" for name, (rec_, nav, _) in BAD.items()]
    (d / "survey.csv").write_text("\n".join(rows) + "\n")
    status = main(["survey", "--manifest", str(d / "survey.csv"), "--out", str(d / "out")])
    return d, status


def test_exit_status_counts_the_failures(survey):
    _, status = survey
    assert status == len(BAD)


@pytest.mark.parametrize("name", list(BAD))
def test_each_bad_line_fails_alone_with_its_reason(survey, name):
    d, _ = survey
    table = pd.read_csv(d / "out" / "survey.csv").set_index("name")
    row = table.loc[name]
    assert row["status"] == "failed"
    assert BAD[name][2] in row["reason"] and "\n" not in row["reason"]
    folder = d / "out" / "recordings" / name
    assert [p.name for p in folder.iterdir()] == ["status.json"]  # no table of a failed run
    assert json.loads((folder / "status.json").read_text())["reason"] == row["reason"]
    assert BAD[name][2] in (d / "out" / "index.html").read_text().replace("&#x27;", "'")


def test_the_good_recording_runs_and_nothing_is_half_written(survey):
    d, _ = survey
    table = pd.read_csv(d / "out" / "survey.csv").set_index("name")
    assert table.loc["good", "status"] == "ok"
    assert len(pd.read_csv(d / "out" / "recordings" / "good" / "bearing_tracks.csv")) > 0
    assert 90 < table.loc["good", "level_db_re_1upa"] < 130  # dB re 1 uPa: 73 dB/Hz over 950 Hz is 103 dB
    assert {"targets.csv", "levels.csv", "index.html", "status.json"} <= {
        p.name for p in (d / "out" / "recordings" / "good").iterdir()}
    assert not [p for p in (d / "out").rglob(".*")]


def test_a_rerun_retries_only_the_failed(survey, capsys):
    d, _ = survey
    shutil.copytree(d / "out", d / "again")
    stamp = (d / "again" / "recordings" / "good" / "status.json").stat().st_mtime_ns
    assert main(["survey", "--manifest", str(d / "survey.csv"), "--out", str(d / "again")]) == len(BAD)
    assert f"0 ran, 1 already done, {len(BAD)} failed" in capsys.readouterr().out
    assert (d / "again" / "recordings" / "good" / "status.json").stat().st_mtime_ns == stamp
