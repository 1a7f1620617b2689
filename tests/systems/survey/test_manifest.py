"""The survey manifest (systems/survey/manifest.py): paths relative to the manifest, a line's own problem kept for
the survey to report, a broken manifest refused in one line."""

from __future__ import annotations

import pytest

from sonartrack.core.errors import InputError
from sonartrack.systems.survey.manifest import read_manifest
from sonartrack.systems.survey.recording import run_recording


def test_lines_and_their_problems(tmp_path):
    (tmp_path / "m.csv").write_text(
        " recording , navigation,spacing_m,calibration,tow_length_m,name\n"
        "rec/a.wav,nav/a.nmea,2.5,cal.toml,200,\n"
        "/abs/b/,b.csv,three,,,\n"
        "rec/a.wav,a.csv,2.5,,,\n")
    a, b, c = read_manifest(tmp_path / "m.csv")
    assert (a.name, a.recording, a.navigation, a.calibration, a.tow_length_m, a.problem) == (
        "a", str(tmp_path / "rec/a.wav"), tmp_path / "nav/a.nmea", tmp_path / "cal.toml", 200.0, None)
    assert b.name == "b" and b.recording == "/abs/b" and "spacing_m 'three' is not a number" in b.problem
    assert c.name == "a-line4" and "used twice" in c.problem
    failed = run_recording(b)
    assert not failed.ok and failed.reason == b.problem and failed.result is None


@pytest.mark.parametrize(("text", "words"), [("recording,spacing_m\nx.wav,2\n", "lacks the column(s) navigation"),
                                             ("recording,navigation,spacing_m\n", "lists no recording")])
def test_refused(tmp_path, text, words):
    (tmp_path / "m.csv").write_text(text)
    with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)")):
        read_manifest(tmp_path / "m.csv")
    with pytest.raises(InputError, match="not found"):
        read_manifest(tmp_path / "none.csv")


def test_a_manifest_that_is_not_utf8_is_one_line(tmp_path):
    (tmp_path / "m.csv").write_bytes(b"\xff\xfe\x00recording,navigation,spacing_m\n")
    with pytest.raises(InputError, match="not UTF-8 text"):
        read_manifest(tmp_path / "m.csv")
