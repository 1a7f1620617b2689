"""The ``sonartrack`` console script's first code: Ctrl-C and SIGTERM end it quietly from its first moment.

The command line's own handling of interrupts (:mod:`sonartrack.cli`: one line, status 130 or 143) starts once
its module and typer are imported, about 0.1 s after the process starts; a signal before then printed Python's
``KeyboardInterrupt`` traceback (SIGINT) or killed the process without a word (SIGTERM). This module imports
nothing heavy, installs a handler that says the same line and exits with the same status (nothing has been
written yet), and only then imports the command line.
"""

from __future__ import annotations

import signal
import sys

#: the line of a command interrupted before it started (the same words as :data:`sonartrack.cli.INTERRUPTED`)
EARLY_INTERRUPTED = "interrupted: nothing half-written was kept; rerun the same command"


def _interrupted_early(signum, frame) -> None:
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    sys.stderr.write(EARLY_INTERRUPTED + "\n")
    raise SystemExit(128 + signum)


def install() -> None:
    """SIGINT and SIGTERM end the process with the interrupted line and status 128 + the signal number, until the
    command line installs its own handlers; a signal ignored on entry (a background job's SIGINT) stays ignored."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, _interrupted_early)


def main() -> None:  # pragma: no cover - the console script
    install()
    from sonartrack.cli import _entry

    _entry()
