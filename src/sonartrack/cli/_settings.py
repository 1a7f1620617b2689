"""Command-line faces of the settings declarations (``core/settings.py``).

A command's settings come, in this order, from the declaration's defaults, the ``--config`` TOML
file, then the command-line options the user gave. Options take their help text (doc and unit) from
the same declaration, so the three faces cannot drift apart. ``--print-config`` prints the resolved
settings as commented TOML (which ``--config`` reads back) and exits.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import typer

from sonartrack.core.settings import field_help, to_commented_toml

PRINT_CONFIG_HELP = ("Print the resolved settings (defaults, then the settings file: --config, or --scene for "
                     "simulate; then options) as TOML and exit.")


def settings_help(default_model) -> Callable[..., str]:
    """A command's ``_help(name, model=default_model)``: the help text of the option that sets field ``name`` of
    ``model`` (:func:`option_help`), the command's settings class unless another is named."""

    def _help(name: str, model=default_model) -> str:
        return option_help(model, name)

    return _help


def option_help(model_cls, name: str, extra: str = "") -> str:
    """Help text of an option that sets field ``name`` of ``model_cls`` (its doc and unit)."""
    return field_help(model_cls, name) + (f" {extra}" if extra else "")


def _defaults(model_cls) -> dict:
    """The declaration's defaults as plain data ({} when a field has no default)."""
    from pydantic import ValidationError

    try:
        return model_cls().model_dump(mode="json")
    except ValidationError:
        return {}


def merged(base: dict, over: dict) -> dict:
    """``over`` laid onto ``base``: tables merge key by key (a partial ``[tracker]`` keeps the command's other
    tracker defaults, which may differ from the class's own), everything else (values, lists) is replaced."""
    out = dict(base)
    for key, value in over.items():
        out[key] = merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def resolve(model_cls, config: Path | None, *, source: str | None = None, **options):
    """Settings from defaults <- TOML file ``config`` <- non-None ``options``.

    ``options`` keys are field names; nested fields are given as ``"group__field"``."""
    from sonartrack.io import toml as toml_io

    data = merged(_defaults(model_cls), toml_io.load(config) if config is not None else {})
    for key, value in options.items():
        if value is None:
            continue
        node = data
        *parents, leaf = key.split("__")
        for p in parents:
            node = node.setdefault(p, {})
        node[leaf] = value
    where = source or (f"config {config}" if config is not None else "settings")
    given = frozenset(key.replace("__", ".") for key, value in options.items() if value is not None)
    return toml_io.validate(model_cls, data, source=where, given=given)


def print_config_and_exit(settings) -> None:
    """Echo ``settings`` as commented TOML and end the command (exit 0)."""
    typer.echo(to_commented_toml(settings), nl=False)
    raise typer.Exit(0)


@contextmanager
def output_folder(out: Path) -> Iterator[Path]:
    """Make the ``--out`` folder before the work, so that a folder that cannot be made fails at once in one line
    (not after minutes of computing); if the work then fails or is interrupted, remove what this run added to it
    (io/run_outputs.py :func:`~sonartrack.io.run_outputs.discard_on_failure`, and the folder when this run made
    it), so that a run's outputs are all or nothing. An ``Exit`` of status 0 is a success, not a failure."""
    from sonartrack.io.run_outputs import discard_on_failure

    success_exit = None
    with discard_on_failure(out) as folder:
        try:
            yield folder
        except BaseException as exc:
            if getattr(exc, "exit_code", getattr(exc, "code", 1)) not in (0, None):
                raise
            success_exit = exc  # typer.Exit(0) / SystemExit(0) ends a successful run: keep its outputs
    if success_exit is not None:
        raise success_exit
