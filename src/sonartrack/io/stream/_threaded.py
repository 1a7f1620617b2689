"""A source read by its own thread: a bounded queue between the reader and the consumer, and a close() that
stops the thread (no thread outlives close()).

The reader puts items in a bounded queue; a slow consumer makes the reader wait (for TCP that is back-pressure on
the sender; memory stays bounded). An exception in the reader is put in the queue and raised by the consumer's
next ``next()`` (an InputError reaches the command line as one line). The iteration ends when the reader
finishes (:data:`_DONE`) or the source is closed.
"""

from __future__ import annotations

import queue
import threading

#: items held between the reader thread and the consumer
QUEUE_ITEMS = 256
#: how often (s) a waiting thread looks whether it was asked to stop
POLL_S = 0.05
_DONE = object()


class ThreadedSource:
    """Base of the sources: subclasses implement ``_run()`` (in the reader thread), calling :meth:`_put` for each
    item and returning at the end; they test ``self._stop`` often."""

    _name = "source"

    def __init__(self):
        self._queue: queue.Queue = queue.Queue(QUEUE_ITEMS)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._finished = False

    def start(self):
        """Start the reader thread (iterating starts it too).

        Returns
        -------
        ThreadedSource
            Itself.
        """
        if self._thread is None and not self._stop.is_set():
            self._thread = threading.Thread(target=self._main, name=f"sonartrack-{self._name}", daemon=True)
            self._thread.start()
        return self

    def _main(self) -> None:
        try:
            self._run()
        except BaseException as exc:  # handed to the consumer, raised there
            self._put(exc)
        finally:
            self._put(_DONE)

    def _put(self, item) -> bool:
        """Queue ``item`` for the consumer, waiting while the queue is full; False once the source is closed."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def __iter__(self):
        self.start()
        return self

    def __next__(self):
        while not self._finished:
            try:
                item = self._queue.get(timeout=POLL_S)
            except queue.Empty:
                if self._stop.is_set():
                    break
                continue
            if item is _DONE:
                break
            if isinstance(item, BaseException):
                self._finished = True
                raise item
            return item
        self._finished = True
        raise StopIteration

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop the reader thread and release its socket or file; waits for the thread to end.

        Parameters
        ----------
        timeout_s : float
            Longest wait for the thread (s); the thread tests the stop flag every :data:`POLL_S`.
        """
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout_s)
        self._finished = True

    @property
    def alive(self) -> bool:
        """Whether the reader thread is running."""
        return self._thread is not None and self._thread.is_alive()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    def _run(self) -> None:  # pragma: no cover (subclasses)
        raise NotImplementedError
