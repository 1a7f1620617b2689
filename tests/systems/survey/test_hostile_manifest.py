"""Hostile manifests and output folders (systems/survey/): a recording's name never reaches outside
``OUT/recordings`` (``..``, ``.``, ``a/b``, an absolute path, a symbolic link of a recording's folder or of
``recordings/`` itself), a folder is written whole or not at all, and a manifest or a file that cannot be read is
one line naming it, not an internal error.

Nothing here runs the passive chain: a line's problem (or a missing recording) fails at once, and the folder of
a failed recording is written by the same code as a finished one's (files.py ``store_outcome``)."""

from __future__ import annotations

import builtins
import json
import os
from pathlib import Path

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.recording_writer import recording_writer
from sonartrack.systems.survey import files
from sonartrack.systems.survey.cluster import check_scheduler
from sonartrack.systems.survey.manifest import SurveyEntry, read_manifest, read_manifests
from sonartrack.systems.survey.recording import RecordingOutcome, run_recording
from sonartrack.systems.survey.run import run_survey

HEADER = "name,recording,navigation,spacing_m\n"


def _manifest(folder: Path, *names: str) -> Path:
    path = folder / "m.csv"
    path.write_text(HEADER + "".join(f"{n},nothing.wav,nav.csv,2.5\n" for n in names), encoding="utf-8")
    return path


def _victim(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "marker").write_text("keep me")
    (folder / "status.json").write_text("{}")  # the old code unlinked NAME/status.json first
    return folder


def _untouched(victim: Path) -> bool:
    return sorted(p.name for p in victim.iterdir()) == ["marker", "status.json"]


@pytest.mark.parametrize("name", ["../../victim", "..", ".", "a/b", "a\\b", ".hidden", "x" * 101, "tab\there"])
def test_a_name_that_is_no_plain_folder_name_is_that_lines_problem(tmp_path, name):
    (tmp_path / "m.csv").write_text(HEADER + f'"{name}",nothing.wav,nav.csv,2.5\nleg2,nothing.wav,nav.csv,2.5\n')
    bad, good = read_manifest(tmp_path / "m.csv")
    assert bad.name == "line2" and bad.problem.startswith("manifest line 2: the name ")
    assert "give a plain name like leg1" in bad.problem and "\n" not in bad.problem and len(bad.problem) < 250
    assert good.name == "leg2" and good.problem is None


def test_an_absolute_name_is_refused(tmp_path):
    (e,) = read_manifest(_manifest(tmp_path, str(tmp_path / "victim")))
    assert e.name == "line2" and "is an absolute path" in e.problem


def test_no_way_out_of_the_output_folder(tmp_path):
    """`..`, an absolute path, `.` and `a/b` as names: the survey writes only OUT/recordings/lineN."""
    victim = _victim(tmp_path / "victim")
    out = tmp_path / "out"
    out.mkdir()
    (out / "recordings").mkdir()  # so that OUT/recordings/../../victim resolves (the old code then removed it)
    _victim(out / "recordings" / "kept")  # a stored recording that `.` would have removed
    names = ["../../victim", str(victim), ".", "a/b"]
    summary = run_survey(read_manifest(_manifest(tmp_path, *names)), out)
    assert summary.failed == len(names)
    assert _untouched(victim) and _untouched(out / "recordings" / "kept")
    assert sorted(p.name for p in (out / "recordings").iterdir()) == ["kept", "line2", "line3", "line4", "line5"]
    assert not (out / "recordings" / "a").exists()


def test_a_name_from_the_recordings_folder_name_is_made_plain(tmp_path):
    (tmp_path / "m.csv").write_text("recording,navigation,spacing_m\n..,nav.csv,2.5\n../x y.wav,nav.csv,2.5\n")
    a, b = read_manifest(tmp_path / "m.csv")
    assert (a.name, a.problem, b.name, b.problem) == ("line2", None, "x_y", None)


