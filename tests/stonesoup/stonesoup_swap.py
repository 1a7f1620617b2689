"""pytest plugin that runs Stone Soup's own tests with sonartrack's components in place of Stone Soup's.

Loaded by tests/stonesoup/test_stonesoup_suite.py in a pytest subprocess (``-p stonesoup_swap``) on the
test files that tests/stonesoup/fetch_stonesoup_suite.py extracted from Stone Soup's sdist. Before any of
those files is imported it

* lets the installed Stone Soup find the extracted ``tests`` folders (``stonesoup.<sub>.__path__``), so the
  test modules' relative imports (``from ..probability import JPDA``) resolve to the installed package;
* rebinds Stone Soup's classes, by mode (env SONARTRACK_SWAP):
  ``jpda``: JPDA, JPDAwithEHM, JPDAwithEHM2 -> sonartrack JPDA;
  ``ipda``: PDA -> IPDA, JPDA / JPDAwithEHM / JPDAwithEHM2 -> JIPDA, PDAHypothesiser -> IPDAHypothesiser
  with existence 1 for tracks that carry none (IPDA is then PDA and JIPDA is JPDA, what the tests check);
* counts the calls into our classes, and writes per test its outcome and whether our code ran
  (JSON at env SONARTRACK_REPORT), so the caller can tell a pass of ours from a pass of theirs.
"""

from __future__ import annotations

import functools
import json
import os
from pathlib import Path

import pytest
import stonesoup.dataassociator
import stonesoup.hypothesiser
import stonesoup.updater
from stonesoup.base import Property
from stonesoup.dataassociator import probability as ss_associators
from stonesoup.hypothesiser import probability as ss_hypothesisers
from stonesoup.types.numeric import Probability

from sonartrack.stonesoup import IPDA, JIPDA, JPDA, IPDAHypothesiser

SUITE = Path(os.environ["SONARTRACK_SUITE"])
for _package in (stonesoup.dataassociator, stonesoup.hypothesiser, stonesoup.updater):
    _package.__path__.append(str(SUITE / "stonesoup" / _package.__name__.split(".")[-1]))


class ExistingIPDAHypothesiser(IPDAHypothesiser):
    """IPDAHypothesiser whose tracks without an existence probability are taken to exist."""

    default_existence: Probability = Property(default=Probability(1.0), doc="P(E) of tracks without one")


SWAPS = {
    "jpda": [(ss_associators, name, JPDA) for name in ("JPDA", "JPDAwithEHM", "JPDAwithEHM2")],
    "ipda": [(ss_associators, "PDA", IPDA), (ss_hypothesisers, "PDAHypothesiser", ExistingIPDAHypothesiser)]
    + [(ss_associators, name, JIPDA) for name in ("JPDA", "JPDAwithEHM", "JPDAwithEHM2")],
}
CALLS = [0]
RESULTS: dict[str, dict] = {}


def _counted(method):
    @functools.wraps(method)
    def wrapper(*args, **kwargs):
        CALLS[0] += 1
        return method(*args, **kwargs)

    return wrapper


for _module, _name, _ours in SWAPS[os.environ["SONARTRACK_SWAP"]]:
    setattr(_module, _name, _ours)
for _cls, _method in ((JPDA, "associate"), (IPDA, "associate"), (JIPDA, "associate"),
                      (IPDAHypothesiser, "hypothesise")):
    setattr(_cls, _method, _counted(getattr(_cls, _method)))


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    before = CALLS[0]
    yield
    RESULTS.setdefault(item.nodeid, {})["ours"] = CALLS[0] > before


def pytest_runtest_logreport(report):
    entry = RESULTS.setdefault(report.nodeid, {"ours": False})
    if report.when == "call" or report.outcome != "passed":
        entry["outcome"] = report.outcome


def pytest_sessionfinish(session):
    Path(os.environ["SONARTRACK_REPORT"]).write_text(json.dumps(RESULTS, indent=1))
