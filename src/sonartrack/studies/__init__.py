"""Studies: one module per source paper, each reproducing that paper's experiment.

A study is simulate -> estimate -> summarize -> claims. Every study module exposes the same small
surface (the *study contract*), so the runner, the report and the CLI treat them alike:

``STUDY_ID``, ``TITLE``, ``PAPER``
    identifier (as typed on the command line), a title, and the citation.
``TRIAL_VERSION``
    an integer bumped whenever ``run_trial`` changes its numbers; it is part of the cache key.
``Config``
    a frozen settings model (``sonartrack.core.settings.Settings``, each field declared with
    ``setting(default, doc, unit=...)``) whose defaults are the paper's values (and our documented
    choices), with a ``runs`` field (full Monte Carlo size) and a classmethod ``quick()`` returning
    the CI preset. It must round-trip through TOML (scalars, lists, nested tables).
``run_trial(config, rng) -> dict[str, np.ndarray]``
    one Monte Carlo trial; a pure function of its inputs; every array has a shape fixed by the
    config (pad with NaN where a trial has fewer values).
``summarize(trials, config) -> dict``
    ``trials`` maps each key to the arrays of all trials stacked on axis 0; the result is
    JSON-serialisable (lists, numbers, strings).
``claims(summary, config) -> list[Claim]``
    each published result restated as a check on our numbers, one
    :class:`sonartrack.experiment.claims.Claim` record each (id, paper, text, ours, holds,
    tolerance: the tolerance used and why); the pipeline stores them as dicts in summary.json.
``prepare(config) -> None`` (optional)
    computes shared inputs once in the main process before trials run (e.g. cached TL fields).

A study draws no pictures: its figures live in ``sonartrack/report/figures/<module>.py`` as
``figures(summary, config) -> {name: matplotlib Figure}`` (the key ``"scenario"``, if present, is shown
first in the report), reached through :func:`sonartrack.report.figures.study_figures`.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from sonartrack.core.errors import InputError

#: study id -> module path, in the order of the papers (P0..P4).
STUDIES: dict[str, str] = {
    "jpda-amplitude": "sonartrack.studies.jpda_amplitude",
    "mftd": "sonartrack.studies.mftd",
    "mftd-sensitivity": "sonartrack.studies.mftd_sensitivity",
    "bftma-imm": "sonartrack.studies.bftma_imm",
    "bftma-sensitivity": "sonartrack.studies.bftma_sensitivity",
    "tma-propagation": "sonartrack.studies.tma_propagation",
    "tma-sensitivity": "sonartrack.studies.tma_sensitivity",
    "bistatic-imm-ipda": "sonartrack.studies.bistatic_imm_ipda",
    "passive-chain": "sonartrack.studies.passive_chain",
    "quiet-target": "sonartrack.studies.quiet_target",
    "active-chain": "sonartrack.studies.active_chain",
}


def available() -> list[str]:
    """Ids of the studies whose module is present in this installation."""
    return [sid for sid, mod in STUDIES.items() if importlib.util.find_spec(mod) is not None]


def load(study_id: str) -> ModuleType:
    """Import a study module by id; unknown ids raise :class:`InputError` listing the choices."""
    ids = available()
    if study_id not in ids:
        raise InputError(f"unknown study '{study_id}': choose one of {', '.join(ids)} (or 'all')")
    return importlib.import_module(STUDIES[study_id])
