"""Every command the README shows runs as written (a copied command that fails is worse than none).

The commands are the lines of the README's ```sh blocks that start with ``sonartrack `` (or
``.venv/bin/sonartrack ``), trailing ``# comments`` stripped, run through bash (so ``> file`` redirections
work) with the installed console script first on PATH. The first one is ``sonartrack simulate``, which
writes every input the others read. Each must exit 0 without a traceback. Skipped, each for a stated
reason (:data:`SKIPS`): runs that need a Dask cluster, and full-size ``reproduce`` runs (minutes to
hours; ``make demo`` runs every study at quick size and tests/cli/test_reproduce_cli.py covers the
command). RAM transmission-loss fields are shared with other runs through the usual cache
(``$SONARTRACK_CACHE_DIR``, else the repository's ``.sonartrack-cache``).

One test per command, so that the test workers share them. ``simulate`` runs once per worker (a
session fixture); every other command runs in a folder of its own holding the simulated files and the
outputs of the earlier README commands that write a file it names (``--print-config > tracker.toml``
before ``--config tracker.toml``), each of those run once per worker in its own folder (after its own
such commands) and copied in: each command is checked as the README's reader would run it after the
ones above it, and no test depends on which tests another worker ran.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PREFIXES = ("sonartrack ", ".venv/bin/sonartrack ")
#: (pattern, reason): a README command matching the pattern is not run here, for that reason
SKIPS = [
    (re.compile(r"--scheduler\b"), "needs a running Dask cluster (dask scheduler / dask worker)"),
    (re.compile(r"\breproduce\b(?!.*--quick)"),
     "a full-size study run takes minutes to hours: make demo runs every study at quick size, "
     "tests/cli/test_reproduce_cli.py the command"),
    (re.compile(r"--stream\b|\blive --tcp\b"),
     "the recorder and the console run together, in two processes: tests/test_readme_live.py runs the pair"),
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


def runnable_commands() -> list[str]:
    """The README commands this module runs, in README order (the first is ``simulate``)."""
    return [c for c in readme_commands() if skip_reason(c) is None]


def written_paths(command: str) -> list[str]:
    """What a command writes that a later one can name: its ``> file`` and its ``--out`` folder."""
    return re.findall(r">\s*(\S+)", command) + re.findall(r"--out[ =](\S+)", command)


def _named_paths(command: str) -> list[str]:
    """The words of a command that may name an input file: paths (with a "." or a "/") after the program and its
    subcommand, options and their output folders left out (``--only passive`` names no file)."""
    words = shlex.split(command.split(">")[0])
    return [w for i, w in enumerate(words) if i >= 2 and not w.startswith("-") and words[i - 1] != "--out"
            and ("/" in w or "." in w)]


def _writes_to(written: str, named: str) -> bool:
    folder = written.rstrip("/")
    return named in (written, folder) or named.startswith(folder + "/")


def prerequisites(commands: list[str], i: int) -> list[int]:
    """Indices of the earlier commands (after the first, ``simulate``) whose outputs command ``i`` names,
    and theirs, in README order: for each named path, the latest earlier command that writes it."""
    need: set[int] = set()
    todo = [i]
    while todo:
        k = todo.pop()
        for named in _named_paths(commands[k]):
            writers = [j for j in range(1, k) if any(_writes_to(w, named) for w in written_paths(commands[j]))]
            if writers and writers[-1] not in need:
                need.add(writers[-1])
                todo.append(writers[-1])
    return sorted(need)


def _environment() -> dict:
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env.setdefault("SONARTRACK_CACHE_DIR", str(ROOT / ".sonartrack-cache"))
    env["MPLBACKEND"] = "Agg"
    return env


def run_command(command: str, folder: Path) -> str | None:
    """Run one README command in ``folder``; None if it ran as written, else what went wrong."""
    if command.startswith(".venv/bin/"):
        command = str(Path(sys.executable).parent / command.removeprefix(".venv/bin/"))
    done = subprocess.run(["bash", "-c", command], cwd=folder, env=_environment(), capture_output=True, text=True,
                          timeout=300)
    if done.returncode != 0 or "Traceback" in done.stderr:
        return f"$ {command}\n(exit {done.returncode}) {done.stderr.strip()[-2000:]}"
    return None


@pytest.fixture(scope="session")
def simulated(tmp_path_factory) -> tuple[Path, str | None]:
    """The folder where the README's first command (``simulate``) ran, once per test worker, and its failure."""
    folder = tmp_path_factory.mktemp("readme-simulate")
    return folder, run_command(runnable_commands()[0], folder)


def _seeded_folder(simulated_folder: Path, folder: Path) -> Path:
    """``folder`` holding the simulated files (hard links where the file system allows: nothing is copied)."""
    try:
        shutil.copytree(simulated_folder, folder, copy_function=os.link, dirs_exist_ok=True)
    except OSError:
        shutil.copytree(simulated_folder, folder, dirs_exist_ok=True)
    return folder


