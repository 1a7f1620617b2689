"""Target motion analysis: sequential bearing (+ frequency) filters (paper P2) and batch ML / EM-MAP (paper P3).

The public entry points, importable from here (loaded on first use, so that importing a submodule stays
light)::

    solve_tma(record, ownship, settings) -> TmaResult      tma/solve.py
    BearingRecord, OwnshipTrack, TmaSolution                tma/records.py
    TmaSettings (and its groups)                            tma/settings.py
"""

from __future__ import annotations

from sonartrack.core.lazy import lazy_exports

_EXPORTS = {
    "solve_tma": "sonartrack.tma.solve", "TmaResult": "sonartrack.tma.solve",
    "correlation_inflation": "sonartrack.tma.solve",
    "BearingRecord": "sonartrack.tma.records", "OwnshipTrack": "sonartrack.tma.records",
    "TmaSolution": "sonartrack.tma.records", "check_coverage": "sonartrack.tma.records",
    "TmaSettings": "sonartrack.tma.settings", "ImmSettings": "sonartrack.tma.settings",
    "SequentialSettings": "sonartrack.tma.settings", "BatchSettings": "sonartrack.tma.settings",
    "EmMapSettings": "sonartrack.tma.settings", "InputSettings": "sonartrack.tma.settings",
}
__getattr__, __all__ = lazy_exports(__name__, _EXPORTS)
