"""Monte Carlo runner: seeds, local processes or a Dask cluster, chunked storage and resume.

Trial i of a study always runs with ``trial_rng(seed, i)`` (core/random.py), so results are
bit-for-bit identical whatever the number of workers, the scheduler, or how often the run was
interrupted. Work is cut into chunks of consecutive trials; each finished chunk is written
atomically by the parent process (experiment/store.py), so an interrupted run loses at most the
chunks in flight and a rerun computes only the trials not yet on disk.

The runner knows a study only as the module it is given (:func:`plan_run`); workers re-import it by
its dotted name (``RunPlan.study_module``), so this layer never imports the studies above it.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.core.random import trial_rng
from sonartrack.experiment import store

DEFAULT_CHUNK = 10


@dataclass(frozen=True, slots=True)
class RunPlan:
    """What a run will do: where its trials live and which ones still need computing."""

    study_id: str
    study_module: str  #: dotted import path of the study module (what a worker imports)
    runs: int
    seed: int
    cache_dir: Path
    todo_chunks: tuple[tuple[int, ...], ...]

    @property
    def n_todo(self) -> int:
        return sum(len(c) for c in self.todo_chunks)


def run_chunk(study_module: str, config_json: dict, seed: int, indices: tuple[int, ...]) -> dict[str, np.ndarray]:
    """Run trials ``indices`` of the study module ``study_module`` (dotted path) and stack their outputs
    (executed in a worker)."""
    mod = importlib.import_module(study_module)
    config = mod.Config.model_validate(config_json)
    outs = [mod.run_trial(config, trial_rng(seed, i)) for i in indices]
    return {k: np.stack([np.asarray(o[k]) for o in outs]) for k in outs[0]}


def _chunks(indices: list[int], size: int) -> list[tuple[int, ...]]:
    """Cut sorted trial indices into runs of consecutive indices, each at most ``size`` long."""
    chunks, cur = [], []
    for i in indices:
        if cur and (i != cur[-1] + 1 or len(cur) >= size):
            chunks.append(tuple(cur))
            cur = []
        cur.append(i)
    if cur:
        chunks.append(tuple(cur))
    return chunks


def plan_run(study_mod, config, runs: int, seed: int, out_dir: Path, chunk_size: int | None = None) -> RunPlan:
    """Work out the cache folder for (study, config, seed) and the chunks still to compute."""
    require(runs >= 1, f"--runs must be at least 1 (got {runs})")
    cfg = config.model_dump(mode="json")
    key = store.config_key(study_mod.STUDY_ID, getattr(study_mod, "TRIAL_VERSION", 1), cfg, seed)
    cache_dir = Path(out_dir) / study_mod.STUDY_ID / "cache" / key
    done = store.done_indices(cache_dir)
    todo = [i for i in range(runs) if i not in done]
    size = chunk_size or getattr(study_mod, "CHUNK_SIZE", DEFAULT_CHUNK)
    return RunPlan(study_mod.STUDY_ID, study_mod.__name__, runs, int(seed), cache_dir, tuple(_chunks(todo, size)))


def execute(plan: RunPlan, config, *, workers: int = 1, scheduler: str | None = None,
            on_chunk: Callable[[int], None] | None = None) -> dict[str, np.ndarray]:
    """Compute the missing chunks of ``plan``, store each as it finishes, and return all trials.

    ``workers`` local processes (1: in this process), or the Dask cluster at ``scheduler``.
    ``on_chunk(n)`` is called with the number of trials each time a chunk is stored.
    """
    cfg = config.model_dump(mode="json")
    for indices, arrays in _iter_results(plan, cfg, workers, scheduler):
        store.write_chunk(plan.cache_dir, indices, arrays)
        if on_chunk:
            on_chunk(len(indices))
    return store.load_trials(plan.cache_dir, plan.runs)


def _iter_results(plan: RunPlan, cfg: dict, workers: int, scheduler: str | None) -> Iterable:
    if not plan.todo_chunks:
        return
    require(workers >= 1, f"--workers must be at least 1 (got {workers})")
    if scheduler:
        yield from _iter_dask(plan, cfg, scheduler)
    elif workers == 1 or len(plan.todo_chunks) == 1:
        for idx in plan.todo_chunks:
            yield idx, run_chunk(plan.study_module, cfg, plan.seed, idx)
    else:
        yield from _iter_processes(plan, cfg, workers)


def _iter_processes(plan: RunPlan, cfg: dict, workers: int):
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # "spawn" would re-import everything per worker; "forkserver" is safe with threads in the parent.
    ctx = mp.get_context("forkserver" if os.name == "posix" else "spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {pool.submit(run_chunk, plan.study_module, cfg, plan.seed, idx): idx for idx in plan.todo_chunks}
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        except BaseException:
            for f in futures:
                f.cancel()
            raise


def _iter_dask(plan: RunPlan, cfg: dict, scheduler: str):
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a dependency
        raise InputError("--scheduler needs dask.distributed: pip install 'dask[distributed]'") from exc
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {scheduler}: start it or fix --scheduler") from exc
    try:
        futures = {client.submit(run_chunk, plan.study_module, cfg, plan.seed, idx, pure=False): idx
                   for idx in plan.todo_chunks}
        for fut in as_completed(list(futures)):
            yield futures[fut], fut.result()
    finally:
        client.close()