def _bring_outputs(commands: list[str], i: int, folder: Path, ran) -> str | None:
    """Copy into ``folder`` what the prerequisites of command ``i`` wrote, each from the folder where it ran
    (``ran(j) -> (folder, failure)``), in README order (a later writer of the same path wins); the first
    failure of one of them, else None."""
    for j in prerequisites(commands, i):
        source, failure = ran(j)
        if failure is not None:
            return failure
        for written in written_paths(commands[j]):
            src, dst = source / written.rstrip("/"), folder / written.rstrip("/")
            if dst.is_dir():
                shutil.rmtree(dst)
            elif dst.exists():
                dst.unlink()
            if src.is_dir():
                shutil.copytree(src, dst)
            elif src.exists():
                shutil.copy2(src, dst)
    return None


@pytest.fixture(scope="session")
def ran_once(simulated, tmp_path_factory):
    """``ran_once(j) -> (folder, failure)``: README command ``j`` run in a folder of its own after its
    prerequisites, once per test worker (commands that others need run once, not once per dependant)."""
    commands, done = runnable_commands(), {}

    def ran(j: int) -> tuple[Path, str | None]:
        if j not in done:
            folder = _seeded_folder(simulated[0], tmp_path_factory.mktemp(f"readme-{j:02d}"))
            failure = _bring_outputs(commands, j, folder, ran)
            done[j] = folder, failure if failure is not None else run_command(commands[j], folder)
        return done[j]

    return ran


def test_readme_starts_with_simulate_and_skips_little():
    commands = readme_commands()
    runnable = runnable_commands()
    assert runnable[0].startswith("sonartrack simulate")
    assert len(runnable) >= 15
    # skipped: full-size reproduce runs, and the live pair that tests/test_readme_live.py runs together
    assert all(skip_reason(c) and ("reproduce" in c or "--stream" in c or c.startswith("sonartrack live --tcp"))
               for c in commands if c not in runnable)


def test_prerequisites_are_the_earlier_writers_of_named_files():
    commands = ["sonartrack simulate --out .", "sonartrack a --print-config > a.toml", "sonartrack b --out peaks/",
                "sonartrack a --config a.toml", "sonartrack c --peaks peaks/p.csv --out peaks/",
                "sonartrack peaks --peaks peaks/p.csv", "sonartrack e --only peaks --out e/"]
    assert prerequisites(commands, 1) == []
    assert prerequisites(commands, 3) == [1]
    assert prerequisites(commands, 4) == [2]  # its own --out is no input
    assert prerequisites(commands, 5) == [2, 4]  # the latest writer and what it needs; not the subcommand
    assert prerequisites(commands, 6) == []  # an option's value that is no path


def test_outputs_of_prerequisites_are_copied_in_order_and_their_failures_passed_on(tmp_path):
    commands = ["sonartrack simulate --out .", "sonartrack b --out peaks/",
                "sonartrack c --peaks peaks/p.csv --out peaks/", "sonartrack d --peaks peaks/p.csv"]
    ran = {}
    for j, text in ((1, "from b"), (2, "from c")):
        (tmp_path / f"ran{j}" / "peaks").mkdir(parents=True)
        (tmp_path / f"ran{j}" / "peaks" / "p.csv").write_text(text)
        ran[j] = tmp_path / f"ran{j}"
    work = tmp_path / "work"
    work.mkdir()
    assert _bring_outputs(commands, 3, work, lambda j: (ran[j], None)) is None
    assert (work / "peaks" / "p.csv").read_text() == "from c"  # the latest writer's
    assert _bring_outputs(commands, 3, work, lambda j: (ran[j], "b failed" if j == 1 else None)) == "b failed"


@pytest.mark.parametrize("index", range(len(runnable_commands())),
                         ids=[f"{i:02d}-{c.split(' ', 1)[1][:60]}" for i, c in enumerate(runnable_commands())])
def test_readme_command_runs_as_written(index, simulated, ran_once, tmp_path):
    simulated_folder, simulate_failure = simulated
    commands = runnable_commands()
    if index == 0:
        assert simulate_failure is None, f"README command does not run as written:\n\n{simulate_failure}"
        return
    if simulate_failure is not None:
        pytest.fail(f"the README's first command, which writes this one's inputs, failed:\n\n{simulate_failure}")
    if any(index in prerequisites(commands, i) for i in range(index + 1, len(commands))):
        failure = ran_once(index)[1]  # others need its outputs: run where they will find them
    else:
        folder = _seeded_folder(simulated_folder, tmp_path / "work")
        failure = _bring_outputs(commands, index, folder, ran_once)
        assert failure is None, f"an earlier README command this one needs does not run as written:\n\n{failure}"
        failure = run_command(commands[index], folder)
    assert failure is None, f"README command does not run as written:\n\n{failure}"
