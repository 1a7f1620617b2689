"""The console's bounded memory: each display update encoded to JSON once, kept in ring buffers by kind.

A client that joins late (or reconnects) gets one ``{"type": "history", "updates": [...]}`` message holding the
series (bearing-time rows, track positions, LOFAR rows, ownship positions, B-scans) as far back as the buffers
reach, the health updates that reported events (the event log), then the latest of every other kind (targets,
health, the selection). The buffers have a fixed length, so a day of updates takes no more memory than
``history_rows`` of them (issue 31 item 4).
"""

from __future__ import annotations

import json
import math
import re
import threading
from collections import deque

import numpy as np

#: kinds kept as a series of rows (oldest dropped first); any other kind keeps its latest update only
SERIES_KINDS = ("ownship", "btr", "tracks", "lofar", "bscan")
#: B-scans are large (bearings x ranges): fewer of them are kept
BSCAN_ROWS = 32
#: health updates that carry events (gaps, reconnects, ...) kept for the event log of a late client
EVENT_ROWS = 256
_KIND = re.compile(r"[a-z_]{1,32}")


def _plain(value):
    """``value`` with NumPy arrays and scalars as lists and numbers, and every non-finite float as None (JSON
    has no NaN: the page shows a missing value, never a made-up one)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def encode_update(update: dict) -> tuple[str, str]:
    """(kind, JSON text) of a display update; ValueError when it is not a dict with a ``"type"`` of lower-case
    letters (the chain's bug, raised in the publisher's thread, not in the server's)."""
    if not isinstance(update, dict) or not isinstance(update.get("type"), str) or not _KIND.fullmatch(update["type"]):
        raise ValueError(f"a display update is a dict with a 'type' of 1-32 lower-case letters, not {update!r:.80}")
    try:
        text = json.dumps(_plain(update), separators=(",", ":"), allow_nan=False)
    except TypeError as exc:
        raise ValueError(f"display update {update['type']!r} holds a value JSON cannot carry: {exc}") from None
    return update["type"], text


class UpdateHistory:
    """Ring buffers of encoded updates, safe to fill from one thread and read from another.

    Parameters
    ----------
    rows : int
        Length of each series buffer (bearing-time rows, track scans, LOFAR rows, ownship fixes).
    """

    def __init__(self, rows: int):
        if int(rows) < 1:
            raise ValueError(f"history_rows must be at least 1, not {rows}")
        self.rows = int(rows)
        self._series = {k: deque(maxlen=BSCAN_ROWS if k == "bscan" else self.rows) for k in SERIES_KINDS}
        self._events: deque[str] = deque(maxlen=EVENT_ROWS)
        self._latest: dict[str, str] = {}
        self._lock = threading.Lock()

    def add(self, kind: str, text: str, *, has_events: bool = False) -> None:
        """Keep an encoded update; ``has_events``: a health update whose events go to the event log too."""
        with self._lock:
            if kind in self._series:
                self._series[kind].append(text)
            else:
                self._latest[kind] = text
            if has_events:
                self._events.append(text)

    def snapshot(self) -> str:
        """The history message: every series oldest first, then the latest update of every other kind."""
        with self._lock:
            latest = list(self._latest.values())
            events = [t for t in self._events if t is not self._latest.get("health")]
            texts = [t for k in SERIES_KINDS for t in self._series[k]] + events + latest
        return '{"type":"history","updates":[' + ",".join(texts) + "]}"

    def chars(self) -> int:
        """Characters held (the history's memory, to within Python's per-string overhead)."""
        with self._lock:
            queues = [*self._series.values(), self._events]
            return sum(len(t) for q in queues for t in q) + sum(map(len, self._latest.values()))
