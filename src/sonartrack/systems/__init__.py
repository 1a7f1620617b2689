"""The systems layer: sonartrack's end-to-end pipelines, one sub-package per system.

A system joins library stages (acoustics/, tracking/, tma/, detection/, io/ ...) into one pipeline a user runs
from end to end: ``systems/passive/`` (an array recording and its navigation in, bearing tracks and target
solutions out), ``systems/track/``, ``systems/tma/``, ``systems/detect/``, ``systems/simulate/`` and later
ones. Each sub-package holds

* ``settings.py``: ONE settings tree. Each physical quantity the stages share (the array, the sound speed, the
  time window, the detection threshold) is declared once at the root and handed down to the stages; a stage's
  group keeps only what is its own (``core.settings.derived_settings``), and the system's overrides of a
  library default are declared there as the system's defaults, with docs that describe those values;
* a run function (``run.py`` or ``chain.py``) with typed inputs and outputs: records and frozen dataclasses of
  arrays between the stages, no DataFrame and no ``object``;
* ``files.py``: the system on files, reading through io/ readers and writing atomically (DataFrames only
  here, at the file edge).

The faces call the systems: ``cli/<command>.py`` parses options and calls one system; a study calls the same
run function instead of re-assembling the stages. Layer rank: above io/ (a system reads and writes files)
and below experiment/ and studies/ (tests/architecture/test_layers.py). A system is an estimator: it never
imports sim/, except ``systems.simulate``, whose job is the simulator.
"""
