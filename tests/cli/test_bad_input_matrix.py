"""The bad-input matrix: every command x every class of bad input ends in one line, never a traceback.

Classes: missing file, empty file, header only, missing column, NaN / inf, unsorted / duplicated times, wrong
unit, 1e300, negative, wrong file type (PNG bytes under a data file's name), a directory, a non-UTF-8 config,
an unknown key, a wrong type, an unwritable output. Each case is one test id ``<command>-<input>-<class>`` and
expects one of:

* ``error``: exit status 2 and exactly one stderr line, starting with ``error:`` (and naming ``match``);
* ``usage``: exit status 2 with the usage text (typer's own parser refused the option);
* ``ok``: exit status 0 and the same answer as the clean files (``answer``): the input is fine.

A refused run leaves no output folder behind.

No case may print a Python traceback. The valid inputs come from one ``sonartrack simulate --duration-s 120``
per module (as tests/cli/test_simulate_cli.py); every bad file is a small edit of one of them.
"""

from __future__ import annotations

import shutil
import struct
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main

PNG_BYTES = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x01\x00\x00\x00\x01\x08\x02\x00\x00\x00\x90wS\xde"
NOT_UTF8 = b"duration_s = 5.0\n# \xff\xfe caf\xe9\n"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """The valid inputs of every command: a simulated scene (120 s) and the peaks of its pair recording."""
    root = tmp_path_factory.mktemp("scene")
    mp = pytest.MonkeyPatch()
    mp.setenv("SONARTRACK_CACHE_DIR", str(root / "cache"))
    assert main(["simulate", "--out", str(root), "--duration-s", "120"]) == 0
    assert main(["bearings", "--wav", str(root / "pair.wav"), "--spacing", "20", "--out", str(root / "pk")]) == 0
    shutil.copy(root / "pk" / "peaks.csv", root / "peaks.csv")
    yield root
    mp.undo()


# ---------------------------------------------------------------- bad-file makers (src folder, tmp folder) -> path

Maker = Callable[[Path, Path], Path]


def csv_edit(name: str, edit: Callable[[pd.DataFrame], pd.DataFrame]) -> Maker:
    def make(src: Path, tmp: Path) -> Path:
        out = tmp / name
        edit(pd.read_csv(src / name)).to_csv(out, index=False)
        return out
    return make


def set_cell(col: str, value, row: int = 2) -> Callable[[pd.DataFrame], pd.DataFrame]:
    def edit(df):
        df[col] = df[col].astype(object)
        df.loc[row, col] = value
        return df
    return edit


def scale(col: str, factor: float) -> Callable[[pd.DataFrame], pd.DataFrame]:
    def edit(df):
        df[col] = df[col] * factor
        return df
    return edit


def drop(col: str):
    return lambda df: df.drop(columns=[col])


def rename(old: str, new: str):
    return lambda df: df.rename(columns={old: new})


def header_only(df):
    return df.iloc[:0]


def reverse(df):
    return df.iloc[::-1].reset_index(drop=True)


def duplicate_row(df, row: int = 3):
    return pd.concat([df.iloc[:row + 1], df.iloc[row:]]).reset_index(drop=True)


def raw_bytes(name: str, data: bytes) -> Maker:
    def make(src: Path, tmp: Path) -> Path:
        (tmp / name).write_bytes(data)
        return tmp / name
    return make


def text(name: str, body: str) -> Maker:
    return raw_bytes(name, body.encode())


def missing(name: str) -> Maker:
    return lambda src, tmp: tmp / "nowhere" / name


def directory(name: str) -> Maker:
    def make(src, tmp):
        (tmp / name).mkdir()
        return tmp / name
    return make


def valid(name: str) -> Maker:
    return lambda src, tmp: src / name


def npy(name: str, edit: Callable[[np.ndarray], np.ndarray]) -> Maker:
    def make(src, tmp):
        np.save(tmp / name, edit(np.load(src / "frames.npy")))
        return tmp / name
    return make


def frames_cell(value: float):
    def edit(a):
        a = a.astype(float)
        a[0, 1, 2] = value
        return a
    return edit


