"""`sonartrack track --contacts`: a synthetic bistatic scenario, and every kind of bad file.

Each command runs in-process through :func:`sonartrack.cli.main` (the same code path as the console script, without
a fresh interpreter's import a test; tests/cli/test_entry.py checks the process itself).
"""

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.sim.bistatic_sonar import simulate_scan
from sonartrack.studies.bistatic_imm_ipda import Config


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    """Contacts of the P4 scenario (40 scans, no turn), plus raw bistatic columns and navigation."""
    from sonartrack.models.bistatic import bistatic_inputs

    folder = tmp_path_factory.mktemp("contacts")
    c = Config(n_scans=40, turn_start_s=1e6)
    ship, sonar, truth = c.ownship(), c.sonar(), c.target_states()
    rng = np.random.default_rng(5)
    rows, raw, nav = [], [], []
    for k, t in enumerate(c.times_s()):
        s = simulate_scan(rng, sonar, ship, float(t), truth[k, :2])
        for z, R in zip(s.z, s.R, strict=True):
            rows.append(dict(time_s=t, x_m=z[0], y_m=z[1], var_x_m2=R[0, 0], var_y_m2=R[1, 1], cov_xy_m2=R[0, 1]))
        rx, phi = ship.towed(t, c.rx_cable_m)
        tx, _ = ship.towed(t, c.tx_cable_m)
        tt, th = bistatic_inputs(s.z, tx, rx, phi, 1500.0)
        for a, b in zip(tt, th, strict=True):
            raw.append(dict(time_s=t, travel_time_s=a, bearing_deg=np.rad2deg(b)))
        nav.append(dict(time_s=t, tx_x_m=tx[0], tx_y_m=tx[1], rx_x_m=rx[0], rx_y_m=rx[1],
                        array_heading_deg=np.rad2deg(phi)))
    pd.DataFrame(rows).to_csv(folder / "contacts.csv", index=False)
    pd.DataFrame(rows).to_parquet(folder / "contacts.parquet")
    pd.DataFrame(raw).to_csv(folder / "raw.csv", index=False)
    pd.DataFrame(nav).to_csv(folder / "nav.csv", index=False)
    return folder, truth


@pytest.fixture
def run(capsys, monkeypatch):
    """``sonartrack track ARGS...`` in-process: its exit status, stdout and stderr."""
    monkeypatch.setenv("COLUMNS", "200")  # typer's usage text, as wide as in a terminal

    def call(*args):
        code = main(["track", *map(str, args)])
        out = capsys.readouterr()
        return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)
    return call


@pytest.mark.parametrize("name", ["contacts.csv", "contacts.parquet"])
def test_tracks_the_target(scenario, tmp_path, name, run):
    folder, truth = scenario
    res = run("--contacts", folder / name, "--out", tmp_path)
    assert res.returncode == 0, res.stderr
    tracks = pd.read_csv(tmp_path / "tracks.csv")
    assert {"time_s", "track_id", "status", "existence", "x_m", "y_m"} <= set(tracks.columns)
    assert tracks.existence.between(0, 1).all()
    last = tracks[(tracks.time_s == tracks.time_s.max()) & (tracks.status == "confirmed")]
    err = np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1])
    assert (err < 600).any(), "no confirmed track near the target at the last scan"
    assert (tmp_path / "tracks.png").stat().st_size > 1000


def test_raw_bistatic_with_navigation(scenario, tmp_path, run):
    folder, truth = scenario
    res = run("--contacts", folder / "raw.csv", "--nav", folder / "nav.csv", "--out", tmp_path, "--confirmed-only")
    assert res.returncode == 0, res.stderr
    tracks = pd.read_csv(tmp_path / "tracks.csv")
    assert (tracks.status == "confirmed").all()
    last = tracks[tracks.time_s == tracks.time_s.max()]
    assert (np.hypot(last.x_m - truth[-1, 0], last.y_m - truth[-1, 1]) < 600).any()


