"""The tma system: a bearings (+ frequency, SNR) record and the ownship track in, a target solution out
(``sonartrack tma``).

* settings.py -- the one settings tree, :class:`~sonartrack.tma.settings.TmaSettings`;
* run.py -- :func:`run_tma`: tma/solve.py's ``solve_tma`` plus the em-map environment looked up from the
  settings (a shipped environment or a profile file);
* files.py -- reads the bearings, ownship and environment files, writes ``tma_solution.csv``.

Nothing is imported here: ``from sonartrack.systems.tma.run import run_tma``.
"""
