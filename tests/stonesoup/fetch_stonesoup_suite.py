"""Fetch Stone Soup's own data-association, hypothesiser and updater tests (install time: `make stonesoup-suite`).

Stone Soup's wheel ships no tests; its source distribution does. This script downloads the sdist of the
*installed* Stone Soup version with pip (``pip download --no-binary :all: --no-deps``) and extracts into
DEST only what tests/stonesoup/test_stonesoup_suite.py runs:

    DEST/pyproject.toml                          Stone Soup's pytest settings (its rootdir)
    DEST/stonesoup/dataassociator/tests/...      the JPDA / PDA associator tests and their conftest
    DEST/stonesoup/hypothesiser/tests/...        the PDA hypothesiser tests and their conftest
    DEST/stonesoup/updater/tests/...             the PDA updater test (among the others)
    DEST/stonesoup/__init__.py, DEST/stonesoup/<sub>/__init__.py
                                                 empty markers, so that pytest names the test modules
                                                 stonesoup.<sub>.tests.* (their relative imports then
                                                 resolve to the installed Stone Soup)
    DEST/VERSION                                 the Stone Soup version the tests came from

Usage: python tests/stonesoup/fetch_stonesoup_suite.py DEST [--sdist PATH]   (PATH: an already downloaded sdist)
The tests themselves never touch the network; without DEST they skip with a reason.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

SUBPACKAGES = ("dataassociator", "hypothesiser", "updater")


def download_sdist(version: str, into: Path) -> Path:
    """pip download of stonesoup==version as a source distribution."""
    subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--no-binary", ":all:",
                    "--dest", str(into), f"stonesoup=={version}"], check=True)
    return next(into.glob("stonesoup-*.tar.gz"))


def extract(sdist: Path, dest: Path, version: str) -> int:
    """Extract the test folders and pytest settings (module doc); returns the number of files."""
    wanted = [f"stonesoup/{sub}/tests/" for sub in SUBPACKAGES]
    count = 0
    with tarfile.open(sdist) as tar:
        for member in tar.getmembers():
            rel = member.name.split("/", 1)[1] if "/" in member.name else ""
            if not member.isfile() or not (rel == "pyproject.toml" or any(rel.startswith(w) for w in wanted)):
                continue
            target = dest / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(tar.extractfile(member).read())
            count += 1
    for marker in ["stonesoup"] + [f"stonesoup/{sub}" for sub in SUBPACKAGES]:
        (dest / marker / "__init__.py").write_text("# marker only: the installed Stone Soup is imported\n")
    (dest / "VERSION").write_text(version + "\n")
    return count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dest", type=Path)
    parser.add_argument("--sdist", type=Path, default=None)
    args = parser.parse_args()
    version = importlib.metadata.version("stonesoup")
    shutil.rmtree(args.dest, ignore_errors=True)
    args.dest.mkdir(parents=True)
    with tempfile.TemporaryDirectory() as tmp:
        sdist = args.sdist or download_sdist(version, Path(tmp))
        n = extract(sdist, args.dest, version)
    print(f"Stone Soup {version} tests: {n} files in {args.dest}")


if __name__ == "__main__":
    main()
