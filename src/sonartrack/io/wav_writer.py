"""A WAV writer that takes the samples block by block (memory does not grow with the recording's length).

WAV format: RIFF/WAVE, format tag 3 (IEEE float) with 32-bit samples, or tag 1 with 16-bit PCM at a stated
full scale (:class:`WavBlockWriter`); the sizes in the header are written when the file is closed. A RIFF file
holds at most 4 GiB: a longer recording is refused with the fix (int16 or a shorter duration).
:func:`wav_block_writer` writes a file atomically (io/atomic.py). The reader is io/wav_blocks.py.
"""

from __future__ import annotations

import struct
from contextlib import contextmanager

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import atomic_path

#: largest data chunk of a RIFF file (bytes)
RIFF_MAX_BYTES = 2**32 - 1 - 36
#: sample formats: numpy dtype, WAVE format tag, bits per sample
WAV_FORMATS = {"float32": ("<f4", 3, 32), "int16": ("<i2", 1, 16)}


class WavBlockWriter:
    """Append (channels, m) blocks to an open binary file as WAV; :meth:`close` writes the header's sizes.

    ``float32`` stores the values as given; ``int16`` stores round(32767 x / full_scale), clipped (the
    scale is stated by the caller: a value of ``full_scale`` is the largest sample).

    Parameters
    ----------
    fh : binary file
        Open for writing and seekable; the header is written at once.
    n_channels : int
        Channels per sample frame.
    sample_rate_hz : float
        Sample rate (Hz), rounded to an integer in the header.
    sample_format : str
        ``float32`` (format tag 3) or ``int16`` (format tag 1, PCM).
    full_scale : float
        For ``int16``: the value stored as the largest sample (the samples' unit, e.g. Pa).
    """

    def __init__(self, fh, n_channels: int, sample_rate_hz: float, sample_format: str = "float32",
                 full_scale: float = 1.0):
        require(sample_format in WAV_FORMATS, f"unknown WAV sample format '{sample_format}': float32 or int16")
        self._fh, self.n_channels, self.full_scale = fh, int(n_channels), float(full_scale)
        self._dtype, tag, bits = WAV_FORMATS[sample_format]
        self.frames_written, self.blocks_written = 0, 0
        block_align = self.n_channels * bits // 8
        fmt = struct.pack("<HHIIHH", tag, self.n_channels, int(round(sample_rate_hz)),
                          int(round(sample_rate_hz)) * block_align, block_align, bits)
        fh.write(b"RIFF" + struct.pack("<I", 0) + b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt
                 + b"data" + struct.pack("<I", 0))
        self._bytes_per_frame = block_align

    def write(self, block) -> None:
        """Append a block of samples.

        Parameters
        ----------
        block : array_like, shape (channels, m)
            m sample frames (the samples' unit, e.g. Pa).
        """
        x = np.asarray(block)
        require(x.ndim == 2 and x.shape[0] == self.n_channels,
                f"a WAV block must be ({self.n_channels}, m) samples, got {x.shape}")
        if self._dtype == "<i2":
            x = np.clip(np.round(x * (32767.0 / self.full_scale)), -32768, 32767)
        data = np.ascontiguousarray(x.T, dtype=self._dtype).tobytes()
        if (self.frames_written + x.shape[1]) * self._bytes_per_frame > RIFF_MAX_BYTES:
            raise InputError("the recording would exceed the 4 GiB limit of a WAV file: shorten --duration-s or "
                             "use fewer elements")
        self._fh.write(data)
        self.frames_written += x.shape[1]
        self.blocks_written += 1

    def close(self) -> None:
        """Write the RIFF and data chunk sizes."""
        n_data = self.frames_written * self._bytes_per_frame
        self._fh.seek(4)
        self._fh.write(struct.pack("<I", 36 + n_data))
        self._fh.seek(40)
        self._fh.write(struct.pack("<I", n_data))
        self._fh.seek(0, 2)


@contextmanager
def wav_block_writer(path, n_channels: int, sample_rate_hz: float, sample_format: str = "float32",
                     full_scale: float = 1.0):
    """A :class:`WavBlockWriter` on ``path``, written atomically: the file appears, complete, when the block ends.

    Parameters
    ----------
    path : path-like
        The WAV file to write.
    n_channels, sample_rate_hz, sample_format, full_scale
        As :class:`WavBlockWriter` (sample rate in Hz).

    Returns
    -------
    contextmanager of WavBlockWriter
        The writer; its header sizes are written and the file moved into place when the block ends.
    """
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        writer = WavBlockWriter(fh, n_channels, sample_rate_hz, sample_format, full_scale)
        yield writer
        writer.close()
