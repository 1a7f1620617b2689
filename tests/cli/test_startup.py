"""A quick start: ``sonartrack --help`` and ``sonartrack studies`` import none of the heavy libraries.

Each command runs in a fresh interpreter through :func:`sonartrack.cli.main`, as the console script does,
which then prints the modules it imported; a heavy one (signal processing, JIT compiler, plotting, data
frames, columnar files, cluster scheduler) is imported only by the command that uses it, inside that
command. No time is asserted here: benchmarks/bench_cli_start.py times the whole process.
"""

import json
import os
import subprocess
import sys

import pytest

#: modules a quick command must not import (any submodule of these either)
HEAVY = ("scipy.signal", "scipy.stats", "scipy.ndimage", "numba", "matplotlib", "pandas", "pyarrow", "dask")

DRIVER = """
import json, sys
import sonartrack.cli as cli
status = cli.main(sys.argv[1:])
print("\\nMODULES " + json.dumps(sorted(sys.modules)))
sys.exit(status)
"""


def imported_by(*args: str) -> list[str]:
    """The modules a fresh interpreter holds after the command ``sonartrack *args`` (which must succeed)."""
    run = subprocess.run([sys.executable, "-c", DRIVER, *args], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "COLUMNS": "120"})
    assert run.returncode == 0, f"sonartrack {' '.join(args)} failed:\n{run.stdout[-2000:]}\n{run.stderr[-3000:]}"
    line = [ln for ln in run.stdout.splitlines() if ln.startswith("MODULES ")][-1]
    return json.loads(line.removeprefix("MODULES "))


def heavy(modules: list[str]) -> list[str]:
    return [m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY)]


@pytest.mark.parametrize("args", [("--help",), ("studies",)], ids=["help", "studies"])
def test_quick_commands_import_no_heavy_library(args):
    modules = imported_by(*args)
    assert "sonartrack.cli" in modules  # the driver went through the command line
    assert heavy(modules) == [], f"sonartrack {' '.join(args)} imported {heavy(modules)}"


def test_the_check_sees_a_heavy_import():
    """The same driver on a command that does use a heavy library reports it (the check can fail)."""
    run = subprocess.run([sys.executable, "-c", DRIVER.replace("status = cli.main(sys.argv[1:])",
                                                               "import scipy.signal; status = 0")],
                         capture_output=True, text=True, timeout=300)
    line = [ln for ln in run.stdout.splitlines() if ln.startswith("MODULES ")][-1]
    assert "scipy.signal" in heavy(json.loads(line.removeprefix("MODULES ")))


def test_studies_loads_only_its_own_command_module():
    """``sonartrack studies`` does not import the other commands' modules (and so their settings)."""
    modules = imported_by("studies")
    others = [m for m in modules if m.startswith("sonartrack.cli.") and m not in ("sonartrack.cli.studies",)
              and not m.rpartition(".")[2].startswith("_")]
    assert others == []


def test_studies_imports_no_study_module_and_no_numpy():
    """``sonartrack studies`` reads its listing from the study modules' source (``studies.listing``): no study
    module is imported, and so none of their numerical libraries or settings models; outside the command line
    itself, only the package root, its launcher, its error type and the studies package are loaded."""
    modules = imported_by("studies")
    ours = [m for m in modules if m.startswith("sonartrack") and not m.startswith("sonartrack.cli")]
    assert "sonartrack.cli.studies" in modules  # the command ran
    assert sorted(ours) == ["sonartrack", "sonartrack._launch", "sonartrack.core", "sonartrack.core.errors",
                            "sonartrack.studies"]
    assert "numpy" not in modules


def help_text(driver: str) -> str:
    run = subprocess.run([sys.executable, "-c", driver], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "COLUMNS": "120"})
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def test_help_lists_the_commands_without_importing_them():
    """``--help`` reads the commands' names and help from their modules' source: no settings, no numpy."""
    modules = imported_by("--help")
    loaded = [m for m in modules if m.startswith("sonartrack.cli.") or m.startswith("sonartrack.systems")]
    assert loaded == [] and "numpy" not in modules and "pydantic" not in modules


def test_help_read_from_the_source_is_the_help_of_the_loaded_commands():
    """The listing printed without importing the command modules is, character for character, the one the
    app prints with every command module imported and registered."""
    quick = help_text("import sonartrack.cli as cli; cli.main(['--help'])")
    full = help_text("import sonartrack.cli as cli; cli.load_commands(); cli.main(['--help'])")
    assert "reproduce" in quick and "studies" in quick
    assert quick == full
