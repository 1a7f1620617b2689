"""The survey page (report/survey_page.py) on a small survey run by ``sonartrack survey``, built as
tests/systems/survey/test_survey.py builds its own (its scene helpers and its NMEA writer reused): the same simulated
recording with its navigation table (local x/y, tuned settings) and with an NMEA log of the ship about 50 N 4 W, and
a line naming a missing recording. Checked: the summary line, the map (one track per recording, the NMEA one in
lat/lon that agrees with an independent projection of the generator's track, its targets where the table's
recording puts them), the targets table, the settings that differ from the defaults, each recording's own page,
and the filters run in headless Chromium."""

from __future__ import annotations

import importlib.util
import json
import math
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.report.survey_positions import recording_positions
from sonartrack.systems.survey.files import read_status

#: the survey tests' helpers (tests are not a package: loaded from their file)
_SPEC = importlib.util.spec_from_file_location(
    "survey_helpers", Path(__file__).parents[1] / "systems" / "survey" / "test_survey.py")
survey_helpers = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(survey_helpers)

#: 300 s with the turn at 40 s: two of the default ships' ranges are determined, the third's is not
SCENE = "duration_s = 300.0\n[ownship]\nturn_start_s = 40.0\n"
#: the generator's NMEA track is about this origin (its x/y = the simulator's)
ORIGIN_LAT, ORIGIN_LON = 50.0, -4.0


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    d = tmp_path_factory.mktemp("survey_page")
    (d / "scene_in.toml").write_text(SCENE)
    assert main(["simulate", "--scene", str(d / "scene_in.toml"), "--only", "passive", "--out", str(d / "sim")]) == 0
    (d / "tuned.toml").write_text("min_track_s = 60.0\n[tracker]\ngate_deg = 5.0\n")
    survey_helpers._nmea_from_nav(d / "sim" / "nav.csv", d / "ship.nmea")
    wav = f"ship_{survey_helpers.START:%Y%m%d_%H%M%S}.wav"
    os.link(d / "sim" / "recording.wav", d / wav)  # its UTC start in its name
    rows = ["recording,navigation,spacing_m,settings,name,tow_length_m",
            "sim/recording.wav,sim/nav.csv,2.5,tuned.toml,table,",
            f"{wav},ship.nmea,2.5,,nmea,200",  # the simulator's array is 200 m astern
            "nothing/here.wav,sim/nav.csv,2.5,,missing,"]
    (d / "survey.csv").write_text("\n".join(rows) + "\n")
    assert main(["survey", "--manifest", str(d / "survey.csv"), "--out", str(d / "out")]) == 1  # one failed
    return d


def _targets(out: Path, name: str) -> pd.DataFrame:
    t = pd.read_csv(out / "recordings" / name / "targets.csv")
    return t[t["method"] == "ml"]


def _aeqd_xy(lat, lon):
    """x east, y north (m) of lat/lon on the azimuthal equidistant projection about the generator's origin, from
    the geodesic's length and azimuth (the projection's definition; not the package's LocalProjection)."""
    from pyproj import Geod

    az, _, d = Geod(ellps="WGS84").inv(np.full(np.size(lat), ORIGIN_LON), np.full(np.size(lat), ORIGIN_LAT), lon, lat)
    return d * np.sin(np.radians(az)), d * np.cos(np.radians(az))


def test_the_page_opens_with_the_summary_and_has_its_sections(survey):
    out = survey / "out"
    page = (out / "index.html").read_text()
    n_targets = sum(_targets(out, n)["target_id"].nunique() for n in ("table", "nmea"))
    hours = 2 * 300.0 / 3600.0
    summary = re.search(r'<p class="summary" id="summary"><b>(.*?)</b>', page).group(1)
    assert summary.startswith(f"3 recordings (2 ok, 1 failed); {n_targets} targets; {hours:.2f} h processed")
    assert summary.endswith("over 2024-05-17 13:45 to 2024-05-17 13:50 UTC")
    assert page.index('id="summary"') < page.index("<h2>Recordings</h2>") < page.index("<h2>Map</h2>")
    for part in ('id="rec-filter"', 'id="t-from"', 'id="t-to"', 'id="targets-table"', "<svg", "survey_targets.png"):
        assert part in page
    assert len(re.findall(r'<input type="checkbox" class="rec"', page)) == 2  # the recordings that ran
    assert len(re.findall(r"<tr data-rec=", page)) == n_targets
    assert not re.search(r"""(src|href)=["'](https?:)?//""", page)  # nothing fetched: the page works offline