def assert_error(res, out, *words):
    assert res.returncode == 2, res.stdout + res.stderr
    lines = [ln for ln in res.stderr.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:") and "Traceback" not in res.stderr, res.stderr
    for w in words:
        assert w in lines[0], lines[0]
    assert not out.exists() or not any(out.iterdir()), "partial output written"


def bad_file(scenario, tmp_path, edit):
    folder, _ = scenario
    df = pd.read_csv(folder / "contacts.csv")
    df = edit(df)
    p = tmp_path / "bad.csv"
    df.to_csv(p, index=False)
    return p


def test_missing_column(scenario, tmp_path, run):
    p = bad_file(scenario, tmp_path, lambda d: d.drop(columns=["y_m"]))
    assert_error(run("--contacts", p, "--out", tmp_path / "o"), tmp_path / "o", "y_m")


def test_nan_values(scenario, tmp_path, run):
    def edit(d):
        d.loc[7, "x_m"] = np.nan
        return d
    assert_error(run("--contacts", bad_file(scenario, tmp_path, edit), "--out", tmp_path / "o"), tmp_path / "o",
                 "x_m", "row 8")


def test_unsorted_times(scenario, tmp_path, run):
    p = bad_file(scenario, tmp_path, lambda d: d.iloc[::-1])
    assert_error(run("--contacts", p, "--out", tmp_path / "o"), tmp_path / "o", "sort")


def test_wrong_unit(scenario, tmp_path, run):
    p = bad_file(scenario, tmp_path, lambda d: d.assign(x_m=d.x_m / 1e3).rename(columns={"x_m": "x_km"}))
    assert_error(run("--contacts", p, "--out", tmp_path / "o"), tmp_path / "o", "x_km", "x_m")


def test_raw_without_navigation(scenario, tmp_path, run):
    folder, _ = scenario
    assert_error(run("--contacts", folder / "raw.csv", "--out", tmp_path / "o"), tmp_path / "o", "--nav")


def test_no_covariance_and_no_default(scenario, tmp_path, run):
    p = bad_file(scenario, tmp_path, lambda d: d[["time_s", "x_m", "y_m"]])
    assert_error(run("--contacts", p, "--out", tmp_path / "o"), tmp_path / "o", "default_sigma_m")


def test_malformed_and_empty_files(tmp_path, run):
    p = tmp_path / "x.parquet"
    p.write_text("not parquet")
    assert_error(run("--contacts", p, "--out", tmp_path / "o"), tmp_path / "o", "Parquet")
    q = tmp_path / "e.csv"
    q.write_text("time_s,x_m,y_m\n")
    assert_error(run("--contacts", q, "--out", tmp_path / "o"), tmp_path / "o", "no rows")


def test_needs_exactly_one_input(tmp_path, run):
    assert_error(run("--out", tmp_path / "o"), tmp_path / "o", "--contacts")


@pytest.mark.parametrize("kind", ["--contacts", "--peaks"])
def test_print_config_reads_back_to_the_same_settings(tmp_path, kind, run):
    """The printed TOML is the library's declarations with their defaults, and --config reads it back unchanged."""
    from sonartrack.io import toml as toml_io
    from sonartrack.systems.track.settings import ContactsTrackSettings, PeaksTrackSettings
    from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings

    model, tracker = ((ContactsTrackSettings, PositionTrackerSettings) if kind == "--contacts"
                      else (PeaksTrackSettings, BearingTrackerSettings))
    res = run(kind, tmp_path / "unused.csv", "--print-config")
    assert res.returncode == 0, res.stderr
    (tmp_path / "c.toml").write_text(res.stdout)
    printed = toml_io.validate(model, toml_io.load(tmp_path / "c.toml"))
    assert printed == model() and printed.tracker == tracker()
    assert "[tracker]" in res.stdout
    # a changed value survives the round trip, and the file then drives --print-config again
    edited = res.stdout.replace("gate_probability = 0.99", "gate_probability = 0.95").replace(
        "gate_deg = 10.0", "gate_deg = 8.0")
    (tmp_path / "d.toml").write_text(edited)
    again = run(kind, tmp_path / "unused.csv", "--config", tmp_path / "d.toml", "--print-config")
    assert again.returncode == 0 and again.stdout == edited


def test_peaks_tracker_option_overrides_the_config(tmp_path, run):
    res = run("--peaks", tmp_path / "unused.csv", "--tracker", "jpda", "--print-config")
    assert res.returncode == 0 and 'associator = "jpda"' in res.stdout


def test_flat_tracker_keys_are_pointed_to_the_tracker_table(scenario, tmp_path, run):
    folder, _ = scenario
    (tmp_path / "flat.toml").write_text("q = [0.001]\npd = 0.9\n")
    res = run("--contacts", folder / "contacts.csv", "--config", tmp_path / "flat.toml", "--out", tmp_path / "o")
    assert_error(res, tmp_path / "o", "[tracker]", "pd, q")
