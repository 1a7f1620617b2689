"""SIGINT and SIGTERM held over a stretch that an interrupt must not break half-way, then delivered.

Used where processes or a cluster start and stop (experiment/runner.py's pool, systems/survey/cluster.py's Dask
cluster): a Ctrl-C in the middle would leave a child started but not yet known (never stopped), or a traceback from
a half-started one. Inside :func:`signals_held` a signal is noted instead of acted on, and the signals named are
blocked in this thread, so threads and processes started inside inherit the blocked mask; once the block ends the
first signal noted is handed to the handler it was meant for.
"""

from __future__ import annotations

import contextlib
import signal
import threading


@contextlib.contextmanager
def signals_held(blocked=(signal.SIGINT, signal.SIGTERM)):
    """Note SIGINT and SIGTERM inside the block (blocking ``blocked`` in this thread), deliver the first noted one
    to its handler once the block ends (module doc).

    In the main thread only (signal handlers belong to it); elsewhere this does nothing. A signal ignored on entry
    stays ignored; without ``pthread_sigmask`` nothing is blocked, only noted.

    Parameters
    ----------
    blocked : tuple of signal numbers
        The signals blocked in this thread (and so in what it starts) inside the block.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    mask = hasattr(signal, "pthread_sigmask")
    caught: list[int] = []
    held = {sig: h for sig in (signal.SIGINT, signal.SIGTERM) if (h := signal.getsignal(sig)) not in
            (signal.SIG_IGN, None)}
    for sig in held:
        signal.signal(sig, lambda signum, frame: caught.append(signum))
    if mask:
        signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
    try:
        yield
    finally:
        if mask:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, blocked)  # a pending one is noted now
        for sig, handler in held.items():
            signal.signal(sig, handler)
    if caught:
        handler = held[caught[0]]
        if callable(handler):
            handler(caught[0], None)
        else:
            signal.raise_signal(caught[0])
