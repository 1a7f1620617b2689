"""Runner: determinism across worker counts and schedulers, resume after interruption, storage."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from sonartrack import studies
from sonartrack.cli import main as cli_main
from sonartrack.core.errors import InputError
from sonartrack.experiment import pipeline, runner, store

STUDY = "bistatic-imm-ipda"
STUDY_MODULE = studies.STUDIES[STUDY]  # the runner is given the module, never the registry


def small_config(runs=6):
    mod = studies.load(STUDY)
    return mod, pipeline.resolve_config(mod, quick=True, runs=runs, overrides={"n_scans": 12, "turn_start_s": 180.0})


def run(tmp, workers=1, scheduler=None, runs=6, chunk=2):
    mod, cfg = small_config(runs)
    plan = runner.plan_run(mod, cfg, runs, seed=7, out_dir=tmp, chunk_size=chunk)
    return plan, runner.execute(plan, cfg, workers=workers, scheduler=scheduler)


def assert_same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_same_trials_with_one_and_two_workers(tmp_path):
    _, one = run(tmp_path / "a", workers=1)
    _, two = run(tmp_path / "b", workers=2)
    assert_same(one, two)


def test_same_trials_on_a_dask_localcluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    _, one = run(tmp_path / "a", workers=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        _, dask_trials = run(tmp_path / "b", scheduler=cluster.scheduler_address)
    assert_same(one, dask_trials)


def test_different_seeds_give_different_trials(tmp_path):
    mod, cfg = small_config(2)
    a = runner.run_chunk(STUDY_MODULE, cfg.model_dump(mode="json"), 1, (0, 1))
    b = runner.run_chunk(STUDY_MODULE, cfg.model_dump(mode="json"), 2, (0, 1))
    assert not np.array_equal(a["meas_error_xy"], b["meas_error_xy"], equal_nan=True)


def test_trial_i_does_not_depend_on_chunking(tmp_path):
    mod, cfg = small_config(4)
    whole = runner.run_chunk(STUDY_MODULE, cfg.model_dump(mode="json"), 3, (0, 1, 2, 3))
    last = runner.run_chunk(STUDY_MODULE, cfg.model_dump(mode="json"), 3, (3,))
    for k in whole:
        np.testing.assert_array_equal(whole[k][3], last[k][0])


def test_interrupted_run_resumes_without_recomputing(tmp_path):
    mod, cfg = small_config(6)
    plan = runner.plan_run(mod, cfg, 6, seed=7, out_dir=tmp_path, chunk_size=2)
    calls = []

    def stop_after_first(n):
        calls.append(n)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        runner.execute(plan, cfg, workers=1, on_chunk=stop_after_first)
    first = sorted(plan.cache_dir.glob("trials-*.parquet"))
    assert [p.name for p in first] == ["trials-000000-000002.parquet"]
    stamp = first[0].stat().st_mtime_ns, first[0].stat().st_ino

    plan2 = runner.plan_run(mod, cfg, 6, seed=7, out_dir=tmp_path, chunk_size=2)
    assert plan2.todo_chunks == ((2, 3), (4, 5))  # the finished chunk is not planned again
    resumed = runner.execute(plan2, cfg, workers=1)
    assert (first[0].stat().st_mtime_ns, first[0].stat().st_ino) == stamp  # and not rewritten
    _, fresh = run(tmp_path / "fresh", runs=6, chunk=2)
    assert_same(resumed, fresh)


def test_killed_process_resumes_to_the_same_trials(tmp_path):
    """A real `sonartrack reproduce` killed with SIGKILL mid-run, then rerun."""
    out = tmp_path / "out"
    cfg = tmp_path / "c.toml"
    cfg.write_text("n_scans = 12\nturn_start_s = 180.0\n")
    cmd = [sys.executable, "-m", "sonartrack.cli", "reproduce", STUDY, "--runs", "40", "--workers", "1",
           "--out", str(out), "--config", str(cfg), "--seed", "11"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    cache = out / STUDY / "cache"
    deadline = time.time() + 120
    while time.time() < deadline and not list(cache.glob("*/trials-*.parquet")):
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done_before = {p.name: p.stat().st_mtime_ns for p in cache.glob("*/trials-*.parquet")}
    assert done_before, "no chunk finished before the kill"
    assert not (out / STUDY / "summary.json").exists() or len(done_before) == 4
    # leftovers of the killed write are temporary files, never a chunk that looks complete
    for p in cache.glob("*/trials-*.parquet"):
        store.read_table(p)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for p in cache.glob("*/trials-*.parquet"):
        if p.name in done_before:
            assert p.stat().st_mtime_ns == done_before[p.name]
    resumed = store.read_table(out / STUDY / "trials.parquet")[1]
    # the run never interrupted: in this process (the same command, without a second interpreter's start-up)
    assert cli_main(cmd[3:-6] + ["--out", str(tmp_path / "fresh"), "--config", str(cfg), "--seed", "11"]) == 0
    fresh = store.read_table(tmp_path / "fresh" / STUDY / "trials.parquet")[1]
    assert_same(resumed, fresh)


def test_more_runs_reuse_stored_trials(tmp_path):
    plan, _ = run(tmp_path, runs=4, chunk=2)
    mod, cfg = small_config(8)
    plan8 = runner.plan_run(mod, cfg, 8, seed=7, out_dir=tmp_path, chunk_size=2)
    assert plan8.cache_dir == plan.cache_dir
    assert plan8.n_todo == 4


def test_store_roundtrip_keeps_shapes_and_types(tmp_path):
    trials = {"a": np.arange(12.0).reshape(3, 2, 2), "b": np.array([[True, False], [False, True], [True, True]]),
              "c": np.array([1, 2, 3]), "d": np.full((3, 2), np.nan)}
    store.write_chunk(tmp_path, [5, 6, 7], trials)
    idx, back = store.read_table(tmp_path / "trials-000005-000008.parquet")
    assert list(idx) == [5, 6, 7]
    for k in trials:
        np.testing.assert_array_equal(back[k], trials[k])
        assert back[k].dtype.kind == trials[k].dtype.kind or (k == "c" and back[k].dtype.kind == "i")


def test_config_key_ignores_runs_but_not_values():
    a = store.config_key("s", 1, {"runs": 5, "x": 1.0}, 1)
    assert a == store.config_key("s", 1, {"runs": 500, "x": 1.0}, 1)
    assert a != store.config_key("s", 1, {"runs": 5, "x": 1.5}, 1)
    assert a != store.config_key("s", 2, {"runs": 5, "x": 1.0}, 1)
    assert a != store.config_key("s", 1, {"runs": 5, "x": 1.0}, 2)


def test_zero_runs_is_an_input_error(tmp_path):
    mod, cfg = small_config(2)
    with pytest.raises(InputError, match="at least 1"):
        runner.plan_run(mod, cfg, 0, seed=1, out_dir=tmp_path)


def test_runner_runs_any_study_module_it_is_given(tmp_path, monkeypatch):
    """The runner never consults the studies registry: workers import the module it was given, by name."""
    import types

    from pydantic import BaseModel

    from sonartrack.core.random import trial_rng

    class Config(BaseModel):
        runs: int = 3
        scale: float = 2.0

    def run_trial(config, rng):
        return {"x": config.scale * rng.normal(size=2)}

    mod = types.ModuleType("toy_study_for_the_runner")
    mod.STUDY_ID, mod.Config, mod.run_trial = "toy", Config, run_trial
    monkeypatch.setitem(sys.modules, mod.__name__, mod)
    cfg = Config()
    plan = runner.plan_run(mod, cfg, 3, seed=5, out_dir=tmp_path, chunk_size=2)
    assert plan.study_module == "toy_study_for_the_runner" and plan.todo_chunks == ((0, 1), (2,))
    trials = runner.execute(plan, cfg, workers=1)
    np.testing.assert_array_equal(trials["x"], [2.0 * trial_rng(5, i).normal(size=2) for i in range(3)])


def test_an_interrupt_kills_the_workers_and_keeps_the_stored_chunks(tmp_path):
    import multiprocessing as mp

    mod, cfg = small_config(12)
    plan = runner.plan_run(mod, cfg, 12, seed=7, out_dir=tmp_path, chunk_size=2)

    def stop(n):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        runner.execute(plan, cfg, workers=2, on_chunk=stop)
    assert mp.active_children() == []  # no worker left running, nor waiting for more work
    assert runner.stored_trials(mod, cfg, 7, tmp_path) == 2  # the one chunk stored before the interrupt
    assert not list(plan.cache_dir.glob(".*tmp*"))


def test_a_signal_while_the_pool_starts_is_acted_on_once_it_has_started():
    """Held, not lost: SIGINT during start-up raises KeyboardInterrupt (pytest's handler) on the way out."""
    # a test run started as a background job inherits an ignored SIGINT: give Python's handler for this test
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _signal_held_during_start_up()
    finally:
        signal.signal(signal.SIGINT, old)


def _signal_held_during_start_up():
    reached = []
    with pytest.raises(KeyboardInterrupt), runner._stop_signals_held():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        reached.append(True)
    assert reached == [True]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_shared_pool_keeps_its_workers_across_runs_and_changes_no_number(tmp_path):
    """Two runs (two seeds, as two studies of one command) through one pool: the same worker processes
    serve both, and each run's trials are those of a run in this process."""
    mod, cfg = small_config(4)
    plans = [runner.plan_run(mod, cfg, 4, seed=s, out_dir=tmp_path / f"s{s}", chunk_size=2) for s in (7, 8)]
    with runner.WorkerPool(2) as pool:
        shared = [runner.execute(plans[0], cfg, workers=2, pool=pool)]
        first = set(pool.executor()._processes)
        shared.append(runner.execute(plans[1], cfg, workers=2, pool=pool))
        assert set(pool.executor()._processes) == first and len(first) >= 1
    import multiprocessing as mp

    assert mp.active_children() == []  # leaving the block ended the workers
    for s, trials in zip((7, 8), shared, strict=True):
        alone = runner.run_chunk(STUDY_MODULE, cfg.model_dump(mode="json"), s, (0, 1, 2, 3))
        assert_same(trials, alone)


def test_an_interrupt_in_a_shared_pool_kills_its_workers(tmp_path):
    import multiprocessing as mp

    mod, cfg = small_config(12)
    plan = runner.plan_run(mod, cfg, 12, seed=7, out_dir=tmp_path, chunk_size=2)

    def stop(n):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt), runner.WorkerPool(2) as pool:
        runner.execute(plan, cfg, workers=2, on_chunk=stop, pool=pool)
    assert mp.active_children() == []
    assert runner.stored_trials(mod, cfg, 7, tmp_path) == 2
