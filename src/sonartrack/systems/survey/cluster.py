"""The survey's Dask client: on a scheduler given by its address, or on a local cluster that Ctrl-C cannot break.

A local cluster (``workers`` single-threaded processes, the scheduler and the nannies in this process) is
started and closed with SIGINT and SIGTERM held (:func:`signals_held`): blocked in this thread, and a signal
that arrives meanwhile is noted and handed to its handler once the cluster is up (or closed). Without this, a
Ctrl-C while the cluster starts breaks Dask's start-up half-way (``AssertionError: Status.init`` and
``Nanny failed to start`` tracebacks). The cluster's threads are created inside the held window and inherit the
blocked mask, and so do the worker processes they spawn: a Ctrl-C to the process group (a terminal) or a
SIGTERM to it (a service manager) never reaches a worker's Python (no KeyboardInterrupt traceback from a
worker); this process alone acts on it and closes the cluster, which stops the workers (and kills one that
does not stop within seconds). Dask's scratch folder is ``OUT/.dask-scratch-PID`` (not ``dask-scratch-space``
in the system's temporary folder) and is removed when the cluster closes, interrupted or not; one left by a
killed run is removed by the next (files.py ``remove_stale``). An interrupt closes the workers at once (a task
under way is dropped: its recording is done again by the next run). With ``--scheduler`` the client connects and
closes with the signals held too; the cluster's workers are not ours to stop.

Glossary of the parameters: ``out``, the survey's output folder (str or Path).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re
import shutil
from pathlib import Path

from sonartrack.core.errors import InputError, require
from sonartrack.core.signals import signals_held

#: a Dask scheduler's address: [protocol://]host:port
_ADDRESS = re.compile(r"(?:(?:tcp|tls|ws|wss|ucx)://)?(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):\d{1,5}")


def check_scheduler(address: str) -> None:
    """Refuse a scheduler address that is not ``[protocol://]host:port`` (e.g. ``tcp://host:8786``).

    Parameters
    ----------
    address : str
        The --scheduler option.

    Raises
    ------
    InputError
        When the address has another form.
    """
    require(bool(_ADDRESS.fullmatch(address)), f"--scheduler {address!r} is not a Dask scheduler address: give "
                                               "it as tcp://host:8786 (protocol, host and port)")


def scratch_dir(out) -> Path:
    """Dask's scratch folder for this process: ``OUT/.dask-scratch-PID`` (module doc).

    Returns
    -------
    Path
        The folder (not created here).
    """
    return Path(out) / f".dask-scratch-{os.getpid()}"


@contextlib.contextmanager
def _remote(scheduler: str):
    from distributed import Client

    check_scheduler(scheduler)
    try:
        with signals_held():  # a connection interrupted half-way would print Dask's tracebacks
            client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError, ValueError):
        raise InputError(f"cannot reach the Dask scheduler at {scheduler}: start it or fix --scheduler") from None
    try:
        yield client
    finally:
        with signals_held():
            client.close()


@contextlib.contextmanager
def _local(workers: int, out):
    from multiprocessing import resource_tracker

    import dask
    from distributed import Client, LocalCluster

    # started inside the held window (by the cluster's first queue), the tracker would unblock SIGINT and SIGTERM
    # in the cluster's thread on its way out, and the workers spawned from it would hear them again
    resource_tracker.ensure_running()
    scratch = scratch_dir(out)
    cluster = client = None
    try:
        # the scheduler and the nannies make their scratch folders from the config, the workers from both
        with dask.config.set({"temporary-directory": str(scratch)}):
            with signals_held():
                # no dashboard; the scheduler's HTTP routes (health, metrics) on loopback and a free port: the
                # default, port 8787, warns into the survey's output whenever another cluster holds it
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, local_directory=str(scratch),
                                       silence_logs=logging.ERROR,
                                       scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
                client = Client(cluster)
            try:
                yield client
            except BaseException:  # an interrupt (or a bug): stop the workers now, not after their tasks
                with signals_held():
                    _stop_workers(client, cluster)
                raise
    finally:
        with signals_held():
            for part in (client, cluster):
                if part is not None:
                    part.close()
            shutil.rmtree(scratch, ignore_errors=True)


def _stop_workers(client, cluster) -> None:
    """Release the tasks and close the nannies with a short timeout: a worker busy with a recording is killed
    within a second instead of finishing it (its result would be dropped anyway)."""
    client.close()

    async def close_nannies():
        await asyncio.gather(*(w.close(timeout=1) for w in cluster.workers.values()), return_exceptions=True)

    cluster.sync(close_nannies)


@contextlib.contextmanager
def dask_client(workers: int, scheduler: str | None, out):
    """A Dask client on ``scheduler``, or on a local cluster of ``workers`` single-threaded processes (module doc).

    Parameters
    ----------
    workers : int
        Local worker processes (not used with ``scheduler``).
    scheduler : str, optional
        A scheduler's address, ``tcp://host:8786``.
    out : str or Path
        The survey's output folder (the local cluster's scratch folder is made in it).

    Yields
    ------
    distributed.Client
        Closed (and its local cluster with it) when the block ends, however it ends.
    """
    with _remote(scheduler) if scheduler else _local(workers, out) as client:
        yield client
