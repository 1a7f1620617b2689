"""Two-channel WAV recordings for the bearing estimator (``sonartrack bearings``).

Accepted: 2-channel PCM 16/32-bit integer or 32/64-bit float WAV, read with scipy.io.wavfile; integer
samples are scaled to [-1, 1). Refused with a one-line reason: mono or > 2 channels, 8-bit or 24-bit
files (scipy reads 24-bit as padded int32 on some versions; convert with sox or ffmpeg), empty or
unreadable files, a directory, NaN/inf samples, float samples beyond +-:data:`MAX_SAMPLE`, and a header that
contradicts itself or the file (a block align or byte rate that does not fit the other fields, data shorter or
longer than the header states: io/riff_header.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.riff_header import walk_riff

#: largest float sample magnitude taken (floats are nominally within [-1, 1]; any gain short of overflow)
MAX_SAMPLE = 1e15


def _read_checked(p: Path) -> tuple[int, np.ndarray]:
    """scipy's reading of ``p``, its header first checked against itself and the file (io/riff_header.py), and the
    frames read compared with the frames stated (scipy reads a truncated file short, with a warning only)."""
    import warnings

    from scipy.io import wavfile

    with open(p, "rb") as fh:
        riff = fh.read(4) in (b"RIFF", b"RF64")
    header = walk_riff(p, 1.0) if riff else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fs, data = wavfile.read(p)
    except (ValueError, EOFError, OSError, TypeError, ZeroDivisionError) as exc:
        raise InputError(f"cannot read {p.name} as WAV ({exc}): give a PCM or float WAV file") from None
    if header is not None and header.block_align and data.ndim == 2:
        stated = header.data_bytes // header.block_align
        require(data.shape[0] >= stated, f"{p.name} is truncated: the header states {stated} frames but only "
                                         f"{data.shape[0]} are present: copy the file again, or repair its header "
                                         "(e.g. sox --ignore-length in.wav out.wav)")
    return fs, data


def read_two_channel_wav(path) -> tuple[np.ndarray, float]:
    """Read a two-channel WAV recording for the bearing estimator (accepted formats in the module docstring).

    Parameters
    ----------
    path : str or path-like
        The WAV file.

    Returns
    -------
    signals : ndarray of float64, shape (2, n)
        The two channels; integer samples scaled to [-1, 1) (full scale), float samples as stored.
    fs : float
        Sample rate (Hz).

    Raises
    ------
    InputError
        If the file is missing, empty, unreadable, not two channels, of an unsupported sample format, or
        holds NaN/inf or implausibly large samples.
    """
    p = Path(path)
    require(not p.is_dir(), f"recording {p} is a directory: give the WAV file inside it")
    require(p.is_file(), f"recording not found: {p}")
    require(p.stat().st_size > 0, f"recording {p.name} is empty (0 bytes): give a two-channel WAV file")
    fs, data = _read_checked(p)
    if data.ndim == 1:
        raise InputError(f"{p.name} is mono: the bearing estimator needs two channels (one per sensor or half-array)")
    require(data.shape[1] == 2, f"{p.name} has {data.shape[1]} channels: extract the two sensors' channels into a "
                                "2-channel file (e.g. sox in.wav out.wav remix 1 2)")
    require(data.shape[0] > 0, f"{p.name} holds no samples")
    kind = data.dtype
    if kind == np.int16:
        x = data.astype(float) / 32768.0
    elif kind == np.int32:
        x = data.astype(float) / 2147483648.0
    elif kind in (np.float32, np.float64):
        x = data.astype(float)
    else:
        raise InputError(f"{p.name} has {kind} samples ({'8-bit' if kind == np.uint8 else 'unsupported'} format): "
                         "convert to 16-bit PCM or 32-bit float WAV")
    require(bool(np.all(np.isfinite(x))), f"{p.name} contains NaN/inf samples: clean the recording")
    peak = float(np.max(np.abs(x)))
    require(peak <= MAX_SAMPLE, f"{p.name} has a sample of magnitude {peak:g} (beyond {MAX_SAMPLE:g}): float samples "
                                "are normally within [-1, 1]; rescale the recording")
    return np.ascontiguousarray(x.T), float(fs)
