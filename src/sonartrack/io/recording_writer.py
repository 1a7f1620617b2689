"""Block writer of N-channel recordings through libsndfile (``soundfile``): WAV below 4 GiB, RF64 above, FLAC.

A plain WAV states its sizes in 32-bit fields, so its data stops at 4 GiB (about 4.7 h of 16 channels of
float32 at 4 kHz); RF64 (EBU Tech 3306) is the same layout with 64-bit sizes in a ``ds64`` chunk, read by
libsndfile, sox, ffmpeg and our reader (io/wav_blocks.py). The container of a ``.wav`` path is chosen from
the frames the caller expects to write: WAV when the data fits in :data:`WAV_LIMIT_BYTES`, RF64 otherwise (so
every file that can be a plain WAV, readable by any tool, is one). libsndfile has an RF64 auto-downgrade
command that decides at close instead, but ``soundfile`` does not expose it; the simulator knows its
duration, so the choice up front costs nothing. Writing past the limit of a WAV is refused, never wrapped.

Sample formats: float32, float64 (stored as given), int16, int24, int32 (stored as
round(x 2^(bits-1) / full_scale), clipped to the integer range: the exact inverse of the reader's
x / 2^(bits-1), so a read-back is within half a step of the input). FLAC holds int16 or int24 only, and at
most 8 channels.
A float32 plain WAV is written by io/wav_writer.py (a 16-byte ``fmt`` chunk, format tag 3, then ``data``: the
smallest header every reader takes, and the bytes ``sonartrack simulate`` has always written); every other
container and sample format by libsndfile.
The file is written to a hidden sibling and renamed when the writer closes (io/atomic.py): it appears
complete or not at all.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import soundfile as sf

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import atomic_path
from sonartrack.io.wav_writer import WavBlockWriter, wav_block_writer

#: data bytes a plain WAV can state (32-bit RIFF size, less its header and a margin for chunks libsndfile adds)
WAV_LIMIT_BYTES = 2**32 - 1 - 4096
#: sample format -> (libsndfile sub-type, bytes per sample, integer bits or 0 for float)
SAMPLE_FORMATS = {"float32": ("FLOAT", 4, 0), "float64": ("DOUBLE", 8, 0), "int16": ("PCM_16", 2, 16),
                  "int24": ("PCM_24", 3, 24), "int32": ("PCM_32", 4, 32)}
_FLAC_FORMATS = ("int16", "int24")
#: the FLAC format's channel limit (its frame header codes 1..8 channels)
FLAC_MAX_CHANNELS = 8


def choose_container(path, channels: int, sample_format: str, expected_frames: int | None,
                     wav_limit_bytes: int = WAV_LIMIT_BYTES) -> str:
    """The libsndfile major format for ``path``: FLAC for .flac, W64 for .w64, RF64 for .rf64; for .wav, WAV
    when ``expected_frames`` x channels x bytes per sample fits in ``wav_limit_bytes``, else RF64.

    Parameters
    ----------
    path : str or Path
        The file to write (its suffix names the container).
    channels : int
        Channels per frame.
    sample_format : str
        One of :data:`SAMPLE_FORMATS`.
    expected_frames : int or None
        Frames the caller will write (None: unknown, a .wav is then a plain WAV up to its limit).
    wav_limit_bytes : int
        Largest data size of a plain WAV (bytes).

    Returns
    -------
    str
        "WAV", "RF64", "W64" or "FLAC".
    """
    require(sample_format in SAMPLE_FORMATS, f"unknown sample format '{sample_format}': choose one of "
                                             f"{', '.join(SAMPLE_FORMATS)}")
    suffix = Path(path).suffix.lower()
    fixed = {".flac": "FLAC", ".w64": "W64", ".rf64": "RF64"}
    require(suffix in fixed or suffix == ".wav", f"{path}: unknown recording suffix '{suffix}': use .wav (WAV or "
                                                 "RF64 by size), .rf64, .w64 or .flac")
    if suffix == ".flac":
        require(sample_format in _FLAC_FORMATS, f"FLAC holds 16- or 24-bit integers, not {sample_format}: use "
                                                "sample format int24 or a .wav file")
        require(channels <= FLAC_MAX_CHANNELS, f"FLAC holds at most {FLAC_MAX_CHANNELS} channels, not {channels}: "
                                               "write a .wav (WAV or RF64) or .w64 file")
    if suffix in fixed:
        return fixed[suffix]
    data_bytes = 0 if expected_frames is None else int(expected_frames) * channels * SAMPLE_FORMATS[sample_format][1]
    return "WAV" if data_bytes <= wav_limit_bytes else "RF64"


class RecordingWriter:
    """Append (channels, m) blocks to an open SoundFile; see the module doc for containers and scaling."""

    def __init__(self, f: sf.SoundFile, container: str, channels: int, sample_format: str, full_scale: float,
                 wav_limit_bytes: int):
        self._f, self.container, self.channels = f, container, int(channels)
        self.sample_format, self.full_scale = sample_format, float(full_scale)
        _, self._bytes, self._bits = SAMPLE_FORMATS[sample_format]
        self._limit = wav_limit_bytes if container == "WAV" else None
        self.frames_written, self.blocks_written = 0, 0

    def _encode(self, x: np.ndarray) -> np.ndarray:
        """(m, channels) array handed to libsndfile: floats as given, integers quantised here (libsndfile takes
        int32 values as the top bits of a 24-bit sample, so those are shifted up by 8 bits)."""
        if not self._bits:
            return np.ascontiguousarray(x.T, dtype=np.float32 if self._bytes == 4 else np.float64)
        top = 2.0 ** (self._bits - 1)
        q = np.clip(np.round(x.T * (top / self.full_scale)), -top, top - 1)
        if self._bits == 16:
            return np.ascontiguousarray(q, dtype=np.int16)
        q = q.astype(np.int64) << (32 - self._bits)
        return np.ascontiguousarray(q, dtype=np.int32)

    def write(self, block) -> None:
        """Append a block of shape (channels, m) (float samples; integers quantised as the module doc says).

        Parameters
        ----------
        block : array_like, shape (channels, m)
            Samples; a .wav that would pass 4 GiB without a stated length is refused (:class:`InputError`).
        """
        x = np.asarray(block, dtype=np.float64)
        require(x.ndim == 2 and x.shape[0] == self.channels,
                f"a recording block must be ({self.channels}, m) samples, got {x.shape}")
        if self._limit is not None and (self.frames_written + x.shape[1]) * self.channels * self._bytes > self._limit:
            raise InputError("the recording would exceed the 4 GiB limit of a WAV file: state its length up front "
                             "(expected_frames) so that it is written as RF64, or shorten it")
        self._f.write(self._encode(x))
        self.frames_written += x.shape[1]
        self.blocks_written += 1


class _PlainFloatWav:
    """A float32 WAV below 4 GiB through io/wav_writer.py (module doc: the same bytes as before RF64 existed)."""

    container, sample_format, full_scale = "WAV", "float32", 1.0

    def __init__(self, plain: WavBlockWriter, wav_limit_bytes: int):
        self._plain, self.channels, self._limit = plain, plain.n_channels, int(wav_limit_bytes)

    def write(self, block) -> None:
        """Append a block of shape (channels, m); refused past the limit of a WAV (as :class:`RecordingWriter`)."""
        m = np.shape(block)[1] if np.ndim(block) == 2 else 0
        if (self.frames_written + m) * self.channels * 4 > self._limit:
            raise InputError("the recording would exceed the 4 GiB limit of a WAV file: state its length up front "
                             "(expected_frames) so that it is written as RF64, or shorten it")
        self._plain.write(block)

    @property
    def frames_written(self) -> int:
        return self._plain.frames_written

    @property
    def blocks_written(self) -> int:
        return self._plain.blocks_written


@contextmanager
def recording_writer(path, channels: int, sample_rate_hz: float, sample_format: str = "float32",
                     full_scale: float = 1.0, *, expected_frames: int | None = None,
                     wav_limit_bytes: int = WAV_LIMIT_BYTES) -> Iterator[RecordingWriter]:
    """A :class:`RecordingWriter` on ``path``, written atomically: the file appears, complete, when the block ends.

    Parameters
    ----------
    path : str or Path
        .wav (WAV or RF64 by size, :func:`choose_container`), .rf64, .w64 or .flac.
    channels : int
        Channels per frame.
    sample_rate_hz : float
        Sample rate (Hz), an integer number of hertz in the header.
    sample_format : str
        float32, float64, int16, int24 or int32 (FLAC: int16 or int24).
    full_scale : float
        For integer formats, the sample value stored as the largest integer (same unit as the samples).
    expected_frames : int or None
        Frames that will be written; a .wav larger than ``wav_limit_bytes`` is then written as RF64.
    wav_limit_bytes : int
        Largest data size (bytes) of a plain WAV.

    Returns
    -------
    Iterator of RecordingWriter
        Yields the writer; ``write(block)`` appends (channels, m) samples.
    """
    require(int(channels) >= 1, f"a recording needs at least one channel, got {channels}")
    rate = int(round(sample_rate_hz))
    require(rate > 0 and abs(rate - sample_rate_hz) < 1e-9 * max(rate, 1),
            f"sample rate {sample_rate_hz} Hz is not a whole number of hertz: a WAV/FLAC header holds an integer")
    container = choose_container(path, int(channels), sample_format, expected_frames, wav_limit_bytes)
    if container == "WAV" and sample_format == "float32":
        with wav_block_writer(path, int(channels), rate, "float32") as plain:
            yield _PlainFloatWav(plain, wav_limit_bytes)
        return
    subtype = SAMPLE_FORMATS[sample_format][0]
    with atomic_path(path) as tmp, sf.SoundFile(str(tmp), "w", rate, int(channels), subtype=subtype,
                                                 format=container) as f:
        writer = RecordingWriter(f, container, int(channels), sample_format, full_scale, wav_limit_bytes)
        yield writer
