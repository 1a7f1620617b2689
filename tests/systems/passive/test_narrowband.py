"""The passive chain's narrowband stage (systems/passive/narrowband.py): the refinement of a line's cone angle and
frequency against a closed form, the roles of line sources against bearing tracks, the tonal of a line, the joining of
a line's fragments across the array's turn (hand-built: one ship's fragments joined; another ship's on the same line,
another frequency, or without the turn's shift not joined) and its outliers left out, and end to
end on a short simulated default scene: the quiet submarine, which the broadband front end never detects, reported
as a narrowband target on its true side, bearing and tonal; no narrowband target on a noise-only recording; the
outputs written (lines.csv, lofar.png, targets.csv's origin) and none left behind by a run that fails."""

from __future__ import annotations

import contextlib
import io
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from sonartrack.acoustics.lofar import LineDetections, LofarGram
from sonartrack.cli import main
from sonartrack.core.angles import bearing_rad, wrap_angle
from sonartrack.io.navigation import Navigation
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.passive import PassiveSettings
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.narrowband import (
    NarrowbandLines,
    SourceRoles,
    refined_detections,
    source_roles,
    tonal_at,
)
from sonartrack.systems.passive.narrowband_targets import narrowband_records
from sonartrack.tracking.line_tracks import LineSource, LineTrack

#: the default scene (default ships, ``--propagation ram`` as in the README), short, the ownship's turn early so
#: that the submarine's line gives its side within the recording
SHORT_SCENE = "duration_s = 360.0\n[ownship]\nturn_start_s = 120.0\n"


def _stages():
    return PassiveSettings(spacing_m=2.5, elements=16).stages(4000.0)


def _gaussian_gram(c0: float, f0: float, beam_sd: float = 4.0, bin_sd: float = 0.8) -> LofarGram:
    """One period; power = 1 + A exp(-(c - c0)^2 / 2 s_c^2 - (f - f0)^2 / 2 s_f^2) over a background of 1, so
    z = power and P - mu = the Gaussian: its log is a parabola in each axis, whose vertex is exactly (c0, f0)."""
    cone = np.linspace(0.0, 180.0, 61)
    freqs = np.arange(150.0, 250.0, 1.0)
    g = 50.0 * np.exp(-((cone[:, None] - c0) ** 2) / (2 * beam_sd**2) - ((freqs[None, :] - f0) ** 2) / (2 * bin_sd**2))
    power = (1.0 + g)[None]
    return LofarGram(np.array([8.0]), cone, freqs, power, power.copy())


@pytest.mark.parametrize("start_offset", [0, 2, -2])
def test_refinement_finds_the_vertex_of_a_gaussian_line_exactly(start_offset):
    c0, f0 = 113.7, 200.3
    gram = _gaussian_gram(c0, f0)
    b = int(np.argmin(np.abs(gram.cone_deg - c0))) + start_offset  # a detection up to two beams off climbs back
    k = int(np.argmin(np.abs(gram.freqs_hz - f0)))
    d = LineDetections(np.array([8.0]), gram.cone_deg[[b]], gram.freqs_hz[[k]], np.array([50.0]), np.array([17.0]),
                       np.array([b]))
    r = refined_detections(gram, d)
    assert r.cone_deg[0] == pytest.approx(c0, abs=1e-9)
    assert r.frequency_hz[0] == pytest.approx(f0, abs=1e-9)


def _line(track_id, t, f, cone, snr=8.0):
    n = len(t)
    return LineTrack(track_id, t, np.full(n, f), cone, np.zeros(n), np.zeros(n), np.full(n, snr), True,
                     np.full(n, f), cone)