def wav_header_only(src, tmp):
    """A 2-channel 16-bit WAV header that announces no samples."""
    fmt = struct.pack("<4sIHHIIHH", b"fmt ", 16, 1, 2, 4000, 16000, 4, 16)
    body = b"WAVE" + fmt + struct.pack("<4sI", b"data", 0)
    (tmp / "hdr.wav").write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    return tmp / "hdr.wav"


def wav_float(values: Callable[[np.ndarray], np.ndarray], channels: int = 2) -> Maker:
    def make(src, tmp):
        from scipy.io import wavfile

        x = np.random.default_rng(1).normal(size=(4000 * 4, channels)).astype(np.float32)
        wavfile.write(tmp / "f.wav", 4000, values(x))
        return tmp / "f.wav"
    return make


def with_nan(x):
    x[10, 0] = np.nan
    return x


# ---------------------------------------------------------------- commands: argv from the named input files


@dataclass(frozen=True)
class Case:
    id: str
    argv: Callable[[dict], list[str]]     # {slot: path} -> argv (an "out" slot is always given)
    files: dict[str, Maker]               # slot -> maker (slots not given take the command's valid default)
    expect: str = "error"                 # "error", "usage" or "ok"
    match: str = ""                       # a word the error line must contain (the column, option, key)
    answer: str = ""                      # for "ok": what the summary line must say (the same answer as the clean file)


def cmd_bearings(*extra):
    return lambda f: ["bearings", "--wav", f["wav"], "--spacing", "20", "--out", f["out"], *extra]


def cmd_contacts(*extra):
    return lambda f: ["track", "--contacts", f["contacts"], "--out", f["out"], *extra]


def cmd_raw(*extra):
    return lambda f: ["track", "--contacts", f["raw"], "--nav", f["nav"], "--out", f["out"], *extra]


def cmd_peaks(*extra):
    return lambda f: ["track", "--peaks", f["peaks"], "--out", f["out"], *extra]


def cmd_detect(*extra):
    # a fixed threshold: the Monte Carlo threshold (2000 noise-only trials) is not what these cases test
    return lambda f: ["detect", "--frames", f["frames"], "--threshold", "5", "--out", f["out"], *extra]


def cmd_tma(*extra):
    return lambda f: ["tma", "--bearings", f["brg"], "--ownship", f["own"], "--out", f["out"], *extra]


def cmd_tl(*extra):
    return lambda f: ["tl", "--profile", f["profile"], "--freq", "300", "--zs", "50", "--zr", "80", "--rmax", "3",
                      "--out", f["out"], *extra]


def cmd_simulate(*extra):
    return lambda f: ["simulate", "--duration-s", "5", "--only", "samples", "--out", f["out"], *extra]


def cmd_reproduce(*extra):
    return lambda f: ["reproduce", "mftd", "--quick", "--out", f["out"], *extra]


DEFAULTS: dict[str, Maker] = {
    "wav": valid("pair.wav"), "contacts": valid("contacts.csv"), "raw": valid("raw.csv"), "nav": valid("raw_nav.csv"),
    "peaks": valid("peaks.csv"), "frames": valid("frames.npy"), "brg": valid("brg.csv"), "own": valid("own.csv"),
    "profile": valid("ctd.csv"), "rec": valid("recording.wav"), "pnav": valid("nav.csv"),
}


def config_cases(prefix: str, cmd, unknown_ok: str, wrong_type: str, wrong_match: str) -> list[Case]:
    """The config classes of a command with --config (or --scene): missing, directory, PNG, non-UTF-8, unknown key,
    wrong type."""
    def c(f):
        return cmd("--config", f["config"])(f) if prefix != "simulate" else cmd("--scene", f["config"])(f)
    return [
        Case(f"{prefix}-config-missing", c, {"config": missing("c.toml")}, match="c.toml"),
        Case(f"{prefix}-config-directory", c, {"config": directory("c.toml")}, match="directory"),
        Case(f"{prefix}-config-filetype", c, {"config": raw_bytes("c.toml", PNG_BYTES)}, match="c.toml"),
        Case(f"{prefix}-config-notutf8", c, {"config": raw_bytes("c.toml", NOT_UTF8)}, match="UTF-8"),
        Case(f"{prefix}-config-unknownkey", c, {"config": text("c.toml", f"{unknown_ok}\nbogus_key = 1\n")},
             match="bogus_key"),
        Case(f"{prefix}-config-wrongtype", c, {"config": text("c.toml", wrong_type)}, match=wrong_match),
    ]


