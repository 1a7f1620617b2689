"""The simulate system: a passive towed-array scene and a sample input for every other command
(``sonartrack simulate``). The one system that imports sim/: making data is its job.

* settings.py -- the one settings tree, :class:`~sonartrack.sim.scene.PassiveSceneSettings`;
* run.py -- :func:`simulate_passive` (the recording, block by block, with the navigation and the truth) and
  :func:`simulate_samples` (contacts, frames, bearings + ownship, sound-speed profile): typed records of arrays;
* files.py -- :func:`~sonartrack.systems.simulate.files.write_scene` writes them all (the file list is there).

Nothing is imported here: ``from sonartrack.systems.simulate.files import write_scene``.
"""