def test_the_settings_that_differ_are_stated_with_their_recordings(survey):
    page = (survey / "out" / "index.html").read_text()
    section = page[page.index("<h2>Settings that differ from the defaults</h2>"):]
    assert "<code>min_track_s</code></td><td>60</td><td>120</td><td>s</td><td>table</td>" in section
    assert "<code>tracker.gate_deg</code></td><td>5</td><td>6</td><td>deg</td><td>table</td>" in section
    assert "<code>spacing_m</code></td><td>2.5</td><td>none</td><td>m</td><td>all</td>" in section
    assert "sound_speed_mps" not in section and "tracker.q" not in section


def test_each_recordings_page_opens_with_its_summary_line(survey):
    for name in ("table", "nmea"):
        t = _targets(survey / "out", name).sort_values("time_s").groupby("target_id").last()
        sides = t["side"].value_counts()
        page = (survey / "out" / "recordings" / name / "index.html").read_text()
        line = re.search(r"<p class='summary'><b>(.*?)</b>", page).group(1)
        by_side = ", ".join(f"{sides[s]} {s}" for s in ("starboard", "port", "unresolved") if s in sides)
        assert line == (f"0.08 h processed; {len(t)} targets: {by_side}; {int(t['range_determined'].sum())} of "
                        f"{len(t)} ranges determined")
        assert "<h2>Settings that differ from the defaults</h2>" in page


def test_the_map_has_one_track_per_recording_with_lat_lon_from_the_navigation(survey):
    out = survey / "out"
    nmea = recording_positions(out / "recordings" / "nmea", read_status(out, "nmea"))
    table = recording_positions(out / "recordings" / "table", read_status(out, "table"))
    assert (nmea.frame, table.frame) == ("latlon", "local") and "local frame" in table.note
    nav = pd.read_csv(survey / "sim" / "nav.csv")
    # the ownship: the log's latitudes and longitudes, over the whole recording, where the generator put them
    assert nmea.time_s[0] <= 0.0 and nmea.time_s[-1] >= 299.0
    x, y = _aeqd_xy(nmea.north, nmea.east)
    assert np.max(np.hypot(x - np.interp(nmea.time_s, nav["time_s"], nav["x_m"]),
                           y - np.interp(nmea.time_s, nav["time_s"], nav["y_m"]))) < 1.0
    # its targets' lat/lon: where the same recording with the table navigation puts them (same scene, same array)
    found = 0
    for a, b in zip(nmea.targets, table.targets, strict=True):
        ok = a.determined & b.determined
        if ok.any():
            x, y = _aeqd_xy(a.north[ok], a.east[ok])
            assert np.max(np.hypot(x - 1e3 * b.east[ok], y - 1e3 * b.north[ok])) < 25.0
            found += 1
    assert found >= 1
    # the SVG: each recording that ran has one ownship track, in pieces that join over its whole span
    page = (out / "index.html").read_text()
    data = json.loads(re.search(r'id="survey-map-data">(.*?)</script>', page).group(1))
    for rec in (0, 1):
        own = [e for e in data["elements"] if e["rec"] == rec and e["kind"] == "ownship"]
        assert own and all(re.search(f'<g id="{e["id"]}">\\s*<path', page) for e in own)
        assert sum(e["kind"] == "start" for e in data["elements"] if e["rec"] == rec) == 1
    own = [e for e in data["elements"] if e["rec"] == 1 and e["kind"] == "ownship"]
    assert data["mode"] == "utc" and own[0]["t0"] == 0.0 and own[-1]["t1"] >= 299.0
    assert all(a["t1"] == b["t0"] for a, b in zip(own, own[1:], strict=False))
    assert all(e["t0"] is None for e in data["elements"] if e["rec"] == 0)  # no UTC start: outside the time filter
    ends = [e for e in data["elements"] if e["kind"] == "target-end"]
    assert len(ends) == sum(t.determined.any() for r in (nmea, table) for t in r.targets)


def _chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        pytest.fail("chromium not found: run `make browser` to install it (headless checks of the pages)")
    return found


def _browse(url: str, tmp_path: Path, *extra: str) -> subprocess.CompletedProcess:
    args = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1400,2000", "--virtual-time-budget=3000",
            *extra, url]
    return subprocess.run(args, capture_output=True, text=True, timeout=180, check=True)


