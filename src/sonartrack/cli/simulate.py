"""``sonartrack simulate``: a passive towed-array scene (recording, navigation, truth) and a sample input for
every other command, written into ``--out`` (io/scene_files.py lists the files).

The scene's settings are :class:`sonartrack.sim.scene.PassiveSceneSettings`: defaults, then the
``--scene`` TOML file (or a shipped scene's name), then the options; ``--print-config`` prints them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import (
    PRINT_CONFIG_HELP,
    option_help,
    output_folder,
    print_config_and_exit,
    resolve,
)
from sonartrack.sim.scene import PassiveSceneSettings


def register(app: typer.Typer) -> None:
    app.command("simulate")(simulate_cmd)


def _help(name: str) -> str:
    return option_help(PassiveSceneSettings, name)


def simulate_cmd(
    scene: Annotated[Path | None, typer.Option(help="Scene TOML file (see --print-config), or a shipped scene's "
                                                    "name (passive).")] = None,
    duration_s: Annotated[float | None, typer.Option(help=_help("duration_s"))] = None,
    seed: Annotated[int | None, typer.Option(help=_help("seed"))] = None,
    propagation: Annotated[str | None, typer.Option(help=_help("propagation"))] = None,
    only: Annotated[str, typer.Option(help="all; passive (recording, nav, truth); samples (the other commands' "
                                           "inputs).")] = "all",
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("scene"),
) -> None:
    """Simulate a passive sonar scene: N-channel WAV, navigation, truth, and sample inputs for every command."""
    from sonartrack.io.scene_files import check_only, shipped_scene_path, write_scene

    path = shipped_scene_path(scene) if scene is not None else None
    settings = resolve(PassiveSceneSettings, path, duration_s=duration_s, seed=seed, propagation=propagation)
    if print_config:
        print_config_and_exit(settings)
    check_only(only)
    from sonartrack.cli._progress import TrialProgress, make_progress

    with output_folder(out), make_progress() as bar:  # the folder before the progress bar: a bad --out is one line
        files = write_scene(settings, out, only=only, progress=TrialProgress(bar))
    typer.echo(f"simulate: {files.summary}; wrote {len(files.paths)} files in {out}")
