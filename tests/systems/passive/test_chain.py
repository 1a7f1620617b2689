"""The passive chain end to end on a simulated scene: targets on the right side, ML within its uncertainty,
clean outputs, and one-line errors for inputs that do not fit."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.systems.passive import PassiveSettings, run_passive_files
from sonartrack.tma.solution_table import solution_columns


@pytest.fixture(scope="module")
def result(scene_dir):
    return run_passive_files(scene_dir / "recording.wav", scene_dir / "nav.csv", PassiveSettings(spacing_m=2.5))


def _ship_of(target, truth):
    """(ship, median cone offset deg) of the ship whose true cone angle the target's peaks follow."""
    best = None
    for ship, g in truth.groupby("ship"):
        cone = np.interp(target.track.time_s, g["time_s"], g["cone_deg"])
        off = float(np.median(np.abs(cone - target.track.cone_deg)))
        if best is None or off < best[1]:
            best = (ship, off)
    return best


def test_targets_follow_ships_on_their_true_side(result, scene_dir):
    truth = pd.read_csv(scene_dir / "truth.csv")
    matched = {}
    for tg in result.targets:
        ship, off = _ship_of(tg, truth)
        assert off < 2.0, f"target {tg.target_id} follows no ship (median offset {off:.1f} deg)"
        matched[ship] = tg
        if tg.side.side != "unresolved":
            side = truth[(truth.ship == ship)]["side"].iloc[-1]
            assert tg.side.side == side, f"{ship}: {tg.side.side}, truth {side}"
    assert set(matched) == {"merchant", "trawler", "tanker"}, f"ships found: {sorted(matched)}"
    assert [matched[s].side.side for s in ("merchant", "trawler", "tanker")] == ["starboard", "starboard", "port"]


def test_ml_position_within_its_uncertainty(result, scene_dir):
    truth = pd.read_csv(scene_dir / "truth.csv")
    judged = 0
    for tg in result.targets:
        ship, _ = _ship_of(tg, truth)
        cols = solution_columns(tg.ml.solution, tg.ml.ownship)
        if not cols["range_determined"][-1]:
            continue
        t_end = cols["time_s"][-1]
        g = truth[truth.ship == ship]
        x, y = np.interp(t_end, g["time_s"], g["x_m"]), np.interp(t_end, g["time_s"], g["y_m"])
        P = tg.ml.solution.covariance[-1, :2, :2]
        d = np.array([cols["x_m"][-1] - x, cols["y_m"][-1] - y])
        # squared Mahalanobis distance of the truth: chi-square(2); 1e-4 quantile is 18.4
        assert d @ np.linalg.solve(P, d) < 18.4, f"{ship}: ML misses the truth by {np.hypot(*d):.0f} m"
        judged += 1
    assert judged >= 2, f"only {judged} ship(s) had their range determined"


def test_cli_writes_every_output_and_a_line_per_target(scene_dir, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["passive", "--wav", str(scene_dir / "recording.wav"), "--nav", str(scene_dir / "nav.csv"),
                 "--spacing", "2.5", "--out", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    for name in ("peaks.csv", "bearing_tracks.csv", "targets.csv", "bearing_time.png", "tactical.png", "index.html"):
        assert (out / name).stat().st_size > 0, name
    targets = pd.read_csv(out / "targets.csv")
    n = targets["target_id"].nunique()
    assert n >= 2 and sum(line.startswith("target ") for line in lines) == n
    assert set(targets["method"]) == {"ml", "imm-mgekf"}
    assert {"side", "side_log_lr", "range_m", "range_std_m", "course_deg", "speed_kn", "frequency_hz",
            "range_determined"} <= set(targets.columns)


def test_noise_only_recording_gives_empty_outputs_and_says_so(tmp_path, capsys):
    scene = tmp_path / "quiet.toml"
    scene.write_text("duration_s = 120.0\nships = []\n")
    assert main(["simulate", "--scene", str(scene), "--only", "passive", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    out = tmp_path / "out"
    assert main(["passive", "--wav", str(tmp_path / "recording.wav"), "--nav", str(tmp_path / "nav.csv"),
                 "--spacing", "2.5", "--out", str(out)]) == 0
    assert "no target" in capsys.readouterr().out
    assert len(pd.read_csv(out / "targets.csv")) == 0 and (out / "index.html").exists()


def _short_nav(scene_dir, tmp_path):
    nav = pd.read_csv(scene_dir / "nav.csv")
    p = tmp_path / "short_nav.csv"
    nav[nav.time_s <= 100].to_csv(p, index=False)
    return p


@pytest.mark.parametrize(("extra", "words"), [
    (["--elements", "8"], "16 channels but --elements is 8"),
    (["--band-hz", "50", "1000"], "aliases above 300.0 Hz"),
    (["--nav", "SHORT"], "covers 0..100 s"),
    (["--wav", "NOTWAV"], "WAV"),
])
def test_inputs_that_do_not_fit_are_one_line_errors(scene_dir, tmp_path, capsys, extra, words):
    notwav = tmp_path / "x.wav"
    notwav.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    swap = {"SHORT": str(_short_nav(scene_dir, tmp_path)), "NOTWAV": str(notwav)}
    args = {"--wav": str(scene_dir / "recording.wav"), "--nav": str(scene_dir / "nav.csv")}
    opts = [swap.get(a, a) for a in extra]
    for k in ("--wav", "--nav"):
        if k in opts:
            args[k] = opts[opts.index(k) + 1]
            del opts[opts.index(k):opts.index(k) + 2]
    code = main(["passive", "--wav", args["--wav"], "--nav", args["--nav"], "--spacing", "2.5", *opts,
                 "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("error:") and words in err[0], err
    assert not (tmp_path / "o" / "targets.csv").exists()


def test_two_channel_recording_uses_the_two_sensor_correlator(scene_dir, tmp_path, capsys):
    # pair.wav: elements 1 and 9 of the array, 20 m apart (paper P0's two-sensor situation)
    out = tmp_path / "pair"
    assert main(["passive", "--wav", str(scene_dir / "pair.wav"), "--nav", str(scene_dir / "nav.csv"),
                 "--spacing", "20", "--out", str(out)]) == 0
    assert "method = \"split-array\"" in (out / "index.html").read_text().replace("&quot;", '"')
    truth = pd.read_csv(scene_dir / "truth.csv")
    targets = pd.read_csv(out / "targets.csv")
    merchant = truth[truth.ship == "merchant"]
    # the loudest ship is found, on its true side
    found = [
        g for _, g in targets[targets.method == "ml"].groupby("target_id")
        if np.median(np.abs(((g["bearing_deg"].to_numpy() - np.interp(g["time_s"], merchant["time_s"],
                                                                        merchant["bearing_deg"])) + 180) % 360 - 180))
        < 2.0
    ]
    assert found and found[0]["side"].iloc[0] == "starboard"