def unwritable(prefix: str, cmd) -> Case:
    """--out below an existing file: the folder cannot be made."""
    return Case(f"{prefix}-out-unwritable", lambda f: _under_file(cmd, f), {}, match="a_file")


def _under_file(cmd, f):
    blocker = Path(f["out"]).parent / "a_file"
    blocker.write_text("x")
    return cmd({**f, "out": str(blocker / "out")})


def table_cases(prefix: str, cmd, slot: str, name: str, *, col: str, time_col: str = "time_s") -> list[Case]:
    """The file classes every CSV input shares."""
    return [
        Case(f"{prefix}-missing", cmd, {slot: missing(name)}, match=name),
        Case(f"{prefix}-empty", cmd, {slot: text(name, "")}, match=name),
        Case(f"{prefix}-headeronly", cmd, {slot: csv_edit(name, header_only)}, match="no rows"),
        Case(f"{prefix}-missingcolumn", cmd, {slot: csv_edit(name, drop(col))}, match=col),
        Case(f"{prefix}-nan", cmd, {slot: csv_edit(name, set_cell(col, np.nan))}, match=col),
        Case(f"{prefix}-inf", cmd, {slot: csv_edit(name, set_cell(col, np.inf))}, match=col),
        Case(f"{prefix}-wrongtype", cmd, {slot: csv_edit(name, set_cell(col, "abc"))}, match=col),
        Case(f"{prefix}-huge", cmd, {slot: csv_edit(name, set_cell(col, 1e300))}, match=col),
        Case(f"{prefix}-unsorted", cmd, {slot: csv_edit(name, reverse)}, match=time_col),
        Case(f"{prefix}-duplicated", cmd, {slot: csv_edit(name, duplicate_row)}, match="row"),
        Case(f"{prefix}-filetype", cmd, {slot: raw_bytes(name, PNG_BYTES)}, match="PNG image"),
        Case(f"{prefix}-directory", cmd, {slot: directory(name)}, match="directory"),
    ]


def shuffle_within_scans(df):
    """Contacts of one scan in another order: the same scans, so the same answer."""
    return df.sample(frac=1.0, random_state=3).sort_values("time_s", kind="stable").reset_index(drop=True)


def add_column(col, value):
    def edit(df):
        df[col] = value
        return df
    return edit


def comment_first(name: str) -> Maker:
    def make(src, tmp):
        (tmp / name).write_text("# recorded on a sunny day\n" + (src / name).read_text())
        return tmp / name
    return make


def rad(col):
    return scale(col, np.pi / 180.0)


def cmd_passive(*extra):
    return lambda f: ["passive", "--wav", f["rec"], "--nav", f["pnav"], "--spacing", "2.5", "--out", f["out"], *extra]


def nav_until(t_end_s: float) -> Callable[[pd.DataFrame], pd.DataFrame]:
    return lambda df: df[df["time_s"] <= t_end_s]


#: `sonartrack passive`: its N-channel WAV, its navigation file, its --config and options
PASSIVE_CASES: list[Case] = [
    Case("passive-wav-missing", cmd_passive(), {"rec": missing("rec.wav")}, match="rec.wav"),
    Case("passive-wav-empty", cmd_passive(), {"rec": text("rec.wav", "")}, match="rec.wav"),
    Case("passive-wav-headeronly", cmd_passive(), {"rec": wav_header_only}, match="hdr.wav"),
    Case("passive-wav-filetype", cmd_passive(), {"rec": raw_bytes("rec.wav", PNG_BYTES)}, match="rec.wav"),
    Case("passive-wav-directory", cmd_passive(), {"rec": directory("rec.wav")}, match="directory"),
    Case("passive-wav-nan", cmd_passive(), {"rec": wav_float(with_nan, channels=16)}, match="NaN"),
    Case("passive-wav-huge", cmd_passive(), {"rec": wav_float(lambda x: x * np.float32(1e20), channels=16)},
         match="f.wav"),
    Case("passive-wav-wrongchannels", cmd_passive("--elements", "8"), {}, match="--elements"),
    Case("passive-spacing-wrongunit", cmd_passive("--spacing", "250"), {}, match="metres"),
    Case("passive-spacing-negative", cmd_passive("--spacing", "-2.5"), {}, match="spacing"),
    Case("passive-band-aliased", cmd_passive("--band-hz", "50", "1000"), {}, match="aliases"),
    *table_cases("passive-nav", cmd_passive(), "pnav", "nav.csv", col="x_m"),
    Case("passive-nav-wrongunit", cmd_passive(), {"pnav": csv_edit("nav.csv", rad("array_heading_deg"))},
         match="radians"),
    Case("passive-nav-short", cmd_passive(), {"pnav": csv_edit("nav.csv", nav_until(60.0))}, match="covers"),
    *config_cases("passive", cmd_passive, unknown_ok="min_track_s = 100.0", wrong_type='min_track_s = "long"',
                  wrong_match="min_track_s"),
    unwritable("passive", cmd_passive()),
    Case("ok-passive-extra-column", cmd_passive(), {"pnav": csv_edit("nav.csv", add_column("note", "calm"))}, "ok",
         answer="passive:"),
]


