"""A rich progress bar for Monte Carlo runs (quiet when stdout is not a terminal and CI is set)."""

from __future__ import annotations

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

console = Console(stderr=True)


class TrialProgress:
    """Adapter between the pipeline's ``start/advance`` hooks and a rich Progress."""

    def __init__(self, progress: Progress):
        self._p = progress
        self._task = None

    def start(self, study_id: str, total: int, done: int) -> None:
        label = f"{study_id}" + (f" (resuming: {done} on disk)" if done else "")
        self._task = self._p.add_task(label, total=total, completed=done)

    def advance(self, n: int) -> None:
        self._p.advance(self._task, n)


def make_progress() -> Progress:
    """The bar on stderr when it is a terminal; nothing otherwise (a log or a pipe gets the result lines only,
    and an error stays the one line it is)."""
    return Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=False,
                    disable=not console.is_terminal)
