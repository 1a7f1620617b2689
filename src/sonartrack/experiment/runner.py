"""Monte Carlo runner: seeds, local processes or a Dask cluster, chunked storage and resume.

Trial i of a study always runs with ``trial_rng(seed, i)`` (core/random.py), so results are
bit-for-bit identical whatever the number of workers, the scheduler, or how often the run was
interrupted. Work is cut into chunks of consecutive trials; each finished chunk is written
atomically by the parent process (experiment/store.py), so an interrupted run loses at most the
chunks in flight and a rerun computes only the trials not yet on disk.

The runner knows a study only as the module it is given (:func:`plan_run`); workers re-import it by
its dotted name (``RunPlan.study_module``), so this layer never imports the studies above it.

Interrupts and orphans. Local workers ignore SIGINT (:func:`_worker_init`): a Ctrl-C from a terminal
reaches the whole process group, and only the parent acts on it: it stops the pool, kills the workers
(their chunks in flight are lost; every stored chunk stays) and re-raises. Workers must also never
outlive the parent when it dies without cleaning up (SIGKILL). With the forkserver start method a
worker's parent process is the fork server, not our process, so ``prctl(PR_SET_PDEATHSIG)`` in the
worker would watch the wrong process; instead each worker waits, in a daemon thread, on
``multiprocessing.parent_process().sentinel``, a pipe whose write end only our process holds: the
kernel closes it when our process dies, however it dies, and the worker ends with ``os._exit`` as
soon as its watcher thread gets the GIL (at once in Python code and in the ``nogil`` numba kernels; a
compiled call that holds the GIL delays it to that call's end). The fork server then sees its "alive"
pipe reach EOF (only our process and the workers held it) and exits, and the resource tracker exits
when the last holder of its pipe is gone.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.core.random import trial_rng
from sonartrack.core.signals import signals_held
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
        """Number of trials still to compute."""
        return sum(len(c) for c in self.todo_chunks)


def run_chunk(study_module: str, config_json: dict, seed: int, indices: tuple[int, ...]) -> dict[str, np.ndarray]:
    """Run trials ``indices`` of a study and stack their outputs (executed in a worker).

    Parameters
    ----------
    study_module : str
        Dotted import path of the study module.
    config_json : dict
        The study's config as JSON data.
    seed : int
        Master seed.
    indices : tuple of int
        Trial indices; trial i draws from ``trial_rng(seed, i)``.

    Returns
    -------
    dict of str to ndarray
        Each output of ``run_trial``, stacked over the trials (first axis).
    """
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
    """Work out the cache folder for (study, config, seed) and the chunks still to compute.

    Parameters
    ----------
    study_mod : module
        The study module (``STUDY_ID``, optional ``TRIAL_VERSION`` and ``CHUNK_SIZE``).
    config : Config
        The resolved config.
    runs : int
        Trials wanted, >= 1.
    seed : int
        Master seed.
    out_dir : path-like
        Output root; the cache is ``<out>/<study>/cache/<key>``.
    chunk_size : int, optional
        Trials per chunk (default the study's ``CHUNK_SIZE``, else 10).

    Returns
    -------
    RunPlan
        The cache folder and the chunks of consecutive trials not yet on disk.

    Raises
    ------
    InputError
        If ``runs`` < 1.
    """
    require(runs >= 1, f"--runs must be at least 1 (got {runs})")
    cfg = config.model_dump(mode="json")
    key = store.config_key(study_mod.STUDY_ID, getattr(study_mod, "TRIAL_VERSION", 1), cfg, seed)
    cache_dir = Path(out_dir) / study_mod.STUDY_ID / "cache" / key
    done = store.done_indices(cache_dir)
    todo = [i for i in range(runs) if i not in done]
    size = chunk_size or getattr(study_mod, "CHUNK_SIZE", DEFAULT_CHUNK)
    return RunPlan(study_mod.STUDY_ID, study_mod.__name__, runs, int(seed), cache_dir, tuple(_chunks(todo, size)))


def execute(plan: RunPlan, config, *, workers: int = 1, scheduler: str | None = None,
            on_chunk: Callable[[int], None] | None = None, pool: WorkerPool | None = None) -> dict[str, np.ndarray]:
    """Compute the missing chunks of ``plan``, store each as it finishes, and return all trials.

    Parameters
    ----------
    plan : RunPlan
        From :func:`plan_run`.
    config : Config
        The resolved config.
    workers : int, default 1
        Local processes (1: in this process).
    scheduler : str, optional
        Address of a Dask scheduler; used instead of local processes.
    on_chunk : callable, optional
        Called with the number of trials each time a chunk is stored.
    pool : WorkerPool, optional
        Local workers shared with other runs (the studies of one command); None: a pool of ``workers``
        processes for this run alone. Not used with ``scheduler``.

    Returns
    -------
    dict of str to ndarray
        Trials 0..runs-1 of every output, in trial order.

    Raises
    ------
    InputError
        If ``workers`` < 1 or the scheduler cannot be reached.
    """
    cfg = config.model_dump(mode="json")
    # closing(): on an interrupt the pool is stopped here and now, not whenever the generator is collected
    with contextlib.closing(_iter_results(plan, cfg, workers, scheduler, pool)) as results:
        for indices, arrays in results:
            store.write_chunk(plan.cache_dir, indices, arrays)
            if on_chunk:
                on_chunk(len(indices))
    return store.load_trials(plan.cache_dir, plan.runs)


def stored_trials(study_mod, config, seed: int, out_dir: Path) -> int:
    """How many of trials ``0..config.runs-1`` of this (study, config, seed) are complete on disk.

    Parameters
    ----------
    study_mod : module
        The study module.
    config : Config
        The resolved config.
    seed : int
        Master seed.
    out_dir : path-like
        Output root.

    Returns
    -------
    int
        Trials already stored.
    """
    plan = plan_run(study_mod, config, config.runs, seed, out_dir)
    return plan.runs - plan.n_todo


def _iter_results(plan: RunPlan, cfg: dict, workers: int, scheduler: str | None,
                  pool: WorkerPool | None = None) -> Iterable:
    if not plan.todo_chunks:
        return
    require(workers >= 1, f"--workers must be at least 1 (got {workers})")
    if scheduler:
        yield from _iter_dask(plan, cfg, scheduler)
    elif workers == 1 or len(plan.todo_chunks) == 1:
        for idx in plan.todo_chunks:
            yield idx, run_chunk(plan.study_module, cfg, plan.seed, idx)
    else:
        yield from _iter_processes(plan, cfg, workers, pool)


def _worker_init() -> None:
    """Worker start-up: leave SIGINT to the parent, and end when the parent process ends."""
    import multiprocessing as mp

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):  # held since start-up (see _stop_signals_held); now ignored
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    parent = mp.parent_process()
    if parent is not None:
        threading.Thread(target=_exit_when_gone, args=(parent.sentinel,), name="parent-watch", daemon=True).start()


def _exit_when_gone(sentinel: int) -> None:
    """Block until the parent's sentinel pipe reaches EOF (the parent is gone), then end this worker."""
    from multiprocessing.connection import wait

    wait([sentinel])
    os._exit(1)


@contextlib.contextmanager
def _stop_signals_held():
    """While the pool starts its processes, hold SIGINT and SIGTERM; act on them once it has started.

    Children inherit the signal mask across fork and exec: the fork server started in here keeps SIGINT
    blocked for good (it ignores it anyway), and so does each worker it forks until :func:`_worker_init`
    has made SIGINT ignored, so a Ctrl-C during start-up cannot print a KeyboardInterrupt traceback from
    a half-started child. In this process a signal arriving meanwhile is noted and handed to the handler
    it was meant for on the way out, so no worker is ever started but missing from the pool's table
    (and thus never stopped). Signal handlers belong to the main thread: elsewhere this does nothing.
    """
    if threading.current_thread() is threading.main_thread() and hasattr(signal, "pthread_sigmask"):
        from multiprocessing import resource_tracker

        resource_tracker.ensure_running()  # started inside, it would unblock SIGINT on its way out
    with signals_held((signal.SIGINT,)):
        yield


def _stop_pool(pool) -> None:
    """Cancel queued chunks and kill the running ones (an interrupt: their results would be dropped anyway)."""
    # taken before shutdown(), which drops the pool's table of processes (Python >= 3.14: pool.kill_workers())
    procs = list((getattr(pool, "_processes", None) or {}).values())
    # and its manager thread: shutdown(wait=False) forgets it, and if it is still closing its wake-up pipe when the
    # interpreter exits, concurrent.futures' exit hook writes to the closed pipe and prints a traceback
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            proc.kill()
    for proc in procs:
        with contextlib.suppress(OSError, ValueError, AttributeError, AssertionError):
            proc.join(5)
    pool.shutdown(wait=True)
    if manager is not None:
        manager.join(5)


class WorkerPool:
    """Local worker processes shared by the runs made inside one ``with`` block (the studies of one command).

    A fresh worker spends seconds importing numpy, the compiled kernels and a study's modules before its
    first trial; a pool kept across the studies of ``reproduce all`` pays that once per worker instead of
    once per study. Sharing changes no number: a trial is a function of (study, config, seed, index) only.
    The processes start at the first chunk sent to them (none with a Dask scheduler or a single worker).
    Leaving the block normally waits for the workers to end; leaving it on an exception (an interrupt, a
    failed trial) kills them, as a run with a pool of its own does.
    """

    def __init__(self, workers: int):
        require(workers >= 1, f"--workers must be at least 1 (got {workers})")
        self.workers = int(workers)
        self._pool = None

    def executor(self):
        """The process pool, started on first use (the forkserver start method on POSIX).

        Returns
        -------
        concurrent.futures.ProcessPoolExecutor
            ``workers`` processes (spawn start method off POSIX), each initialised by ``_worker_init``.
        """
        if self._pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            # "spawn" would re-import everything per worker; "forkserver" is safe with threads in the parent.
            ctx = mp.get_context("forkserver" if os.name == "posix" else "spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_worker_init)
        return self._pool

    def stop(self) -> None:
        """Cancel queued chunks and kill the workers (see :func:`_stop_pool`); the pool restarts if used again."""
        if self._pool is not None:
            pool, self._pool = self._pool, None
            _stop_pool(pool)

    def close(self) -> None:
        """Let the workers end once idle and wait for them."""
        if self._pool is not None:
            pool, self._pool = self._pool, None
            pool.shutdown(wait=True)

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.stop()


def _iter_processes(plan: RunPlan, cfg: dict, workers: int, shared: WorkerPool | None = None):
    from concurrent.futures import as_completed

    pool = shared if shared is not None else WorkerPool(workers)
    with contextlib.nullcontext() if shared is not None else pool:
        executor = pool.executor()
        try:
            with _stop_signals_held():
                futures = {executor.submit(run_chunk, plan.study_module, cfg, plan.seed, idx): idx
                           for idx in plan.todo_chunks}
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        except BaseException:  # KeyboardInterrupt, GeneratorExit (the consumer stopped), a failed trial
            pool.stop()
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