def test_sources_follow_tracks_leak_or_stand_alone():
    t = (np.arange(20) + 0.5) * 16.0
    tracks = [TrackMeasurements(1, t, 60.0 + 0.01 * t, np.ones(20), t, 60.0 + 0.01 * t)]
    # line 1 follows the track (2 deg off: within half a 9.6 deg beam at 200 Hz); line 2 is at the track's tonal
    # frequency 30 deg away (a leak); line 3 is another frequency far from every track (a target of its own)
    lines = (_line(1, t, 200.0, 62.0 + 0.01 * t), _line(2, t, 120.4, 95.0 + 0 * t), _line(3, t, 150.0, 130.0 + 0 * t))
    sources = tuple(LineSource(i, (i,), (), np.nan) for i in (1, 2, 3))
    tonal = tonal_at(t, np.full(20, 120.0), np.full(20, 9.0), t, _stages())
    roles = source_roles(NarrowbandLines(None, lines, sources), tracks, [tonal], _stages())
    assert roles.track == {1: 0}
    assert set(roles.leak) == {2} and roles.leak[2] == pytest.approx(120.0)


def test_tonal_has_one_frequency_per_period_at_the_nearest_record_time():
    period = (np.arange(5) + 0.5) * 16.0  # 8, 24, ... (the gram's period centres)
    record = np.arange(0.5, 80.0, 1.0)  # the bearing track's window centres
    tonal = tonal_at(period, 200.0 + 0.01 * np.arange(5), np.full(5, 6.0), record, _stages())
    assert np.all(np.isin(tonal.time_s, record)) and len(tonal.time_s) == 5
    assert np.all(np.abs(tonal.time_s - period) <= 0.5)
    assert tonal.line_hz == pytest.approx(200.02)
    assert tonal.line_snr_db == pytest.approx(6.0)


#: the narrowband periods (s) and the array: 3 m/s north, turning 45 deg to port at 0.5 deg/s from 600 s (no tow)
PERIODS = (np.arange(75) + 0.5) * 16.0


def _turning_nav() -> Navigation:
    t = np.arange(0.0, 1201.0, 1.0)
    own, _, heading = ManeuveringTrack(0.0, 0.0, 3.0, 0.0, ((600.0, 690.0, -np.deg2rad(0.5)),)).state(t)
    return Navigation(t, own[:, 0], own[:, 1], heading, own[:, 0], own[:, 1], heading)


def _cone_deg(x0, t, nav, sd_deg=1.0, seed=0):
    """Cone angles (deg, ``sd_deg`` Gaussian noise) of a CV target [x, y, vx, vy] (m, m/s at t = 0) at times t."""
    xy, heading = nav.array_at(t)
    tgt = np.asarray(x0[:2]) + t[:, None] * np.asarray(x0[2:])
    rel = wrap_angle(bearing_rad(tgt[:, 0] - xy[:, 0], tgt[:, 1] - xy[:, 1]) - heading)
    return np.clip(np.rad2deg(np.abs(rel)) + np.random.default_rng(seed).normal(0.0, sd_deg, len(t)), 0.0, 180.0)


#: the submarine-like target (port, about 4.6 km, moving slowly) and another ship on the same side whose cone angle
#: after the array's turn lies about 10 deg from the first's (a beam away at 200 Hz)
PORT_SHIP = [-4000.0, 2500.0, 1.5, 1.0]
OTHER_SHIP = [-3000.0, 5500.0, 1.0, -2.0]


def _sources(spans, ships, freqs, nav):
    """Line tracks (one per source) over the given spans (s) of the given ships at the given frequencies."""
    lines, sources = [], []
    for i, ((t0, t1), ship, f) in enumerate(zip(spans, ships, freqs, strict=True)):
        t = PERIODS[(t0 <= PERIODS) & (t1 >= PERIODS)]
        lines.append(_line(i + 1, t, f, _cone_deg(ship, t, nav, seed=i + 1), snr=4.0))
        sources.append(LineSource(i + 1, (i + 1,), (), np.nan))
    return NarrowbandLines(None, tuple(lines), tuple(sources))


def _records(nb, nav):
    return narrowband_records(nb, SourceRoles({}, {}), nav, _stages())


