"""The detect system's files: the frames file in, ``detection.csv`` out (atomically).

The frames reader and its checks are io/frames.py's (a K x Nr x Nd stack in a .npy, or in a .npz under
``frames`` or as its only array). ``detection.csv`` holds the best track, a row per frame: frame (1-based),
range_index, doppler_index, range_m, range_rate_mps, cell_value. The picture is report/figures/detection.py's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

CSV_NAME = "detection.csv"
PNG_NAME = "detection.png"


def read_frames_file(path) -> np.ndarray:
    """Load and check a stack of square-law cell values.

    Parameters
    ----------
    path : path-like
        A .npy or .npz file holding a K x Nr x Nd stack.

    Returns
    -------
    numpy.ndarray, shape (K, Nr, Nd)
        The cell values (powers, >= 0).
    """
    from sonartrack.io.frames import read_frames

    return read_frames(path)


def write_detection(detection, out) -> Path:
    """Write ``detection``'s best track (frame, cells, centres, cell values: what
    :func:`~sonartrack.systems.detect.run.run_detect` returned) as ``detection.csv`` (10 significant digits) in the
    output folder ``out``, atomically; returns the file's path."""
    import pandas as pd

    from sonartrack.io.atomic import write_csv

    return write_csv(pd.DataFrame(detection.best_track_table()), Path(out) / CSV_NAME, float_format="%.10g")