def test_the_filters_run_in_headless_chromium(survey, tmp_path):
    page = (survey / "out" / "index.html").resolve()
    n_nmea = _targets(survey / "out", "nmea")["target_id"].nunique()
    n_all = n_nmea + _targets(survey / "out", "table")["target_id"].nunique()
    dom = _browse(f"{page.as_uri()}#recordings=nmea&from=200", tmp_path, "--dump-dom").stdout
    assert f">{n_nmea} of {n_all} targets shown<" in dom  # written by the script: it ran
    assert len(re.findall(r'<input type="checkbox" class="rec"', dom)) == 2
    assert re.search(r'<input type="range" id="t-from"', dom) and re.search(r'<input type="range" id="t-to"', dom)
    assert re.search(r'<output id="t-from-label">2024-05-17 13:48:20 UTC</output>', dom)
    hidden_rows = re.findall(r'<tr data-rec="(\d)"[^>]*style="display: none;"', dom)
    assert hidden_rows == ["0"] * (n_all - n_nmea)  # the table recording's rows, unchecked
    data = json.loads(re.search(r'id="survey-map-data">(.*?)</script>', dom).group(1))
    hidden = set(re.findall(r'<g id="(sv-\d+)" style="display: none;"', dom))
    expect = {e["id"] for e in data["elements"] if e["rec"] == 0 or (e["t1"] is not None and e["t1"] < 200)}
    assert hidden == expect and expect
    shot = tmp_path / "survey_page.png"
    _browse(page.as_uri(), tmp_path, f"--screenshot={shot}")
    assert shot.stat().st_size > 50_000  # the page drawn (a blank page is a few kB)
    print(f"screenshot: {shot}")


def _hand_made(name: str, hours: float, n: int, start=None):
    """A recording going north-east at 5 m/s for ``hours`` with ``n`` fixes and one target 2 km east of it, whose
    range is determined in the second half only (hand-made: no chain)."""
    from sonartrack.report.survey_positions import RecordingPositions, TargetPath

    t = np.linspace(0.0, hours * 3600.0, n)
    x, y = 5.0 * t / 1e3 / math.sqrt(2), 5.0 * t / 1e3 / math.sqrt(2)
    known = np.where(t > t[-1] / 2, 1.0, np.nan)
    return RecordingPositions(name, "local", start, t, x, y, [TargetPath(1, t, (x + 2.0) * known, y * known, "port",
                                                                         90.0)])


def test_a_long_track_is_thinned_in_pieces_that_join():
    from sonartrack.report.figures.survey_map import MAX_POINTS, PIECES, survey_map_svg

    rec = _hand_made("long", 10.0, 100_001)
    svg, items = survey_map_svg([rec], [0.0], 36_000.0)
    own = [e for e in items if e["kind"] == "ownship"]
    assert len(own) == PIECES and all(a["t1"] == b["t0"] for a, b in zip(own, own[1:], strict=False))
    assert own[0]["t0"] == 0.0 and own[-1]["t1"] == 36_000.0
    target = [e for e in items if e["kind"] == "target"]
    assert target[0]["t0"] >= 18_000.0 and len(target) == PIECES // 2  # drawn where its position is known
    vertices = sum(len(re.findall(r"[ML] ", m)) for m in re.findall(r'<path d="([^"]*)"', svg))
    assert MAX_POINTS < vertices < 3 * (MAX_POINTS + PIECES) and len(svg) < 1_000_000  # thinned, not emptied


def test_without_any_start_the_time_axis_is_hours_from_each_start():
    from datetime import UTC, datetime

    from sonartrack.report.survey_map_section import map_section, time_axis

    recs = [_hand_made("a", 1.0, 50), _hand_made("b", 2.0, 50)]
    assert time_axis(recs) == ("relative", None, [0.0, 0.0], 7200.0)
    start = datetime(2024, 1, 1, 12, tzinfo=UTC)
    recs[1] = _hand_made("b", 2.0, 50, start)
    mode, origin, offsets, span = time_axis(recs)
    assert (mode, origin, offsets, span) == ("utc", start, [None, 0.0], 7200.0)
    assert "a (no UTC start: not filtered by time)" in map_section(recs)


def test_a_navigation_that_cannot_be_read_is_said_not_drawn(tmp_path):
    status = {"name": "leg1", "status": "ok", "navigation": str(tmp_path / "gone.nmea"), "start_utc": None,
              "duration_s": 10.0}
    p = recording_positions(tmp_path, status)
    assert p.time_s.size == 0 and p.note.startswith("leg1: ownship and targets not drawn: navigation file not found")
    assert recording_positions(tmp_path, {**status, "status": "failed"}) is None
