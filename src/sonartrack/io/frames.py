"""Range-Doppler frames in and detections out.

In: a stack from a user's file, ``.npy`` (one K x Nr x Nd array) or ``.npz`` (the stack under the
key ``frames`` or as its only array). Values are square-law cell outputs (powers, >= 0). Checks
(one-line :class:`InputError` each): unreadable or pickled files, the wrong rank, K < 1, NaN/inf,
negative values (see ``detection.frames.validate_frames``).

Out: the best track of a detection as CSV, a row per frame (:func:`write_detection_csv`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require


def read_frames(path: str | Path) -> np.ndarray:
    """Load and validate a K x Nr x Nd stack of square-law cell values."""
    from sonartrack.detection.frames import validate_frames

    p = Path(path)
    require(p.exists(), f"frames file {p} does not exist")
    suffix = p.suffix.lower()
    require(suffix in (".npy", ".npz"),
            f"frames file {p.name}: expected a .npy or .npz file, got '{suffix or 'no suffix'}'")
    try:
        data = np.load(p, allow_pickle=False)
    except ValueError as exc:  # pickled object arrays, corrupt headers
        raise InputError(f"frames file {p.name} is not a plain numeric NumPy array ({exc}): "
                         "save it with np.save") from None
    except (OSError, EOFError) as exc:
        raise InputError(f"cannot read frames file {p.name}: {exc}") from None
    if suffix == ".npz":
        with data:
            keys = list(data.keys())
            if "frames" in keys:
                arr = data["frames"]
            elif len(keys) == 1:
                arr = data[keys[0]]
            else:
                raise InputError(f"{p.name} holds arrays {keys}: name the frame stack 'frames'")
    else:
        arr = data
    require(np.issubdtype(arr.dtype, np.number) and not np.iscomplexobj(arr),
            f"frames in {p.name} have dtype {arr.dtype}: need real square-law powers (|x|^2 of complex data)")
    return validate_frames(arr)


def write_detection_csv(path: str | Path, detection) -> Path:
    """Write a :class:`~sonartrack.detection.detect.FrameDetection`'s best track (frame, cells,
    centres, cell values) as CSV, atomically."""
    import pandas as pd

    from sonartrack.io.atomic import write_csv

    return write_csv(pd.DataFrame(detection.best_track_table()), path, float_format="%.10g")
