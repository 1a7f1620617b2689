"""Re-export of the TMA record containers (defined in tma/records.py, below io/ in the layering)."""

from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution

__all__ = ["BearingRecord", "OwnshipTrack", "TmaSolution"]