def test_a_symlinked_recording_folder_is_refused_and_its_target_kept(tmp_path):
    victim = _victim(tmp_path / "victim")
    out = tmp_path / "out"
    (out / "recordings").mkdir(parents=True)
    (out / "recordings" / "leg1").symlink_to(victim, target_is_directory=True)
    with pytest.raises(InputError, match=r"recordings/leg1 is a symbolic link \(to .*victim\): a survey writes"):
        run_survey(read_manifest(_manifest(tmp_path, "leg1")), out)
    assert _untouched(victim)


def test_a_symlinked_recordings_folder_is_refused_and_its_target_kept(tmp_path):
    victim = _victim(tmp_path / "victim" / "leg1").parent
    out = tmp_path / "out"
    out.mkdir()
    (out / "recordings").symlink_to(victim, target_is_directory=True)
    with pytest.raises(InputError, match=r"out/recordings is a symbolic link"):
        run_survey(read_manifest(_manifest(tmp_path, "leg1")), out)
    assert _untouched(victim / "leg1")


def test_store_never_follows_a_link_that_appears_meanwhile(tmp_path):
    """A link made after the checks (between the start and a recording's storing) is refused there too."""
    victim = _victim(tmp_path / "victim")
    out = tmp_path / "out"
    (out / "recordings").mkdir(parents=True)
    entry = SurveyEntry("leg1", "x.wav", Path("nav.csv"), 2.5)
    (out / "recordings" / "leg1").symlink_to(victim, target_is_directory=True)
    with pytest.raises(InputError, match="is a symbolic link"):
        files.store_outcome(out, entry, RecordingOutcome("leg1", False, "why", None, None, 0.0, 0.0))
    assert _untouched(victim)
    with pytest.raises(InputError, match="give a plain name like leg1"):
        files.recording_dir(out, "../victim")


def test_a_folder_is_whole_or_absent_and_stale_partials_go(tmp_path):
    """An error while a recording's folder is written leaves the old folder as it was and no hidden sibling; a
    sibling left by a process that is gone is removed by the next run, one of a live process kept."""
    out = tmp_path / "out"
    old = _victim(out / "recordings" / "leg1")
    entry = SurveyEntry("leg1", "x.wav", Path("nav.csv"), 2.5)
    outcome = RecordingOutcome("leg1", True, "", object(), None, 0.0, 0.0)
    with pytest.raises(AttributeError):  # the tables of a result that is none: fails half-way through
        files.store_outcome(out, entry, outcome)
    assert _untouched(old) and [p.name for p in (out / "recordings").iterdir()] == ["leg1"]
    files.store_outcome(out, entry, RecordingOutcome("leg1", False, "why", None, None, 0.0, 0.0))
    assert [p.name for p in old.iterdir()] == ["status.json"]  # replaced whole
    dead = 2 ** 22 + 12345  # above the default pid_max of 4194304: no such process
    for stale in (out / "recordings" / f".leg1.partial-{dead}", out / "recordings" / f".leg2.old-{dead}",
                  out / f".dask-scratch-{dead}", out / "recordings" / f".leg3.partial-{os.getppid()}"):
        stale.mkdir()
    removed = files.remove_stale(out)
    assert sorted(p.name for p in removed) == [f".dask-scratch-{dead}", f".leg1.partial-{dead}", f".leg2.old-{dead}"]
    assert (out / "recordings" / f".leg3.partial-{os.getppid()}").is_dir()  # a live process's: kept


def test_names_that_differ_in_case_only_are_one_name(tmp_path):
    a, b = read_manifest(_manifest(tmp_path, "Leg1", "leg1"))
    assert a.problem is None and b.name == "leg1-line3" and "used twice" in b.problem


def test_a_name_repeated_across_manifests_stays_plain(tmp_path):
    (tmp_path / "a b").mkdir()
    first, second = _manifest(tmp_path, "leg1"), _manifest(tmp_path / "a b", "leg1")
    _, e = read_manifests([first, second])
    assert e.name == "leg1-a_b" and "used by an earlier manifest" in e.problem


def test_a_byte_order_mark_is_not_part_of_the_first_column(tmp_path):
    (tmp_path / "m.csv").write_bytes(b"\xef\xbb\xbf" + _manifest(tmp_path, "leg1").read_bytes())
    (e,) = read_manifest(tmp_path / "m.csv")
    assert e.name == "leg1" and e.problem is None


