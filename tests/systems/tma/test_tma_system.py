"""The tma system from Python: arrays in, a solved record out; the environment looked up; the same file as the CLI."""

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.core.units import KNOT_MPS as KN
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.systems.tma import run as run_mod
from sonartrack.systems.tma.files import read_tma_inputs, write_tma_solution
from sonartrack.systems.tma.run import run_tma, tma_environment
from sonartrack.systems.tma.settings import TmaSettings
from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.solve import TmaResult


@pytest.fixture(scope="module")
def scenario():
    """Noise-free bearings every 4 s of a CV target (10 kn, 10 km) from an ownship that zig-zags twice."""
    t = np.arange(0.0, 1600.0 + 1e-9, 4.0)
    obs = ManeuveringTrack(0.0, 0.0, 5 * KN, np.deg2rad(45), ((500.0, 540.0, np.deg2rad(-2.25)),
                                                             (1100.0, 1140.0, np.deg2rad(2.25))))
    tgt = ManeuveringTrack(-3000.0, 9500.0, 10 * KN, np.deg2rad(100))
    po, _, _ = obs.state(t)
    pt, vt, _ = tgt.state(t)
    d = pt - po
    record = BearingRecord(time_s=t, bearing_rad=np.arctan2(d[:, 0], d[:, 1]))
    return record, OwnshipTrack(time_s=t, x_m=po[:, 0], y_m=po[:, 1]), np.column_stack([pt, vt])


def test_batch_ml_on_arrays_finds_the_target(scenario):
    record, own, truth = scenario
    result = run_tma(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.1))
    assert isinstance(result, TmaResult) and result.solution.state.shape == (len(record.time_s), 4)
    # noise-free bearings and a two-leg maneuver: the ML solution is the truth to within a few metres
    np.testing.assert_allclose(result.solution.state[-1], truth[-1], atol=5.0)


def test_the_environment_is_looked_up_only_where_it_is_used():
    assert tma_environment(TmaSettings(method="mgekf", batch={"env": "east-summer"})) is None
    assert tma_environment(TmaSettings(method="em-map")) is None
    assert tma_environment(TmaSettings(method="em-map", batch={"env": "east-summer"})).name == "east-summer"


def test_run_tma_hands_the_looked_up_environment_to_the_solver(scenario, monkeypatch):
    record, own, _ = scenario
    seen = {}

    def fake_solve(record, ownship, settings, *, environment, tl_store):
        seen.update(environment=environment, tl_store=tl_store)
        return "solved"

    monkeypatch.setattr(run_mod, "solve_tma", fake_solve)
    s = TmaSettings(method="em-map", batch={"env": "east-summer", "sl_db": 140.0})
    assert run_tma(record, own, s, tl_store="store") == "solved"
    assert seen["environment"].name == "east-summer" and seen["tl_store"] == "store"
    given = tma_environment(TmaSettings(method="em-map", batch={"env": "south-summer"}))
    run_tma(record, own, s, environment=given)
    assert seen["environment"] is given  # a given environment wins over settings.batch.env


def test_files_and_run_write_what_the_cli_writes(scenario, tmp_path, capsys):
    record, own, _ = scenario
    pd.DataFrame({"time_s": record.time_s, "bearing_deg": np.rad2deg(record.bearing_rad) % 360}).to_csv(
        tmp_path / "brg.csv", index=False)
    pd.DataFrame({"time_s": own.time_s, "x_m": own.x_m, "y_m": own.y_m}).to_csv(tmp_path / "own.csv", index=False)
    assert main(["tma", "--bearings", str(tmp_path / "brg.csv"), "--ownship", str(tmp_path / "own.csv"),
                 "--method", "mgekf", "--out", str(tmp_path / "cli")]) == 0
    capsys.readouterr()
    s = TmaSettings(method="mgekf")
    inputs = read_tma_inputs(tmp_path / "brg.csv", tmp_path / "own.csv", s)
    assert inputs.environment is None
    path = write_tma_solution(run_tma(inputs.record, inputs.ownship, s), tmp_path / "py")
    assert path.read_bytes() == (tmp_path / "cli" / "tma_solution.csv").read_bytes()