def test_fragments_of_one_line_on_either_side_of_the_turn_are_joined():
    nav = _turning_nav()
    nb = _sources([(72.0, 600.0), (790.0, 1020.0), (1080.0, 1180.0)], [PORT_SHIP] * 3, [200.1, 200.0, 199.9], nav)
    out = _records(nb, nav)
    assert len(out) == 1
    m, tonal = out[0]
    assert m.track_id == 1 and m.joined_track_ids == (2, 3)
    assert m.time_s[0] == pytest.approx(72.0, abs=16.0) and m.time_s[-1] == pytest.approx(1180.0, abs=16.0)
    assert tonal.line_hz == pytest.approx(200.0, abs=0.1)


def test_a_later_fragment_of_another_ship_on_the_same_line_is_not_joined():
    nav = _turning_nav()
    late = (PERIODS >= 790.0) & (PERIODS <= 1020.0)
    sep = np.abs(_cone_deg(PORT_SHIP, PERIODS[late], nav, 0.0) - _cone_deg(OTHER_SHIP, PERIODS[late], nav, 0.0))
    assert sep.min() > 6.0  # the geometry is as stated: the two ships a beam apart after the turn
    nb = _sources([(72.0, 600.0), (790.0, 1020.0)], [PORT_SHIP, OTHER_SHIP], [200.0, 200.0], nav)
    out = _records(nb, nav)
    assert [m.track_id for m, _ in out] == [1, 2] and all(m.joined_track_ids == () for m, _ in out)


def test_fragments_on_different_frequencies_are_not_joined():
    nav = _turning_nav()
    nb = _sources([(72.0, 600.0), (790.0, 1020.0)], [PORT_SHIP] * 2, [200.0, 230.0], nav)
    out = _records(nb, nav)
    assert [m.track_id for m, _ in out] == [1, 2] and all(m.joined_track_ids == () for m, _ in out)


def test_a_later_fragment_that_ignores_the_turn_is_not_joined():
    """The later fragment's cone angles are the target's through the array's 45 deg turn to port (a port target's
    cone angle falls by the turn). Moved back by the turn, as if the array had held its heading, they are not
    joined: only the navigation's turn ties the fragments."""
    nav = _turning_nav()
    nb = _sources([(72.0, 600.0), (790.0, 1020.0)], [PORT_SHIP] * 2, [200.0, 200.0], nav)
    late = nb.lines[1]
    unturned = replace(late, measured_cone_deg=late.measured_cone_deg + 45.0, cone_deg=late.cone_deg + 45.0)
    assert [m.joined_track_ids for m, _ in _records(nb, nav)] == [(2,)]
    out = _records(replace(nb, lines=(nb.lines[0], unturned)), nav)
    assert [m.joined_track_ids for m, _ in out] == [(), ()]


def test_outliers_off_the_constant_velocity_fit_are_left_out():
    nav = _turning_nav()
    t = PERIODS[(PERIODS >= 72.0) & (PERIODS <= 1000.0)]
    cone = _cone_deg(PORT_SHIP, t, nav, seed=5)
    cone[[10, 30]] += [21.0, -15.0]
    nb = NarrowbandLines(None, (_line(1, t, 200.0, cone),), (LineSource(1, (1,), (), np.nan),))
    (m, _), = _records(nb, nav)
    assert len(m.time_s) == len(t) - 2 and not np.isin(t[[10, 30]], m.time_s).any()


