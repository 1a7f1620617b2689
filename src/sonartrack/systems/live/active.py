"""Active pings on a live stream: each ping through the active chain's front end and single-ping detector as it
arrives, a B-scan update per ping (issue 31 items 1 and 3; partly: see below).

A ping frame (io/stream/frames.py, kind 4) carries one listening window as complex baseband. Per ping, the stages
systems/active/run.py runs for a file ping: the front end (detection/cells.py ``ping_front_end`` for an LFM,
detection/cw_cells.py ``cw_ping_cells`` for a CW: beams, matched filter, CFAR -> the normalised statistic per
beam x travel time x Doppler), the single-ping detections at the root's ``pfa``, and the B-scan row (the largest
statistic of each travel-time bin, run.py's own reduction, so that a live row equals the file chain's
``BScan.level`` row of the same ping). The update::

    {"type": "bscan", "t_s", "ping", "bearing_deg": [cone per beam], "range_m": [per bin],
     "level_db": [[per range] per bearing], "detections": int}

``bearing_deg`` are the beams' cone angles (deg from the array's forward axis, as the bearing-time record's);
``range_m`` is c tau / 2 of each bin's travel time tau: the monostatic range (the source and the array are a
tow length apart, so a bistatic target's range differs by up to half that); ``level_db`` = 10 log10 s.

Not done yet (what is left of item 3): the contacts, the IMM-IPDA tracker, the sides and the active targets in
the table need the ping's geometry (source and array positions and velocities) from the live navigation, as
systems/active/run.py's ``_Chain`` takes an ActiveGeometry of the whole run; and a CW's reverberation ridge is
notched here for a platform at rest (zero velocity) until then.
"""

from __future__ import annotations

import numpy as np

from sonartrack.io.stream.types import PingBlock, StreamHeader


class LiveActive:
    """The active chain's per-ping front end and detector on a stream's pings (module doc).

    Parameters
    ----------
    settings : ActiveSettings
        The active chain's settings (``spacing_m`` required; ``elements`` set from the stream).
    header : StreamHeader
        The stream (its channels are the array's elements).
    """

    def __init__(self, settings, header: StreamHeader):
        from sonartrack.acoustics.active_beams import LineArray

        s = self.settings = settings.checked(int(header.channels))
        self.array = LineArray(int(s.elements), float(s.spacing_m))
        self.front_end = s.front_end_settings()
        self.pings = 0
        self.last: dict | None = None

    def _cells(self, ping: PingBlock):
        from sonartrack.acoustics.matched_filter import Waveform
        from sonartrack.detection.cells import detection_threshold, ping_front_end
        from sonartrack.detection.cw_cells import cw_ping_cells, cw_threshold

        s, x = self.settings, np.asarray(ping.samples)
        w = Waveform(ping.kind, ping.duration_s, ping.fc_hz, ping.bandwidth_hz)
        if w.kind != "cw":
            return ping_front_end(x, ping.fs_hz, w, self.array, self.front_end, time_s=ping.transmit_time_s,
                                  ping=ping.ping), detection_threshold(self.front_end)
        motion = (0.0, np.zeros(2), np.zeros(2))  # platforms at rest until the live navigation reaches here
        cells = cw_ping_cells(x, ping.fs_hz, w, self.array, self.front_end, s.cw, time_s=ping.transmit_time_s,
                              ping=ping.ping, motion=motion)
        return cells, cw_threshold(s.pfa, s.cw)

    def push_ping(self, ping: PingBlock) -> list[dict]:
        """One ping: its B-scan update (module doc)."""
        from sonartrack.core.errors import require
        from sonartrack.detection.cells import detect_ping
        from sonartrack.systems.active.run import _bscan_axis, _bscan_row  # the file chain's own B-scan reduction

        s = self.settings
        require(ping.samples.shape[0] == s.elements, f"ping {ping.ping} has {ping.samples.shape[0]} channels, the "
                                                     f"stream {s.elements}: give the pings of one array")
        cells, threshold = self._cells(ping)
        detections = detect_ping(cells, threshold)
        row = _bscan_row(cells.statistic, s.bscan_bins)
        range_m = 0.5 * s.sound_speed_mps * _bscan_axis(np.asarray(cells.delay_s, float), s.bscan_bins)
        self.pings += 1
        self.last = {"type": "bscan", "t_s": float(ping.transmit_time_s), "ping": int(ping.ping),
                     "bearing_deg": [float(c) for c in cells.cone_deg], "range_m": [float(r) for r in range_m],
                     "level_db": (10.0 * np.log10(np.maximum(row, 1e-12))).round(2).tolist(),
                     "detections": int(len(detections))}
        return [self.last]
