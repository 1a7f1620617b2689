"""Range-Doppler frames in (the detect system writes its detections: systems/detect/files.py).

A stack from a user's file, ``.npy`` (one K x Nr x Nd array) or ``.npz`` (the stack under the
key ``frames`` or as its only array). Values are square-law cell outputs (powers, >= 0). Checks
(one-line :class:`InputError` each): a directory, unreadable or pickled files, the wrong rank, K < 1,
NaN/inf, negative values (see ``detection.frames.validate_frames``), and cell values beyond any sonar's
dynamic range (a cell more than :data:`MAX_DYNAMIC_RANGE_DB` above the median cell, or beyond
:data:`MAX_CELL_VALUE`: 1e300 overflows the detector's statistic into nonsense).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require

#: largest cell value taken (square-law powers; any calibration short of overflow)
MAX_CELL_VALUE = 1e100
#: largest ratio of a cell to the median cell (dB): beyond it the file is not one sonar's square-law output
MAX_DYNAMIC_RANGE_DB = 150.0


def read_frames(path: str | Path) -> np.ndarray:
    """Load and validate a stack of square-law cell values from a ``.npy`` or ``.npz`` file (module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The file; a ``.npz`` holds the stack under ``frames`` or as its only array.

    Returns
    -------
    ndarray of float64, shape (K, Nr, Nd)
        Cell values (powers, >= 0), frame by frame, range index then Doppler index.

    Raises
    ------
    InputError
        For a missing, unreadable, pickled or non-numeric file, a wrong rank, NaN/inf, negative values or
        values beyond any sonar's dynamic range.
    """
    from sonartrack.detection.frames import validate_frames

    p = Path(path)
    require(not p.is_dir(), f"frames file {p} is a directory: give the .npy or .npz file inside it")
    require(p.exists(), f"frames file {p} does not exist")
    suffix = p.suffix.lower()
    require(suffix in (".npy", ".npz"),
            f"frames file {p.name}: expected a .npy or .npz file, got '{suffix or 'no suffix'}'")
    _check_magic(p, suffix)
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
    return _check_dynamic_range(validate_frames(arr), p.name)


def _check_dynamic_range(y: np.ndarray, name: str) -> np.ndarray:
    """Refuse cell values no sonar produces (module doc): the largest cell, absolute and against the median."""
    peak = float(y.max())
    require(peak <= MAX_CELL_VALUE, f"frames in {name}: cell value {peak:g} at (frame, range, Doppler) "
                                    f"{tuple(int(i) for i in np.unravel_index(np.argmax(y), y.shape))} exceeds "
                                    f"{MAX_CELL_VALUE:g}: rescale the frames (e.g. divide by the noise power)")
    median = float(np.median(y))
    if median > 0 and peak > median * 10 ** (MAX_DYNAMIC_RANGE_DB / 10):
        raise InputError(f"frames in {name}: the largest cell value {peak:g} is {10 * np.log10(peak / median):.0f} dB "
                         f"above the median cell {median:g} (more than {MAX_DYNAMIC_RANGE_DB:g} dB): a corrupt cell or "
                         "amplitudes squared twice? fix the frames")
    return y


def _check_magic(p: Path, suffix: str) -> None:
    """A .npy starts with NumPy's magic, a .npz is a ZIP archive: anything else is named (not 'pickled data')."""
    from sonartrack.io.tables import sniff_file_type

    require(p.stat().st_size > 0, f"frames file {p.name} is empty (0 bytes): save the stack with np.save")
    kind = sniff_file_type(p)
    want = "a NumPy .npy array" if suffix == ".npy" else "a ZIP archive (.npz, .xlsx ...)"
    if kind != want:
        raise InputError(f"frames file {p.name} is {kind or 'of unknown content'}, not a plain NumPy "
                         f"{'.npy array' if suffix == '.npy' else '.npz archive'}: save the K x Nr x Nd stack with "
                         "np.save (or np.savez)")

