"""The sonar chains on a live stream: passive window by window, active ping by ping; bounded state, checkpoints (issue
31).

    from sonartrack.systems.live import LivePassive, run_live

Modules: passive.py (:class:`LivePassive`: the file chain's windowed core on a stream's windows, the finishing
stages on its bounded history), windows.py (blocks -> windows, the tonal spectra ring), navigation.py (fixes ->
Navigation, coasting), updates.py (the display updates), checkpoint.py (versioned, atomic checkpoints), run.py
(:func:`run_live`: the loop with its refresh and navigation threads); active pings: active.py (:class:`LiveActive`:
the file chain's per-ping core on a stream's pings), active_geometry.py (the source and the array from the fixes),
active_updates.py (the B-scan and the active target rows).
"""

from __future__ import annotations

from sonartrack.core.lazy import lazy_exports

_EXPORTS = {"LivePassive": "sonartrack.systems.live.passive", "run_live": "sonartrack.systems.live.run"}
__getattr__, __all__ = lazy_exports(__name__, _EXPORTS)
