"""Command-line faces of the settings declarations (``core/settings.py``).

A command's settings come, in this order, from the declaration's defaults, the ``--config`` TOML
file, then the command-line options the user gave. Options take their help text (doc and unit) from
the same declaration, so the three faces cannot drift apart. ``--print-config`` prints the resolved
settings as commented TOML (which ``--config`` reads back) and exits.
"""

from __future__ import annotations

from pathlib import Path

import typer

from sonartrack.core.settings import field_help, to_commented_toml

PRINT_CONFIG_HELP = "Print the resolved settings (defaults, then --config, then options) as TOML and exit."


def option_help(model_cls, name: str, extra: str = "") -> str:
    """Help text of an option that sets field ``name`` of ``model_cls`` (its doc and unit)."""
    return field_help(model_cls, name) + (f" {extra}" if extra else "")


def resolve(model_cls, config: Path | None, *, source: str | None = None, **options):
    """Settings from defaults <- TOML file ``config`` <- non-None ``options``.

    ``options`` keys are field names; nested fields are given as ``"group__field"``."""
    from sonartrack.io import toml as toml_io

    data = toml_io.load(config) if config is not None else {}
    for key, value in options.items():
        if value is None:
            continue
        node = data
        *parents, leaf = key.split("__")
        for p in parents:
            node = node.setdefault(p, {})
        node[leaf] = value
    where = source or (f"config {config}" if config is not None else "settings")
    return toml_io.validate(model_cls, data, source=where)


def print_config_and_exit(settings) -> None:
    """Echo ``settings`` as commented TOML and end the command (exit 0)."""
    typer.echo(to_commented_toml(settings), nl=False)
    raise typer.Exit(0)
