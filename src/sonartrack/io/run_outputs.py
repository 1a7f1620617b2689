"""A run's outputs are all or nothing: what a failed or interrupted run wrote into its output folder is removed.

Each file is written atomically (io/atomic.py), but a run writes several (tables, figures, a page): a failure
after the first leaves a folder that looks like a result and is not one. :func:`discard_on_failure` notes what
the folder held before the run, and on any exception (a user mistake, a bug, Ctrl-C) removes every entry that was
not there, then the folder itself if the run made it and it is empty again. Entries that were there before are
never touched (a rerun into a folder of older results keeps them).
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from sonartrack.core.errors import require


def check_out_path(out) -> Path:
    """Refuse an empty output folder name (``--out ''`` would write into the working directory).

    Parameters
    ----------
    out : str or path-like
        The output folder as given.

    Returns
    -------
    pathlib.Path
        The folder.
    """
    require(str(out).strip() != "", "--out is empty: give an output folder (e.g. --out results; '.' for the "
                                    "working directory)")
    return Path(out)


@contextmanager
def discard_on_failure(folder) -> Iterator[Path]:
    """Context manager: on an exception in the block, remove what the block added to ``folder`` (module doc).

    Parameters
    ----------
    folder : str or path-like
        The run's output folder (made here if missing).

    Yields
    ------
    pathlib.Path
        The folder.
    """
    folder = Path(folder)
    made = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    before = {p.name for p in folder.iterdir()}
    try:
        yield folder
    except BaseException:
        for p in folder.iterdir() if folder.is_dir() else ():
            if p.name in before:
                continue
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                p.unlink(missing_ok=True)
        if made and folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
        raise