@pytest.fixture(scope="module")
def short_scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("narrowband_scene")
    (out / "in.toml").write_text(SHORT_SCENE)
    assert main(["simulate", "--scene", str(out / "in.toml"), "--only", "passive", "--propagation", "ram",
                 "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def cli_run(short_scene, tmp_path_factory):
    """(exit code, --out folder, stdout) of the README's first passive command line on the short scene."""
    out = tmp_path_factory.mktemp("narrowband_out") / "passive"
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        code = main(["passive", "--wav", str(short_scene / "recording.wav"), "--nav", str(short_scene / "nav.csv"),
                     "--spacing", "2.5", "--out", str(out)])
    return code, out, printed.getvalue()


def test_the_submarine_is_a_narrowband_target_on_its_side_bearing_and_tonal(cli_run, short_scene):
    code, out, _ = cli_run
    assert code == 0
    truth = pd.read_csv(short_scene / "truth.csv")
    sub = truth[truth.ship == "submarine"]
    targets = pd.read_csv(out / "targets.csv")
    ml = targets[(targets.method == "ml") & (targets.origin == "narrowband")]
    assert ml.target_id.nunique() == 1, f"narrowband targets: {sorted(ml.target_id.unique())}"
    last = ml.iloc[-1]
    assert last.side == sub.side.iloc[-1] == "port"
    true_bearing = np.interp(last.time_s, sub.time_s, sub.bearing_deg)
    assert abs((last.bearing_deg - true_bearing + 180.0) % 360.0 - 180.0) < 3.0
    # its tonal within a bin (1 Hz at the 1 s window) of the received 200 Hz line
    true_f = np.interp(last.time_s, sub.time_s, sub.tonal_hz)
    assert abs(np.nanmean(ml.frequency_hz) - true_f) < 1.0
    # the broadband targets are the other ships, not it: none of them follows the submarine
    assert set(targets[targets.origin == "broadband"].target_id) and "narrowband" in set(targets.origin)


def test_outputs_hold_the_lines_and_the_lofar_picture(cli_run):
    _, out, _ = cli_run
    lines = pd.read_csv(out / "lines.csv")
    assert {"line_id", "source_id", "target_id", "time_s", "frequency_hz", "cone_deg", "frequency_rate_hz_s",
            "cone_rate_deg_s", "snr_db", "harmonic"} <= set(lines.columns)
    targets = pd.read_csv(out / "targets.csv")
    nb = targets[targets.origin == "narrowband"].target_id.iloc[0]
    fed = lines[lines.target_id == nb]
    assert len(fed) and np.all(np.abs(fed.frequency_hz - 200.2) < 1.0)
    assert (out / "lofar.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = (out / "index.html").read_text()
    assert "<td>narrowband</td>" in page and page.count("data:image/png;base64") == 3
    assert not list(out.glob("*.tmp*")) and not list(out.glob(".*tmp*"))


def test_summary_line_marks_the_narrowband_target(cli_run):
    lines = [ln for ln in cli_run[2].splitlines() if "(narrowband, " in ln]
    assert len(lines) == 1 and lines[0].startswith("target ") and ": port " in lines[0] and "200." in lines[0]


def test_a_failing_run_leaves_none_of_its_files(short_scene, tmp_path, monkeypatch, capsys):
    import sonartrack.report.figures.passive as figures

    def broken(result):
        raise RuntimeError("drawing failed")

    monkeypatch.setattr(figures, "lofar_picture", broken)
    out = tmp_path / "p"
    code = main(["passive", "--wav", str(short_scene / "recording.wav"), "--nav", str(short_scene / "nav.csv"),
                 "--spacing", "2.5", "--out", str(out)])
    assert code == 1 and "internal error" in capsys.readouterr().err
    assert not (out / "lines.csv").exists() and not (out / "targets.csv").exists()


def test_noise_only_recording_gives_no_narrowband_target(tmp_path, capsys):
    (tmp_path / "quiet.toml").write_text("duration_s = 320.0\nships = []\n")
    assert main(["simulate", "--scene", str(tmp_path / "quiet.toml"), "--only", "passive", "--out", str(tmp_path)]) == 0
    out = tmp_path / "out"
    assert main(["passive", "--wav", str(tmp_path / "recording.wav"), "--nav", str(tmp_path / "nav.csv"),
                 "--spacing", "2.5", "--out", str(out)]) == 0
    assert "no target" in capsys.readouterr().out
    assert len(pd.read_csv(out / "targets.csv")) == 0
    assert (out / "lines.csv").exists() and (out / "lofar.png").exists()
