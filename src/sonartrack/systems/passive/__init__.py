"""The passive sonar system: an array recording and its navigation in, target tracks and solutions out.

    from sonartrack.systems.passive import PassiveSettings, run_passive_files
    result = run_passive_files("scene/recording.wav", "scene/nav.csv", PassiveSettings(spacing_m=2.5))
    for target in result.targets: print(target.side.side, target.ml.summary())

Modules: settings.py (the one settings tree and the stages built from it), chain.py (the stages joined:
:func:`run_passive`), measurements.py (a track's raw peaks), tonal_pass.py (tonal lines on the tracks'
beams), targets.py (side decision and TMA per track), tables.py (targets.csv and the summary lines), files.py
(the chain on files). The names below load on first use, so that importing the settings (the command line
does, at start) stays light.
"""

from __future__ import annotations

from sonartrack.core.lazy import lazy_exports

_EXPORTS = {
    "PassiveResult": "sonartrack.systems.passive.chain", "run_passive": "sonartrack.systems.passive.chain",
    "run_passive_files": "sonartrack.systems.passive.files",
    "write_passive_tables": "sonartrack.systems.passive.files",
    "PassiveSettings": "sonartrack.systems.passive.settings", "PassiveStages": "sonartrack.systems.passive.settings",
}
__getattr__, __all__ = lazy_exports(__name__, _EXPORTS)
