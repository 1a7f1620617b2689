"""Atomic file writes: an output is either the complete new file or absent, never half written.

Write to a hidden temporary sibling (same folder, so the rename is atomic on POSIX), then
``os.replace`` it over the target; on any error the temporary is removed and the target untouched.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path) -> Iterator[Path]:
    """Context manager: a temporary path next to ``path`` (same suffix), renamed over ``path`` if the block succeeds.

    On an error in the block the temporary is removed and ``path`` is left untouched.

    Parameters
    ----------
    path : str or path-like
        The final file.

    Yields
    ------
    pathlib.Path
        The hidden temporary sibling to write to.
    """
    p = Path(path)
    tmp = p.with_name(f".{p.stem}.{os.getpid()}.tmp{p.suffix}")
    try:
        yield tmp
        os.replace(tmp, p)
    finally:
        tmp.unlink(missing_ok=True)


def save_figure(fig, path, **savefig_kwargs) -> Path:
    """``fig.savefig`` atomically, then close the figure (also on an error).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or path-like
        Output image file.
    **savefig_kwargs
        Passed to ``savefig`` (e.g. ``dpi``).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, **savefig_kwargs)
    finally:
        plt.close(fig)
    return Path(path)


def write_csv(frame, path, **to_csv_kwargs) -> Path:
    """``DataFrame.to_csv`` atomically (no index by default).

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.
    path : str or path-like
        Output CSV file.
    **to_csv_kwargs
        Passed to ``to_csv``.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    to_csv_kwargs.setdefault("index", False)
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, **to_csv_kwargs)
    return Path(path)


def write_text(path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` atomically.

    Parameters
    ----------
    path : str or path-like
        Output file.
    text : str
        Content.
    encoding : str, default "utf-8"
        Text encoding.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding=encoding)
    return Path(path)


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` atomically.

    Parameters
    ----------
    path : str or path-like
        Output file.
    data : bytes
        Content.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)
