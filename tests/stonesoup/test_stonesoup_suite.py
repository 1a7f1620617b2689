"""Stone Soup's own tests, run with sonartrack's components in place of Stone Soup's.

The test files come from Stone Soup's sdist (its wheel has none), fetched at install time by
``make stonesoup-suite`` (tests/stonesoup/fetch_stonesoup_suite.py) into .venv/stonesoup-suite, or the
folder named by SONARTRACK_STONESOUP_SUITE. Each case runs pytest on those files in a subprocess with the
plugin tests/stonesoup/stonesoup_swap.py, which rebinds Stone Soup's classes to ours before the files are
imported and reports, per test, its outcome and whether our code ran:

* ``jpda``: Stone Soup's JPDA / JPDAwithEHM / JPDAwithEHM2 -> our JPDA, in its associator tests
  (dataassociator/tests/test_probability.py) and its KD-tree / TPR-tree associators built on JPDA
  (dataassociator/tests/test_tree.py);
* ``ipda``: PDA -> our IPDA, the JPDAs -> our JIPDA, PDAHypothesiser -> our IPDAHypothesiser (tracks without
  an existence probability taken to exist, where IPDA is PDA and JIPDA is JPDA), in the same files plus the
  hypothesiser tests (hypothesiser/tests/test_probability.py, test_composite.py) and the PDA updater test
  (updater/tests/test_probability.py).

No test code of Stone Soup's is copied here; nothing here touches the network.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

pytest.importorskip("stonesoup", reason="Stone Soup extra not installed: pip install sonartrack[stonesoup]")

HERE = Path(__file__).resolve().parent
SUITE = Path(os.environ.get("SONARTRACK_STONESOUP_SUITE", HERE.parents[1] / ".venv" / "stonesoup-suite"))
ASSOCIATOR_FILES = ["dataassociator/tests/test_probability.py", "dataassociator/tests/test_tree.py"]
CASES = {
    # mode: (files, least number of tests that must run our code)
    "jpda": (ASSOCIATOR_FILES, 12),
    "ipda": (ASSOCIATOR_FILES + ["hypothesiser/tests/test_probability.py", "hypothesiser/tests/test_composite.py",
                                 "updater/tests/test_probability.py"], 20),
}


def _suite() -> Path:
    """The fetched suite, or skip with the reason and the fix."""
    version_file = SUITE / "VERSION"
    if not version_file.is_file():
        pytest.skip(f"Stone Soup's own tests are not fetched into {SUITE}: run `make stonesoup-suite` "
                    "(downloads the stonesoup sdist at install time)")
    fetched, installed = version_file.read_text().strip(), importlib.metadata.version("stonesoup")
    if fetched != installed:
        pytest.skip(f"Stone Soup tests fetched for {fetched} but {installed} is installed: run `make stonesoup-suite`")
    return SUITE


def run_suite(mode: str, files: list[str], workdir: Path, plugin: str = "stonesoup_swap"):
    """pytest on Stone Soup's ``files`` with our classes swapped in by ``plugin`` (module doc; importable from
    this folder or ``workdir``): (per-test results, the completed run)."""
    suite = _suite()
    report = workdir / f"{mode}.json"
    path = [str(HERE), str(workdir)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])
    env = {**os.environ, "SONARTRACK_SUITE": str(suite), "SONARTRACK_SWAP": mode, "SONARTRACK_REPORT": str(report),
           "PYTHONPATH": os.pathsep.join(path)}
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", plugin, "-p", "no:cacheprovider",
           *[str(suite / "stonesoup" / f) for f in files]]
    run = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True, timeout=600)
    results = json.loads(report.read_text()) if report.is_file() else {}
    return results, run


@pytest.mark.parametrize("mode", sorted(CASES))
def test_stonesoup_suite_with_our_components(mode, tmp_path):
    files, least_ours = CASES[mode]
    results, run = run_suite(mode, files, tmp_path)
    counts = Counter(r.get("outcome", "error") for r in results.values())
    ours = Counter(r.get("outcome", "error") for r in results.values() if r["ours"])
    print(f"Stone Soup suite ({mode}): {dict(counts)}; tests that ran our components: {dict(ours)}")
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert counts["failed"] == 0 and counts["error"] == 0
    assert ours["passed"] >= least_ours, f"only {ours['passed']} passing tests ran our components"


def test_the_harness_can_fail(tmp_path):
    # Stone Soup's JPDA tests, run against a broken associator (every track left out), must fail
    (tmp_path / "broken_swap.py").write_text("from stonesoup_swap import *  # noqa: F403\n"
                                             "from sonartrack.stonesoup import JPDA\n"
                                             "JPDA.associate = lambda self, tracks, detections, timestamp, **kw: {}\n")
    results, run = run_suite("jpda", CASES["jpda"][0][:1], tmp_path, plugin="broken_swap")
    failed = [name for name, r in results.items() if r.get("outcome") == "failed"]
    assert run.returncode == 1 and failed and all("JPDA" in name for name in failed)