def test_a_cell_over_the_csv_field_limit_is_one_line(tmp_path):
    (tmp_path / "m.csv").write_text(HEADER + "leg1,nothing.wav,nav.csv," + "1" * 140_000 + "\n")
    with pytest.raises(InputError, match=r"m.csv line 2: field larger than field limit .*close the quote"):
        read_manifest(tmp_path / "m.csv")


def test_a_control_character_in_a_path_is_that_lines_problem(tmp_path):
    (tmp_path / "m.csv").write_text(HEADER + "leg1,rec\x00.wav,nav.csv,2.5\n")
    (e,) = read_manifest(tmp_path / "m.csv")
    assert e.problem == "manifest line 2: the recording cell 'rec\\x00.wav' holds a control character: remove it"


@pytest.mark.parametrize("address", ["notaurl", "tcp://host", "http://host:8786", "tcp://host:port"])
def test_a_scheduler_address_of_another_form_is_refused(tmp_path, address):
    with pytest.raises(InputError, match=r"is not a Dask scheduler address: give it as tcp://host:8786"):
        run_survey(read_manifest(_manifest(tmp_path, "leg1")), tmp_path / "out", scheduler=address)
    check_scheduler("tcp://10.0.0.5:8786")
    check_scheduler("localhost:8786")


@pytest.fixture
def unreadable(monkeypatch):
    """``open``, ``os.scandir`` and ``os.listdir`` refuse the paths put in the returned set with PermissionError.

    The tests run as root, whom chmod 000 does not stop; this stands in for a file or folder the user may not
    read. It covers what the survey does with the refusal (the reason it reports), not whether a given reader
    gets the refusal through these calls on a real unreadable file."""
    denied: set[str] = set()

    def guard(real):
        def call(path=".", *args, **kwargs):
            if os.path.abspath(os.fspath(path)) in denied:
                raise PermissionError(13, "Permission denied", os.fspath(path))
            return real(path, *args, **kwargs)
        return call

    monkeypatch.setattr(builtins, "open", guard(builtins.open))
    monkeypatch.setattr(os, "scandir", guard(os.scandir))
    monkeypatch.setattr(os, "listdir", guard(os.listdir))
    return denied


@pytest.mark.parametrize("which", ["recording", "navigation", "folder"])
def test_an_unreadable_file_is_an_input_problem_named_with_its_path(tmp_path, unreadable, which):
    (tmp_path / "parts").mkdir()
    for name in ("rec.wav", "parts/rec_20240101_000000.wav"):
        with recording_writer(tmp_path / name, 4, 2000, "float32") as w:
            w.write(np.zeros((4, 2000)))
    (tmp_path / "nav.csv").write_text("time_s,x_m,y_m,heading_deg\n0,0,0,0\n1,0,1,0\n")
    rec = "parts" if which == "folder" else "rec.wav"
    (tmp_path / "m.csv").write_text(HEADER + f"leg1,{rec},nav.csv,2.5\n")
    (e,) = read_manifest(tmp_path / "m.csv")
    path = {"recording": e.recording, "navigation": str(e.navigation), "folder": e.recording}[which]
    unreadable.add(os.path.abspath(path))
    outcome = run_recording(e)
    assert outcome.reason == f"cannot read {path}: permission denied: check its permissions (and its folder's)"


def test_the_page_links_a_name_that_holds_address_characters(tmp_path):
    from sonartrack.report.survey_page import write_survey_page

    name = "leg#1 ?"
    folder = tmp_path / "recordings" / name
    folder.mkdir(parents=True)
    (folder / "index.html").write_text("<html></html>")
    (folder / "status.json").write_text(json.dumps({"name": name, "status": "failed", "reason": "why"}))
    rows = files.survey_rows(tmp_path, [SurveyEntry(name, "x.wav", Path("nav.csv"), 2.5)])
    page = write_survey_page(tmp_path, rows).read_text()
    assert 'href="recordings/leg%231%20%3F/index.html"' in page
