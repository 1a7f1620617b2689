"""The passive sonar system: an array recording and its navigation in, target tracks and solutions out.

    from sonartrack.passive import PassiveSettings, run_passive_files
    result = run_passive_files("scene/recording.wav", "scene/nav.csv", PassiveSettings(spacing_m=2.5))
    for target in result.targets: print(target.side.side, target.ml.summary())

Modules: settings.py (the chain's settings, one group per stage), chain.py (the stages joined),
measurements.py (a track's raw peaks), tonal_pass.py (tonal lines on the tracks' beams), targets.py (side
decision and TMA per track), tables.py (targets.csv and the summary lines), files.py (the chain on files).
"""

from sonartrack.passive.chain import PassiveResult, run_passive
from sonartrack.passive.files import run_passive_files, write_passive_tables
from sonartrack.passive.settings import PassiveSettings

__all__ = ["PassiveResult", "PassiveSettings", "run_passive", "run_passive_files", "write_passive_tables"]
