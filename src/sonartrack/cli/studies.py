"""``sonartrack studies``: list the papers' experiments that ``sonartrack reproduce`` runs.

A module of its own so that listing the studies imports the studies and nothing of the other commands
(cli/__init__.py loads only the module named like the command).
"""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    app.command("studies")(studies_cmd)


def studies_cmd() -> None:
    """List the studies (one per source paper) that `reproduce` can run."""
    from sonartrack import studies

    for sid in studies.available():
        mod = studies.load(sid)
        typer.echo(f"{sid:20s} {mod.TITLE}  [{mod.PAPER}]  full: {mod.Config().runs} runs, "
                   f"quick: {mod.Config.quick().runs}")
