"""Hostile scenes, settings, recordings and navigation for `simulate` and `passive`: one line each, nothing left.

Each class of the hardening is a case with one test id ``<command>-<what>-<class>``, run in-process through
:func:`sonartrack.cli.main` (as tests/cli/test_bad_input_matrix.py), expecting exit status 2 and exactly one
``error:`` line naming ``match`` (no internal error, no traceback), and no output folder left behind. The classes:

* bounds: a value outside its physical range (1e300 m, 1e300 dB, 1e5 elements, 1e12 Hz), a sample rate no WAV
  header holds, an array whose delays wrap round the synthesis block, a memory estimate over the limit, a RAM
  field out to hundreds of km, a recording the disk cannot hold (refused before writing);
* the recording: silence, DC only, a clipped square wave, a band without signal or narrower than a bin, a spacing
  in kilometres or centimetres, a 2-channel pair given the array's element spacing;
* navigation: radians on a straight course, no array columns on a turning ship;
* outputs: ``--out ''``, a run failing or interrupted half-way (nothing of it is left; older files are kept);
* answers: an undetermined range leaves its cells empty.

Valid inputs come from one ``sonartrack simulate --duration-s 120`` (module fixture).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import Interrupted, main

SHIP = 'name = "far"\nx_m = {x}\ny_m = 1000.0\ncourse_deg = 0.0\nspeed_kn = 5.0\nsource_level_db = {sl}\n'


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    root = tmp_path_factory.mktemp("scene")
    mp = pytest.MonkeyPatch()
    mp.setenv("SONARTRACK_CACHE_DIR", str(root / "cache"))
    assert main(["simulate", "--out", str(root), "--duration-s", "120"]) == 0
    yield root
    mp.undo()


# ---------------------------------------------------------------- inputs made from the scene (scene, tmp) -> path

Maker = Callable[[Path, Path], Path]


def toml(body: str) -> Maker:
    def make(src, tmp):
        (tmp / "c.toml").write_text(body)
        return tmp / "c.toml"
    return make


def ship(x="1000.0", sl="120.0") -> Maker:
    return toml("[[ships]]\n" + SHIP.format(x=x, sl=sl))


def wav16(values: Callable[[np.random.Generator, tuple], np.ndarray], seconds: int = 20) -> Maker:
    """A 16-channel float32 WAV at 4 kHz of ``values(rng, (n, 16))``."""
    def make(src, tmp):
        from scipy.io import wavfile

        x = values(np.random.default_rng(1), (4000 * seconds, 16)).astype(np.float32)
        wavfile.write(tmp / "r.wav", 4000, x)
        return tmp / "r.wav"
    return make


def nav_edit(edit: Callable[[pd.DataFrame], pd.DataFrame]) -> Maker:
    def make(src, tmp):
        edit(pd.read_csv(src / "nav.csv")).to_csv(tmp / "n.csv", index=False)
        return tmp / "n.csv"
    return make


def straight_in_radians(df: pd.DataFrame) -> pd.DataFrame:
    """The ownship on a straight 60 deg course at 3 m/s, its heading written in radians (1.047)."""
    t = df["time_s"].to_numpy()
    c = np.deg2rad(60.0)
    return pd.DataFrame({"time_s": t, "x_m": 3.0 * t * np.sin(c), "y_m": 3.0 * t * np.cos(c), "heading_deg": c})


def without_array_columns(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=["array_x_m", "array_y_m", "array_heading_deg"])


# ---------------------------------------------------------------- the cases


@dataclass(frozen=True)
class Case:
    id: str
    argv: Callable[[dict], list[str]]
    files: dict[str, Maker]
    match: str


def simulate(*extra, scene_file: bool = False):
    def argv(f):
        return ["simulate", "--duration-s", "5", *(["--scene", f["config"]] if scene_file else []), "--out", f["out"],
                *extra]
    return argv


def passive(*extra, wav: str = "recording.wav"):
    def argv(f):
        return ["passive", "--wav", f.get("wav", f"{f['src']}/{wav}"), "--nav", f.get("nav", f"{f['src']}/nav.csv"),
                "--spacing", "2.5", "--out", f["out"], *extra]
    return argv


CASES = [
    # ---- simulate: bounds in the declarations, checked before anything is written
    Case("simulate-ship-position-huge", simulate(scene_file=True), {"config": ship(x="1e300")}, "x_m"),
    Case("simulate-source-level-huge", simulate(scene_file=True), {"config": ship(sl="1e300")}, "source_level_db"),
    Case("simulate-source-level-negative-huge", simulate(scene_file=True), {"config": ship(sl="-1e300")},
         "source_level_db"),
    Case("simulate-noise-level-huge", simulate(scene_file=True), {"config": toml("noise_level_db = 1e300\n")},
         "noise_level_db"),
    Case("simulate-elements-huge", simulate(scene_file=True), {"config": toml("[array]\nelements = 100000\n")},
         "elements"),
    Case("simulate-samplerate-huge", simulate(scene_file=True), {"config": toml("sample_rate_hz = 1e12\n")},
         "sample_rate_hz"),
    Case("simulate-samplerate-fraction", simulate(scene_file=True), {"config": toml("sample_rate_hz = 4000.5\n")},
         "whole number"),
    Case("simulate-spacing-wraps-block", simulate(scene_file=True), {"config": toml("[array]\nspacing_m = 250.0\n")},
         "block_s"),
    Case("simulate-block-memory", simulate(scene_file=True),
         {"config": toml("duration_s = 1200.0\nblock_s = 600.0\n")}, "GB of memory"),
    Case("simulate-frames-memory", simulate(scene_file=True),
         {"config": toml("[samples]\nframes = 1000\nframe_range_cells = 4096\nframe_doppler_cells = 4096\n")},
         "frames.npy"),
    Case("simulate-ram-too-far", simulate(scene_file=True),
         {"config": toml('propagation = "ram"\n[[ships]]\n' + SHIP.format(x="900000.0", sl="120.0"))}, "ram"),
    Case("simulate-out-empty", lambda f: ["simulate", "--duration-s", "5", "--only", "samples", "--out", ""], {},
         "--out is empty"),
    # ---- passive: the recording checked for what it is
    Case("passive-wav-silent", passive(), {"wav": wav16(lambda r, s: np.zeros(s))}, "only zeros"),
    Case("passive-wav-dc", passive(), {"wav": wav16(lambda r, s: np.full(s, 0.01))}, "constant"),
    Case("passive-wav-clipped-square", passive(), {"wav": wav16(lambda r, s: 0.5 * np.sign(r.standard_normal(s)))},
         "extremes"),
    Case("passive-band-nosignal", passive("--band-hz", "1200", "1900", "--allow-grating-lobes"), {}, "no signal"),
    Case("passive-band-narrower-than-bin", passive("--band-hz", "200", "200.5"), {}, "resolution"),
    Case("passive-spacing-kilometres", passive("--spacing", "0.0025"), {}, "wavelength"),
    Case("passive-spacing-centimetres", passive("--spacing", "250", "--band-hz", "1", "2.5", "--allow-grating-lobes"),
         {}, "centimetres"),
    Case("passive-pair-element-spacing", passive(wav="pair.wav"), {}, "apart"),
    # ---- passive: settings bounds and memory
    Case("passive-threshold-negative", passive("--config", "{config}"), {"config": toml("threshold = -1.0\n")},
         "threshold"),
    Case("passive-soundspeed-wrongunit", passive("--config", "{config}"), {"config": toml("sound_speed_mps = 1.5\n")},
         "sound_speed_mps"),
    Case("passive-beams-memory", passive("--config", "{config}"), {"config": toml("[front_end]\nbeams = 100000\n")},
         "beams"),
    Case("passive-window-memory", passive("--config", "{config}"), {"config": toml("window_s = 100.0\n")},
         "window_s"),
    # ---- passive: navigation
    Case("passive-nav-radians-straight", passive(), {"nav": nav_edit(straight_in_radians)}, "radians"),
    Case("passive-nav-noarray-turning", passive(), {"nav": nav_edit(without_array_columns)}, "no array columns"),
    Case("passive-out-empty", lambda f: passive()({**f, "out": ""}), {}, "--out is empty"),
]


def _argv(case: Case, src: Path, tmp: Path) -> list[str]:
    files = {"out": str(tmp / "out"), "src": str(src)}
    files.update({slot: str(make(src, tmp)) for slot, make in case.files.items()})
    return [a.replace("{config}", files.get("config", "")) for a in case.argv(files)]


def run(argv, capsys) -> tuple[int, str, str]:
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_refused_in_one_line(case, scene, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    monkeypatch.chdir(tmp_path)  # an empty --out must not write into the working directory
    code, out, err = run(_argv(case, scene, tmp_path), capsys)
    assert "Traceback" not in out + err
    assert code == 2, (code, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert case.match.lower() in lines[0].lower(), (case.match, lines[0])
    assert "internal error" not in lines[0]
    assert not (tmp_path / "out").exists()
    assert {p.name for p in tmp_path.iterdir()} <= {"c.toml", "r.wav", "n.csv"}


def test_simulate_longer_than_the_disk_holds_is_refused_before_writing(tmp_path, capsys, monkeypatch):
    # a day of 16 channels is 22 GB: with 5 GB free the run cannot finish, and is refused before it starts
    import shutil
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(100e9, 95e9, 5e9))
    code, _, err = run(["simulate", "--duration-s", "86400", "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and err.startswith("error: ") and len(err.strip().splitlines()) == 1
    assert "GB free" in err and "--duration-s" in err
    assert not (tmp_path / "out").exists()


def test_case_ids_are_unique():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))


# ---------------------------------------------------------------- a run failing or interrupted half-way


def _fail(exc: BaseException):
    def boom(*args, **kwargs):
        raise exc
    return boom


@pytest.mark.parametrize("older", [False, True], ids=["new-folder", "folder-with-older-files"])
def test_simulate_failing_half_way_leaves_none_of_its_files(tmp_path, capsys, monkeypatch, older):
    from sonartrack.systems.simulate import files

    out = tmp_path / "out"
    if older:
        out.mkdir()
        (out / "notes.txt").write_text("mine")
    monkeypatch.setattr(files, "write_sample_files", _fail(RuntimeError("disk on fire")))
    code, _, err = run(["simulate", "--duration-s", "5", "--out", str(out)], capsys)
    assert code == 1 and "internal error" in err
    assert not out.exists() if not older else {p.name for p in out.iterdir()} == {"notes.txt"}


def test_simulate_interrupted_says_it_keeps_nothing(tmp_path, capsys, monkeypatch):
    from sonartrack.systems.simulate import files

    monkeypatch.setattr(files, "write_sample_files", _fail(Interrupted()))
    code, _, err = run(["simulate", "--duration-s", "5", "--out", str(tmp_path / "out")], capsys)
    assert code == 130
    assert "simulate keeps no part of an unfinished scene" in err and "finished trials" not in err
    assert not (tmp_path / "out").exists()


def test_passive_failing_in_the_figures_leaves_no_table(scene, tmp_path, capsys, monkeypatch):
    from sonartrack.report.figures import passive as figures

    monkeypatch.setattr(figures, "write_passive_figures", _fail(RuntimeError("no fonts")))
    code, _, err = run(passive()({"src": str(scene), "out": str(tmp_path / "out")}), capsys)
    assert code == 1 and "internal error" in err
    assert not (tmp_path / "out").exists()


def test_passive_interrupted_says_it_keeps_nothing(scene, tmp_path, capsys, monkeypatch):
    from sonartrack.systems.passive import files

    monkeypatch.setattr(files, "run_passive", _fail(Interrupted()))
    code, _, err = run(passive()({"src": str(scene), "out": str(tmp_path / "out")}), capsys)
    assert code == 130
    assert "passive keeps no" in err and "finished trials" not in err
    assert not (tmp_path / "out").exists()


def test_passive_leaves_undetermined_cells_empty(scene, tmp_path, capsys):
    # tracks of 60 s get a TMA: the 120 s scene's ships before and through the turn, their ML ranges undetermined
    (tmp_path / "c.toml").write_text("min_track_s = 60.0\n")
    argv = passive("--config", str(tmp_path / "c.toml"))({"src": str(scene), "out": str(tmp_path / "out")})
    code, out, err = run(argv, capsys)
    assert code == 0, err
    targets = pd.read_csv(tmp_path / "out" / "targets.csv")
    undetermined = targets[~targets["range_determined"].astype(bool)]
    assert len(undetermined), "the 120 s scene has no undetermined row: the case tests nothing"
    for col in ("range_m", "range_std_m", "x_m", "course_deg", "speed_kn", "speed_std_kn"):
        assert undetermined[col].isna().all(), col
    assert undetermined["bearing_deg"].notna().all()
    determined = targets[targets["range_determined"].astype(bool)]
    assert determined["range_m"].notna().all()


def test_passive_warns_of_a_band_of_few_bins_and_still_answers(scene, tmp_path, capsys):
    code, out, err = run(passive("--band-hz", "200", "202")({"src": str(scene), "out": str(tmp_path / "out")}),
                         capsys)
    assert code == 0, err
    assert err.strip().splitlines() == [line for line in err.strip().splitlines() if line.startswith("warning: ")]
    assert "holds 2 frequency bin(s)" in err and "passive: wrote" in out
