"""The advise system: target solutions (or bearings) and the ownship's navigation in, the next ownship leg out
(``sonartrack advise``).

* settings.py -- the one settings tree, :class:`AdviceSettings`;
* run.py -- :func:`run_advice`: the ownship's legs (tma/observer_legs.py), its position and velocity now, and the
  advice of tma/advice.py for the targets brought to a common time;
* files.py -- reads the targets (``tma_solution.csv`` files of ``sonartrack tma``, or bearings files solved here by
  the constant-velocity batch ML) and the ownship file, writes ``advice.csv``.

Nothing is imported here: ``from sonartrack.systems.advise.run import run_advice``.
"""