CASES: list[Case] = [
    # ---- entry point
    Case("entry-noargs", lambda f: [], {}, "usage"),
    Case("entry-unknown-command", lambda f: ["no-such-command"], {}, "usage"),
    # ---- bearings: WAV in, options
    Case("bearings-wav-missing", cmd_bearings(), {"wav": missing("rec.wav")}, match="rec.wav"),
    Case("bearings-wav-empty", cmd_bearings(), {"wav": text("rec.wav", "")}, match="rec.wav"),
    Case("bearings-wav-headeronly", cmd_bearings(), {"wav": wav_header_only}, match="hdr.wav"),
    Case("bearings-wav-filetype", cmd_bearings(), {"wav": raw_bytes("rec.wav", PNG_BYTES)}, match="WAV"),
    Case("bearings-wav-directory", cmd_bearings(), {"wav": directory("rec.wav")}, match="directory"),
    Case("bearings-wav-mono", cmd_bearings(), {"wav": wav_float(lambda x: x, channels=1)}, match="mono"),
    Case("bearings-wav-nan", cmd_bearings(), {"wav": wav_float(with_nan)}, match="NaN"),
    Case("bearings-wav-huge", cmd_bearings(), {"wav": wav_float(lambda x: x * np.float32(1e20))}, match="f.wav"),
    Case("bearings-spacing-negative", cmd_bearings("--spacing", "-1"), {}, match="spacing"),
    Case("bearings-spacing-huge", cmd_bearings("--spacing", "1e300"), {}, match="spacing"),
    Case("bearings-spacing-nan", cmd_bearings("--spacing", "nan"), {}, match="spacing"),
    Case("bearings-soundspeed-wrongunit", cmd_bearings("--sound-speed", "1.5"), {}, match="sound_speed"),
    Case("bearings-window-negative", cmd_bearings("--window", "-1"), {}, match="window"),
    Case("bearings-maxpeaks-wrongtype", cmd_bearings("--max-peaks", "abc"), {}, "usage"),
    *config_cases("bearings", cmd_bearings, "", 'window_s = "long"\n', "window_s"),
    unwritable("bearings", cmd_bearings()),
    # ---- track --contacts (Cartesian)
    *table_cases("contacts", cmd_contacts(), "contacts", "contacts.csv", col="x_m"),
    Case("contacts-wrongunit-km", cmd_contacts(), {"contacts": csv_edit("contacts.csv", rename("x_m", "x_km"))},
         match="x_km"),
    Case("contacts-negative-variance", cmd_contacts(),
         {"contacts": csv_edit("contacts.csv", set_cell("var_x_m2", -5.0))}, match="var_x_m2"),
    Case("contacts-huge-variance", cmd_contacts(),
         {"contacts": csv_edit("contacts.csv", set_cell("var_y_m2", 1e300))}, match="var_y_m2"),
    *config_cases("contacts", cmd_contacts, "", 'default_sigma_m = "big"\n', "default_sigma_m"),
    Case("contacts-config-negative", cmd_contacts("--config", "{config}"),
         {"config": text("c.toml", "[tracker]\npd = -0.5\n")}, match="pd"),
    unwritable("contacts", cmd_contacts()),
    # ---- track --contacts --nav (raw bistatic)
    *table_cases("raw", cmd_raw(), "raw", "raw.csv", col="travel_time_s"),
    Case("raw-wrongunit-radians", cmd_raw(), {"raw": csv_edit("raw.csv", rad("bearing_deg"))}, match="radians"),
    Case("raw-wrongunit-ms", cmd_raw(), {"raw": csv_edit("raw.csv", scale("travel_time_s", 1000.0))},
         match="millisecond"),
    Case("raw-negative-traveltime", cmd_raw(), {"raw": csv_edit("raw.csv", set_cell("travel_time_s", -2.0))},
         match="travel_time_s"),
    Case("raw-huge-bearing", cmd_raw(), {"raw": csv_edit("raw.csv", set_cell("bearing_deg", 1e300))},
         match="bearing_deg"),
    Case("raw-nav-missing", cmd_raw(), {"nav": missing("raw_nav.csv")}, match="raw_nav.csv"),
    Case("raw-nav-headeronly", cmd_raw(), {"nav": csv_edit("raw_nav.csv", header_only)}, match="no rows"),
    Case("raw-nav-missingcolumn", cmd_raw(), {"nav": csv_edit("raw_nav.csv", drop("rx_y_m"))}, match="rx_y_m"),
    Case("raw-nav-huge", cmd_raw(), {"nav": csv_edit("raw_nav.csv", set_cell("tx_x_m", 1e300))}, match="tx_x_m"),
    Case("raw-nav-unsorted", cmd_raw(), {"nav": csv_edit("raw_nav.csv", reverse)}, match="time_s"),
    Case("raw-nav-km", cmd_raw(), {"nav": csv_edit("raw_nav.csv", rename("tx_x_m", "tx_x_km"))}, match="tx_x_km"),
    Case("raw-nav-notgiven", lambda f: ["track", "--contacts", f["raw"], "--out", f["out"]], {}, match="--nav"),
    Case("raw-config-soundspeed-wrongunit", cmd_raw("--config", "{config}"),
         {"config": text("c.toml", "[bistatic]\nsound_speed_mps = 1.5\n")}, match="sound_speed_mps"),
    # ---- track --peaks
    *table_cases("peaks", cmd_peaks(), "peaks", "peaks.csv", col="amplitude"),
    Case("peaks-wrongunit-radians", cmd_peaks(), {"peaks": csv_edit("peaks.csv", rad("bearing_deg"))},
         match="radians"),
    Case("peaks-bearing-beyond", cmd_peaks(), {"peaks": csv_edit("peaks.csv", set_cell("bearing_deg", 270.0))},
         match="bearing_deg"),
    Case("peaks-negative-amplitude", cmd_peaks(), {"peaks": csv_edit("peaks.csv", set_cell("amplitude", -100.0))},
         match="amplitude"),
    Case("peaks-tracker-unknown", cmd_peaks("--tracker", "kalman"), {}, match="--tracker"),
    *config_cases("peaks", cmd_peaks, "", "associator = 5\n", "associator"),
    Case("peaks-config-confirm", cmd_peaks("--config", "{config}"),
         {"config": text("c.toml", "[tracker]\nconfirm_m = 5\nconfirm_n = 3\n")}, match="confirm"),
    unwritable("peaks", cmd_peaks()),
    # ---- detect
    Case("detect-frames-missing", cmd_detect(), {"frames": missing("f.npy")}, match="f.npy"),
    Case("detect-frames-empty", cmd_detect(), {"frames": text("f.npy", "")}, match="f.npy"),
    Case("detect-frames-headeronly", cmd_detect(), {"frames": npy("f.npy", lambda a: a[:0])}, match="K = 0"),
    Case("detect-frames-rank", cmd_detect(), {"frames": npy("f.npy", lambda a: a[0])}, match="rank"),
    Case("detect-frames-nan", cmd_detect(), {"frames": npy("f.npy", frames_cell(np.nan))}, match="NaN"),
    Case("detect-frames-inf", cmd_detect(), {"frames": npy("f.npy", frames_cell(np.inf))}, match="NaN/inf"),
    Case("detect-frames-negative", cmd_detect(), {"frames": npy("f.npy", frames_cell(-1.0))}, match="negative"),
    Case("detect-frames-huge", cmd_detect(), {"frames": npy("f.npy", frames_cell(1e300))}, match="1e+300"),
    Case("detect-frames-wrongtype", cmd_detect(), {"frames": npy("f.npy", lambda a: a.astype(complex))},
         match="dtype"),
    Case("detect-frames-filetype", cmd_detect(), {"frames": raw_bytes("f.npy", PNG_BYTES)}, match="PNG image"),
    Case("detect-frames-csv", cmd_detect(), {"frames": valid("brg.csv")}, match=".npy"),
    Case("detect-frames-directory", cmd_detect(), {"frames": directory("f.npy")}, match="directory"),
    Case("detect-threshold-nan", cmd_detect("--threshold", "nan"), {}, match="threshold"),
    Case("detect-pfa-nan", cmd_detect("--pfa", "nan"), {}, match="pfa"),
    Case("detect-pfa-wrongunit", cmd_detect("--pfa", "5"), {}, match="pfa"),
    Case("detect-ntracks-negative", cmd_detect("--n-tracks", "-1"), {}, match="n_tracks"),
    Case("detect-snr-huge", cmd_detect("--snr-db", "1e300"), {}, match="snr_db"),
    Case("detect-sigma-huge", cmd_detect("--sigma-a", "1e300"), {}, match="sigma_a_mps2"),
    Case("detect-ntracks-huge", cmd_detect("--n-tracks", "1000000000"), {}, match="n_tracks"),  # filled the memory
    Case("detect-config-soundspeed-wrongunit", cmd_detect("--config", "{config}"),
         {"config": text("c.toml", "[plane]\nsound_speed_mps = 1.5\n")}, match="sound_speed_mps"),
    *config_cases("detect", cmd_detect, "", '[detector]\nsnr_db = "loud"\n', "snr_db"),
    Case("detect-config-nan", cmd_detect("--config", "{config}"),
         {"config": text("c.toml", "[detector]\nsigma_a_mps2 = nan\n")}, match="sigma_a_mps2"),
    unwritable("detect", cmd_detect()),
    # ---- tma
    *table_cases("tma-bearings", cmd_tma(), "brg", "brg.csv", col="bearing_deg"),
    Case("tma-bearings-radians", cmd_tma(), {"brg": csv_edit("brg.csv", rad("bearing_deg"))}, match="radians"),
    Case("tma-bearings-negative-freq", cmd_tma(), {"brg": csv_edit("brg.csv", set_cell("frequency_hz", -200.0))},
         match="frequency_hz"),
    Case("tma-bearings-huge-freq", cmd_tma(), {"brg": csv_edit("brg.csv", set_cell("frequency_hz", 1e300))},
         match="frequency_hz"),
    Case("tma-bearings-huge-snr", cmd_tma(), {"brg": csv_edit("brg.csv", set_cell("snr_db", 1e300))},
         match="snr_db"),
    *table_cases("tma-ownship", cmd_tma(), "own", "own.csv", col="x_m"),
    Case("tma-ownship-km", cmd_tma(), {"own": csv_edit("own.csv", rename("x_m", "x_km"))}, match="x_km"),
    Case("tma-sigma-huge", cmd_tma("--sigma-bearing-deg", "1e300"), {}, match="sigma_bearing_deg"),
    Case("tma-sigma-negative", cmd_tma("--sigma-bearing-deg", "-1"), {}, match="sigma_bearing_deg"),
    Case("tma-method-unknown", cmd_tma("--method", "magic"), {}, match="method"),
    Case("tma-env-notutf8", cmd_tma("--method", "em-map", "--sl", "140", "--env", "{config}"),
         {"config": raw_bytes("e.toml", NOT_UTF8)}, match="UTF-8"),
    Case("tma-env-unknownkey", cmd_tma("--method", "em-map", "--sl", "140", "--env", "{config}"),
         {"config": text("e.toml", "depth_m = [0.0, 100.0]\nsound_speed_mps = [1500.0, 1490.0]\nbogus = 1\n")},
         match="bogus"),
    *config_cases("tma", cmd_tma, "", "sigma_bearing_deg = \"one\"\n", "sigma_bearing_deg"),
    unwritable("tma", cmd_tma()),
    # ---- tl
    *[c for c in table_cases("tl-profile", cmd_tl(), "profile", "ctd.csv", col="sound_speed_mps", time_col="depth")
      if not c.id.endswith("huge")],  # unsorted or repeated depths are refused too (depths must increase strictly)
    Case("tl-profile-huge", cmd_tl(), {"profile": csv_edit("ctd.csv", set_cell("sound_speed_mps", 1e300))},
         match="sound_speed_mps"),
    Case("tl-profile-wrongunit", cmd_tl(), {"profile": csv_edit("ctd.csv", scale("sound_speed_mps", 1e-3))},
         match="km/s"),
    Case("tl-profile-negative-depth", cmd_tl(), {"profile": csv_edit("ctd.csv", set_cell("depth_m", -20.0, 1))},
         match="depth"),
    Case("tl-profile-toml-notutf8", cmd_tl(), {"profile": raw_bytes("p.toml", NOT_UTF8)}, match="UTF-8"),
    Case("tl-profile-toml-unknownkey", cmd_tl(),
         {"profile": text("p.toml", "depth_m = [0.0, 100.0]\nsound_speed_mps = [1500.0, 1490.0]\nbogus = 1\n")},
         match="bogus"),
    Case("tl-freq-huge", cmd_tl("--freq", "1e300"), {}, match="freq"),
    Case("tl-sl-nan", cmd_tl("--sl", "nan"), {}, match="sl_db"),
    Case("tl-nl-huge", cmd_tl("--nl", "1e300"), {}, match="nl_db"),  # was "SNR > 0 dB at none", exit 0
    Case("tl-average-huge", cmd_tl("--average", "1e300"), {}, match="average_m"),
    Case("tl-rmax-huge", cmd_tl("--rmax", "1e300"), {}, match="rmax_km"),
    Case("tl-waterdepth-negative", cmd_tl("--water-depth", "-5"), {}, match="water depth"),
    Case("tl-zs-negative", cmd_tl("--zs", "-50"), {}, match="source depth"),
    Case("tl-env-and-profile", cmd_tl("--env", "east-summer"), {}, match="exactly one"),
    *config_cases("tl", cmd_tl, "", 'nl_db = "loud"\n', "nl_db"),
    unwritable("tl", cmd_tl()),
    # ---- simulate
    *config_cases("simulate", cmd_simulate, "", 'seed = "lucky"\n', "seed"),
    Case("simulate-scene-empty", cmd_simulate("--scene", "{config}"), {"config": text("c.toml", "")}, "ok",
         answer="simulate: 5 s"),  # an empty scene file is the default scene
    Case("simulate-duration-negative", cmd_simulate("--duration-s", "-5"), {}, match="duration_s"),
    Case("simulate-duration-huge", cmd_simulate("--duration-s", "1e300"), {}, match="duration_s"),
    Case("simulate-duration-nan", cmd_simulate("--duration-s", "nan"), {}, match="duration_s"),
    Case("simulate-seed-negative", cmd_simulate("--seed", "-1"), {}, match="seed"),
    Case("simulate-propagation-unknown", cmd_simulate("--propagation", "magic"), {}, match="propagation"),
    Case("simulate-only-unknown", cmd_simulate("--only", "everything"), {}, match="only"),
    Case("simulate-seed-wrongtype", cmd_simulate("--seed", "abc"), {}, "usage"),
    unwritable("simulate", cmd_simulate()),
    # ---- reproduce (error cases only: a valid run is the studies' own tests)
    *config_cases("reproduce", cmd_reproduce, "", 'runs = "many"\n', "runs"),
    Case("reproduce-study-unknown", lambda f: ["reproduce", "no-such-study", "--out", f["out"]], {},
         match="no-such-study"),
    Case("reproduce-runs-negative", cmd_reproduce("--runs", "-1"), {}, match="--runs"),
    Case("reproduce-runs-huge", cmd_reproduce("--runs", "1e300"), {}, "usage"),
    Case("reproduce-seed-negative", cmd_reproduce("--seed", "-1"), {}, match="--seed"),
    Case("reproduce-workers-zero", cmd_reproduce("--workers", "0"), {}, match="--workers"),
    Case("reproduce-missing-study", lambda f: ["reproduce"], {}, "usage"),
    # ---- inputs that are fine, in a form the readers must still take: the same answer as the clean files
    Case("ok-bearings-valid", cmd_bearings(), {}, "ok", answer="bearings: 120 windows of 1 s"),
    Case("ok-contacts-scan-reordered", cmd_contacts(), {"contacts": csv_edit("contacts.csv", shuffle_within_scans)},
         "ok", answer="7 scans, 307 contacts -> 2 confirmed track(s)"),
    Case("ok-contacts-extra-column", cmd_contacts(), {"contacts": csv_edit("contacts.csv", add_column("note", "x"))},
         "ok", answer="7 scans, 307 contacts -> 2 confirmed track(s)"),
    Case("ok-raw-soundspeed-column", cmd_raw(), {"raw": csv_edit("raw.csv", add_column("sound_speed_mps", 1500.0))},
         "ok", answer="7 scans, 307 contacts -> 2 confirmed track(s)"),
    Case("ok-peaks-valid", cmd_peaks(), {}, "ok", answer="1 confirmed track(s)"),
    Case("ok-detect-valid", cmd_detect(), {}, "ok", answer="TARGET PRESENT"),
    Case("ok-detect-nothing-passes", cmd_detect("--threshold", "1e9"), {}, "ok", answer="no target"),
    Case("ok-peaks-nothing-starts", cmd_peaks("--config", "{config}"),
         {"config": text("c.toml", "[tracker]\ninit_amplitude = 1e5\namplitude_threshold = 9e4\n")}, "ok",
         answer="0 confirmed track(s) (0 started)"),
    Case("ok-tma-comment-line", cmd_tma(), {"brg": comment_first("brg.csv")}, "ok", answer="13 bearings over 0..120 s"),
    Case("ok-tl-extra-column", cmd_tl(), {"profile": csv_edit("ctd.csv", add_column("note", "ctd cast"))}, "ok",
         answer="tl ctd: 300 Hz, source 50 m, receiver 80 m, to 3 km"),
    Case("contacts-positions-km", cmd_contacts(),
         {"contacts": csv_edit("contacts.csv", lambda df: scale("y_m", 1e-3)(scale("x_m", 1e-3)(df)))},
         match="kilometres"),
    # ---- passive (the lead's new command): its rows go in PASSIVE_CASES below
    *PASSIVE_CASES,
]


