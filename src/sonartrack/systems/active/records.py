"""Typed records of an active scene's files: the ping table and the navigation (systems/active/scene_files.py).

Arrays in SI units (headings in radians, clockwise from north, unwrapped); one row per ping or per navigation
time. Each record is a frozen dataclass of arrays, the form the active chain's stages pass between them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.matched_filter import Waveform


@dataclass(frozen=True, slots=True)
class PingTable:
    """The pings, arrays (P,): ``ping`` number (1-based), ``transmit_time_s`` (s), ``file`` (path relative to the
    scene folder), waveform ``kind`` (lfm | cw), carrier ``fc_hz``, ``bandwidth_hz`` (0 for a CW),
    ``duration_s`` (pulse length), sample rate ``fs_hz``, ``channels`` and ``samples`` of each ping file."""

    ping: np.ndarray
    transmit_time_s: np.ndarray
    file: np.ndarray
    kind: np.ndarray
    fc_hz: np.ndarray
    bandwidth_hz: np.ndarray
    duration_s: np.ndarray
    fs_hz: np.ndarray
    channels: np.ndarray
    samples: np.ndarray

    def __len__(self) -> int:
        return int(self.ping.size)

    def waveform(self, i: int) -> Waveform:
        """The transmitted pulse of row ``i``.

        Parameters
        ----------
        i : int
            Row of the table (0-based).

        Returns
        -------
        Waveform
            Kind (lfm | cw), pulse length (s), carrier (Hz) and bandwidth (Hz; 0 for a CW).
        """
        kind = str(self.kind[i])
        return Waveform(kind, float(self.duration_s[i]), float(self.fc_hz[i]),
                        float(self.bandwidth_hz[i]) if kind == "lfm" else 0.0)


@dataclass(frozen=True, slots=True)
class ActiveNav:
    """Ownship, source and array centre against time (T,): positions (T, 2) in m, headings (T,) in rad
    (unwrapped, so a turn through north interpolates the short way)."""

    time_s: np.ndarray
    own_xy: np.ndarray
    own_heading_rad: np.ndarray
    source_xy: np.ndarray
    array_xy: np.ndarray
    array_heading_rad: np.ndarray

    def at(self, t_s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(source xy (n, 2), array centre xy (n, 2), array heading (n,) rad) at times ``t_s``, linear in time
        (end values outside the record).

        Parameters
        ----------
        t_s : float or array (n,)
            Time(s) (s).

        Returns
        -------
        source_xy, array_xy : numpy.ndarray
            (n, 2) positions [x east, y north] (m); n = 1 for a scalar ``t_s``.
        array_heading_rad : numpy.ndarray
            (n,) heading of the array's forward axis (rad, clockwise from north, unwrapped).
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float))

        def lerp(v):
            return np.interp(t, self.time_s, v)

        source = np.stack([lerp(self.source_xy[:, 0]), lerp(self.source_xy[:, 1])], axis=-1)
        array = np.stack([lerp(self.array_xy[:, 0]), lerp(self.array_xy[:, 1])], axis=-1)
        return source, array, lerp(self.array_heading_rad)
