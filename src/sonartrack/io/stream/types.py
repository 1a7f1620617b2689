"""What the live sources yield: a stream's header, blocks of samples, navigation fixes and health events.

The contract between the streaming input (io/stream/), the live chain (systems/live/) and the console: a sample
source has a ``header`` (known after its first frame or file) and yields :class:`SampleBlock` in order and
contiguous, or a :class:`StreamEvent` (a gap before the block that follows it, a reconnect, a bad frame); a
navigation source yields :class:`NavFix` or :class:`StreamEvent`. Both stop with ``close()``.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

import numpy as np

#: the sample formats a stream carries (io/stream/frames.py codes them in one byte)
SAMPLE_FORMATS = ("int16", "int24", "float32")


@dataclass(frozen=True, slots=True)
class StreamHeader:
    """A sample stream's description: channels, sample rate (Hz), sample format on the wire (int16, int24,
    float32), the UTC time of sample index 0 (timezone-aware), the full-scale voltage of integer samples when the
    recorder states one (calibration, as passive's --full-scale; None: float samples are in pascals as simulate's
    WAV, integers are fractions of full scale), and where it comes from (for messages)."""

    channels: int
    rate_hz: float
    sample_format: str
    start_utc: datetime
    full_scale_v: float | None = None
    source: str = ""


@dataclass(frozen=True, slots=True)
class SampleBlock:
    """Samples ``first_index`` .. ``first_index + n - 1`` (indices since the header's start_utc at rate_hz), as
    float32 (n, channels), scaled as passive's file reader scales: integers k / 2^(bits - 1), floats as sent."""

    first_index: int
    samples: np.ndarray


@dataclass(frozen=True, slots=True)
class PingBlock:
    """One active ping's listening window (io/stream/frames.py, frame kind 4): its number (from 1), transmit time
    (s after the header's start_utc), the transmitted pulse (carrier and bandwidth (Hz; 0 for a CW), length (s)),
    the baseband sample rate (Hz) and the samples, complex64 (channels, n), as systems/active reads a ping file."""

    ping: int
    transmit_time_s: float
    fc_hz: float
    bandwidth_hz: float
    duration_s: float
    fs_hz: float
    samples: np.ndarray

    @property
    def kind(self) -> str:
        """The pulse: "lfm" (a sweep) or "cw" (a tone)."""
        return "lfm" if self.bandwidth_hz > 0 else "cw"


@dataclass(frozen=True, slots=True)
class NavFix:
    """One navigation fix: UTC time, position (deg, WGS84), true heading (deg; NaN when no sentence gives one:
    a course over ground is not a heading) and speed over ground (m/s; NaN when not given)."""

    utc: datetime
    lat_deg: float
    lon_deg: float
    heading_deg: float
    speed_mps: float = float("nan")


@dataclass(frozen=True, slots=True)
class StreamEvent:
    """What happened on the wire, for the operator: ``kind`` ("connected", "disconnected", "gap", "duplicate",
    "late", "overlap", "bad_frame", "refused", "nav_dropout", "nav_resumed", "bad_sentence", "nav_jump", ...), a
    one-line ``detail``, and for a gap, duplicate or late block its first sample index and sample count."""

    kind: str
    detail: str
    first_index: int | None = None
    count: int | None = None
