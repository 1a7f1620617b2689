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
