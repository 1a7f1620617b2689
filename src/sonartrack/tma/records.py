"""Plain containers for TMA data shared by the estimators, the readers (io/) and the CLI.

They live in tma/ (not io/) because the estimators take and return them and io/ sits above tma/ in
the layering; ``sonartrack.io.records`` re-exports them for readers.

These are the API boundary between ``io/`` (which reads and validates files) and the algorithm
layers (which take arrays). All quantities are SI: seconds, metres, radians, hertz, dB.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class BearingRecord:
    """Passive measurements against time: bearing (rad, clockwise from north, (-pi, pi]),
    optionally received frequency (Hz) and SNR (dB). Times strictly increasing."""

    time_s: np.ndarray
    bearing_rad: np.ndarray
    frequency_hz: np.ndarray | None = None
    snr_db: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class OwnshipTrack:
    """Own-ship navigation: position (m, x east, y north) against time (s), strictly increasing."""

    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray

    def position_at(self, t_s) -> np.ndarray:
        """Linearly interpolated position (..., 2) at times ``t_s`` (caller checks the time span)."""
        t = np.asarray(t_s, dtype=float)
        return np.stack([np.interp(t, self.time_s, self.x_m), np.interp(t, self.time_s, self.y_m)], axis=-1)


@dataclass(frozen=True, slots=True)
class TmaSolution:
    """A target solution against time: state ``[x, y, vx, vy]`` (m, m/s) and its covariance."""

    time_s: np.ndarray
    state: np.ndarray  # (n, 4)
    covariance: np.ndarray  # (n, 4, 4)
    method: str