def _argv(case: Case, src: Path, tmp: Path) -> list[str]:
    files = {"out": str(tmp / "out")}
    slots = dict(DEFAULTS)
    slots.update(case.files)
    for slot, make in slots.items():
        files[slot] = str(make(src, tmp)) if slot in case.files or slot in DEFAULTS else ""
    argv = case.argv(files)
    return [a.replace("{config}", files.get("config", "")) if isinstance(a, str) else str(a) for a in argv]


def run_case(case: Case, src: Path, tmp: Path, capsys) -> tuple[int, str, str]:
    code = main(_argv(case, src, tmp))
    out = capsys.readouterr()
    return code, out.out, out.err


def check_outcome(case: Case, code: int, out: str, err: str) -> None:
    assert "Traceback" not in out + err
    if case.expect == "ok":
        assert code == 0, err
        assert "error:" not in err and case.answer in out, (case.answer, out)
        return
    assert code == 2, (code, out, err)
    if case.expect == "usage":
        assert "Usage: sonartrack" in out + err
        return
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert case.match.lower() in lines[0].lower(), (case.match, lines[0])
    assert "internal error" not in lines[0]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case, inputs, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(inputs / "cache"))
    code, out, err = run_case(case, inputs, tmp_path, capsys)
    check_outcome(case, code, out, err)
    if case.expect != "ok":
        assert not (tmp_path / "out").exists()  # a refused run leaves no output folder behind


def test_case_ids_are_unique_and_every_class_is_covered():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    for cls in ("missing", "empty", "headeronly", "missingcolumn", "nan", "inf", "unsorted", "duplicated",
                "wrongunit", "huge", "negative", "filetype", "directory", "notutf8", "unknownkey", "wrongtype",
                "unwritable"):
        assert any(cls in i for i in ids), cls
