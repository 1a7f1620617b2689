"""The live stream's types: a stream's header, its sample blocks, navigation fixes and health events.

STUB (helper CHAIN's branch): the definitions of /work/team/LIVE.md, verbatim, until helper STREAM's io/stream/
lands; the lead keeps STREAM's copy.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

import numpy as np


@dataclass(frozen=True, slots=True)
class StreamHeader:
    """A sample stream's header."""

    channels: int
    rate_hz: float
    sample_format: str            # "int16" | "int24" | "float32"
    start_utc: datetime           # UTC time of sample index 0 (timezone-aware)
    full_scale_v: float | None = None   # calibration, as passive's --full-scale
    source: str = ""              # "tcp://host:port" or a folder path, for messages


@dataclass(frozen=True, slots=True)
class SampleBlock:
    """Samples from ``first_index`` on."""

    first_index: int              # index of the first sample since start_utc (rate_hz)
    samples: np.ndarray           # float32 (n, channels), scaled as passive's file reader scales (full scale = 1.0)


@dataclass(frozen=True, slots=True)
class NavFix:
    """One navigation fix."""

    utc: datetime
    lat_deg: float
    lon_deg: float
    heading_deg: float            # NaN when the sentence gives none (course over ground is not a heading)
    speed_mps: float = float("nan")


@dataclass(frozen=True, slots=True)
class StreamEvent:
    """Health: what happened on the wire."""

    kind: str                     # "connected" | "disconnected" | "gap" | "duplicate" | "late" | "bad_frame" | ...
    detail: str                   # one line for the operator
    first_index: int | None = None
    count: int | None = None
