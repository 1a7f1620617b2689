"""The survey system (systems/survey/): a manifest of simulated recordings in three forms -- one WAV, a folder of
consecutive 24-bit files with a gap, and the same WAV with an NMEA log of the ship -- plus a line naming a
missing recording; failures reported and the others run; a rerun recomputes nothing; a local Dask cluster gives
the same targets as the run in this process."""

from __future__ import annotations

import json
import math
import os
from datetime import UTC, datetime, timedelta

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.io.nmea import LocalProjection
from sonartrack.io.recording_writer import recording_writer
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info
from sonartrack.systems.survey.manifest import read_manifest
from sonartrack.systems.survey.run import run_survey

START = datetime(2024, 5, 17, 13, 45, 0, tzinfo=UTC)
SCENE = "duration_s = 150.0\n[ownship]\nturn_start_s = 20.0\n"


def _sentence(body: str) -> str:
    c = 0
    for ch in body.encode():
        c ^= ch
    return f"${body}*{c:02X}"


def _dm(deg: float, width: int, hemi: str) -> str:
    d = int(abs(deg))
    return f"{d:0{width}d}{(abs(deg) - d) * 60:09.6f},{hemi[0] if deg >= 0 else hemi[1]}"


def _nmea_from_nav(nav_csv, path):
    """The simulated ship's track as RMC + HDT sentences in UTC (from START), about 50 N 4 W."""
    nav = pd.read_csv(nav_csv)
    proj = LocalProjection(50.0, -4.0)
    lat, lon = proj.latlon(nav["x_m"].to_numpy(), nav["y_m"].to_numpy())
    lines = []
    for t, la, lo, h in zip(nav["time_s"], lat, lon, nav["heading_deg"], strict=True):
        w = START + timedelta(seconds=float(t))
        lines.append(_sentence(f"GPRMC,{w:%H%M%S}.{w.microsecond // 10000:02d},A,{_dm(la, 2, 'NS')},"
                               f"{_dm(lo, 3, 'EW')},10.0,{h % 360:.1f},{w:%d%m%y},,,A"))
        lines.append(_sentence(f"HEHDT,{h % 360:.2f},T"))
    path.write_text("\n".join(lines) + "\n")


def _split_with_gap(wav, folder):
    """The recording cut into files of 50 s, named by their start; the samples of 100..110 s left out (a gap)."""
    info = read_wav_info(wav)
    fs = int(info.sample_rate_hz)
    x = np.concatenate(list(iter_wav_blocks(info, fs)), axis=1)
    folder.mkdir()
    for a, b in [(0, 50), (50, 100), (110, 150)]:
        name = f"rec_{START + timedelta(seconds=a):%Y%m%d_%H%M%S}.wav"
        with recording_writer(folder / name, info.channels, fs, "int24", full_scale=float(np.abs(x).max()) * 1.01) \
                as w:
            w.write(x[:, a * fs: b * fs])


@pytest.fixture(scope="module")
def survey_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("survey")
    (d / "scene_in.toml").write_text(SCENE)
    assert main(["simulate", "--scene", str(d / "scene_in.toml"), "--only", "passive", "--out", str(d / "sim")]) == 0
    (d / "p.toml").write_text("min_track_s = 60.0\n")
    _split_with_gap(d / "sim" / "recording.wav", d / "parts")
    _nmea_from_nav(d / "sim" / "nav.csv", d / "ship.nmea")
    os.link(d / "sim" / "recording.wav", d / f"ship_{START:%Y%m%d_%H%M%S}.wav")  # its start time in its name
    rows = ["recording,navigation,spacing_m,settings,name,tow_length_m",
            "sim/recording.wav,sim/nav.csv,2.5,p.toml,wav,",
            "parts,sim/nav.csv,2.5,p.toml,parts,",
            f"ship_{START:%Y%m%d_%H%M%S}.wav,ship.nmea,2.5,p.toml,nmea,200",
            "nothing/here.wav,sim/nav.csv,2.5,,missing,"]
    (d / "survey.csv").write_text("\n".join(rows) + "\n")
    return d


def _targets(out, name):
    return pd.read_csv(out / "recordings" / name / "targets.csv")


def test_local_run_reports_failures_and_resumes(survey_dir):
    out = survey_dir / "out-local"
    entries = read_manifest(survey_dir / "survey.csv")
    s = run_survey(entries, out)
    assert (s.ok, s.failed, s.skipped) == (3, 1, 0)
    by = {r["name"]: r for r in s.rows}
    assert by["missing"]["status"] == "failed" and "recording not found" in by["missing"]["reason"]
    assert "\n" not in by["missing"]["reason"]
    assert by["wav"]["targets"] >= 2
    # the folder with a gap: one 10 s gap reported, its targets at the same bearings as the whole recording's
    status = json.loads((out / "recordings" / "parts" / "status.json").read_text())
    assert status["gaps"] == ["gap of 10.000 s at 100.000..110.000 s between rec_20240517_134550.wav and "
                              "rec_20240517_134650.wav"]
    assert status["recorded_s"] == pytest.approx(140.0) and status["start_utc"] == START.isoformat()
    assert by["parts"]["targets"] >= 2
    # the NMEA log: the same ship track, projected about 50 N 4 W: the same number of targets as the CSV's
    assert by["nmea"]["status"] == "ok" and by["nmea"]["targets"] == by["wav"]["targets"]
    a, b = _targets(out, "wav"), _targets(out, "nmea")
    np.testing.assert_allclose(np.sort(b["bearing_deg"].to_numpy()), np.sort(a["bearing_deg"].to_numpy()), atol=0.5)
    table = pd.read_csv(out / "survey.csv")
    assert list(table["status"]) == ["ok", "ok", "ok", "failed"]
    stamp = (out / "recordings" / "wav" / "status.json").stat().st_mtime_ns
    again = run_survey(entries, out)
    assert (again.ok, again.failed, again.skipped) == (0, 1, 3)  # the missing one is tried again, and fails
    assert (out / "recordings" / "wav" / "status.json").stat().st_mtime_ns == stamp
    assert all((f / "status.json").is_file() for f in (out / "recordings").iterdir())


def test_a_local_dask_cluster_gives_the_same_targets(survey_dir):
    entries = [e for e in read_manifest(survey_dir / "survey.csv") if e.name in ("wav", "missing")]
    local = run_survey(entries, survey_dir / "one")
    cluster = run_survey(entries, survey_dir / "two", workers=2)
    assert (local.ok, local.failed) == (cluster.ok, cluster.failed) == (1, 1)
    pd.testing.assert_frame_equal(_targets(survey_dir / "one", "wav"), _targets(survey_dir / "two", "wav"))


def test_the_command_writes_the_page_and_exits_with_the_failures(survey_dir):
    out = survey_dir / "cli"
    rows = (survey_dir / "survey.csv").read_text().splitlines()
    (survey_dir / "small.csv").write_text("\n".join([rows[0], rows[1], rows[4]]) + "\n")
    status = main(["survey", "--manifest", str(survey_dir / "small.csv"), "--out", str(out)])
    assert status == 1
    page = (out / "index.html").read_text()
    assert 'href="recordings/wav/index.html"' in page and "recording not found" in page
    assert (out / "recordings" / "wav" / "index.html").is_file() and (out / "survey_targets.png").is_file()
    assert math.isfinite(pd.read_csv(out / "survey_targets.csv")["first_s"].min())
