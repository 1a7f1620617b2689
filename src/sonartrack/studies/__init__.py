"""Studies: one module per source paper, each reproducing that paper's experiment.

A study is simulate -> estimate -> summarize -> claims. Every study module exposes the same small
surface (the *study contract*), so the runner, the report and the CLI treat them alike:

``STUDY_ID``, ``TITLE``, ``PAPER``
    identifier (as typed on the command line), a title, and the citation (string literals).
``RUNS``, ``QUICK_RUNS``
    integer literals: the Monte Carlo size of the full run and of the quick preset, the defaults that
    ``Config`` uses (below); :func:`listing` reads them and the title and citation from the module's source.
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

import ast
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
    "manoeuvring-target": "sonartrack.studies.manoeuvring_target",
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


#: the module-level names that :func:`listing` reads from a study's source, and the type each must have
_LISTED: dict[str, type] = {"TITLE": str, "PAPER": str, "RUNS": int, "QUICK_RUNS": int}


def _source_literals(origin: str | None) -> dict | None:
    """The :data:`_LISTED` names assigned a literal of their type at the top level of the source file ``origin``;
    None if the file is not Python source, cannot be read or parsed, or lacks one of them."""
    if not origin or not origin.endswith(".py"):
        return None
    try:
        with open(origin, encoding="utf-8") as fh:
            tree = ast.parse(fh.read(), origin)
    except (OSError, SyntaxError, ValueError):
        return None
    found = {}
    for stmt in tree.body:
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
            name = stmt.targets[0].id
            if name in _LISTED:
                try:
                    found[name] = ast.literal_eval(stmt.value)
                except (ValueError, TypeError):  # an expression: only the module itself can say its value
                    found.pop(name, None)
    ok = all(type(found.get(name)) is kind for name, kind in _LISTED.items())
    return found if ok else None


def listing() -> list[tuple[str, str, str, int, int]]:
    """What ``sonartrack studies`` prints: each available study's id, title, citation, full and quick run counts.

    Read from each module's source (``TITLE``, ``PAPER``, ``RUNS``, ``QUICK_RUNS``, literals by the study
    contract) without importing it, so that listing the studies loads none of their numerical libraries.

    Returns
    -------
    list of (str, str, str, int, int)
        (study id, ``TITLE``, ``PAPER``, ``Config().runs``, ``Config.quick().runs``) in :data:`STUDIES` order;
        run counts in Monte Carlo runs.
    """
    rows = []
    for sid, module in STUDIES.items():
        spec = importlib.util.find_spec(module)
        if spec is None:
            continue
        values = _source_literals(spec.origin)
        if values is None:
            # no readable source, or a name missing or built by an expression (a contract breach that
            # tests/studies/test_listing.py reports): import the module, slower but still right
            mod = importlib.import_module(module)
            values = {"TITLE": mod.TITLE, "PAPER": mod.PAPER, "RUNS": mod.Config().runs,
                      "QUICK_RUNS": mod.Config.quick().runs}
        rows.append((sid, values["TITLE"], values["PAPER"], values["RUNS"], values["QUICK_RUNS"]))
    return rows
