"""Every command the README shows runs as written, in order, in a fresh folder (a copied command that fails is
worse than none).

The commands are the lines of the README's ```sh blocks that start with ``sonartrack `` (or
``.venv/bin/sonartrack ``), trailing ``# comments`` stripped, run through bash (so ``> file`` redirections
work) with the installed console script first on PATH. The first one is ``sonartrack simulate``, which
writes every input the others read. Each must exit 0 without a traceback. Skipped, each for a stated
reason (:data:`SKIPS`): runs that need a Dask cluster, and full-size ``reproduce`` runs (minutes to
hours; ``make demo`` runs every study at quick size and tests/cli/test_reproduce_cli.py covers the
command). RAM transmission-loss fields are shared with other runs through the usual cache
(``$SONARTRACK_CACHE_DIR``, else the repository's ``.sonartrack-cache``).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PREFIXES = ("sonartrack ", ".venv/bin/sonartrack ")
#: (pattern, reason): a README command matching the pattern is not run here, for that reason
SKIPS = [
    (re.compile(r"--scheduler\b"), "needs a running Dask cluster (dask scheduler / dask worker)"),
    (re.compile(r"\breproduce\b(?!.*--quick)"),
     "a full-size study run takes minutes to hours: make demo runs every study at quick size, "
     "tests/cli/test_reproduce_cli.py the command"),
]


def readme_commands() -> list[str]:
    """The README's command lines, in order, without their trailing comments."""
    lines = []
    for block in re.findall(r"```sh\n(.*?)```", README.read_text(), re.DOTALL):
        for line in block.splitlines():
            line = line.strip()
            if line.startswith(PREFIXES):
                lines.append(re.split(r"\s+#", line, maxsplit=1)[0].strip())
    return lines


def skip_reason(command: str) -> str | None:
    return next((reason for pattern, reason in SKIPS if pattern.search(command)), None)


def test_readme_starts_with_simulate_and_skips_little():
    commands = readme_commands()
    runnable = [c for c in commands if skip_reason(c) is None]
    assert runnable[0].startswith("sonartrack simulate")
    assert len(runnable) >= 15
    assert all(skip_reason(c) and "reproduce" in c for c in commands if c not in runnable)


def _environment(tmp_path: Path) -> dict:
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env.setdefault("SONARTRACK_CACHE_DIR", str(ROOT / ".sonartrack-cache"))
    env["MPLBACKEND"] = "Agg"
    return env


def test_every_readme_command_runs_as_written(tmp_path):
    env = _environment(tmp_path)
    failures = []
    for command in readme_commands():
        if skip_reason(command) is not None:
            continue
        if command.startswith(".venv/bin/"):
            command = str(Path(sys.executable).parent / command.removeprefix(".venv/bin/"))
        done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=300)
        if done.returncode != 0 or "Traceback" in done.stderr:
            failures.append(f"$ {command}\n(exit {done.returncode}) {done.stderr.strip()[-2000:]}")
    assert not failures, "README commands that do not run as written:\n\n" + "\n\n".join(failures)
