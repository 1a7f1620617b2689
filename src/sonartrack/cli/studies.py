"""``sonartrack studies``: list the papers' experiments that ``sonartrack reproduce`` runs.

A module of its own so that listing the studies imports nothing of the other commands (cli/__init__.py
loads only the module named like the command); the listing itself is read from the study modules' source
(:func:`sonartrack.studies.listing`), so no study module and none of its libraries is imported either.
"""

from __future__ import annotations

import typer


def studies_cmd() -> None:
    """List the studies (one per source paper) that `reproduce` can run."""
    from sonartrack import studies

    for sid, title, paper, runs, quick_runs in studies.listing():
        typer.echo(f"{sid:20s} {title}  [{paper}]  full: {runs} runs, quick: {quick_runs}")
