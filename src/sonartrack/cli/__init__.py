"""The ``sonartrack`` command line (typer + rich).

Each sub-command lives in its own module in this package and exposes ``register(app)``; the
modules are discovered here, so adding a command means adding a file. Heavy imports stay inside
the command functions so that ``sonartrack --help`` is quick.

User mistakes raise :class:`sonartrack.InputError`; :func:`main` prints its one-line message
(``error: ...``) and exits with status 2, with no traceback. Any other exception is a bug and is
shown in full.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import typer

from sonartrack.core.errors import InputError

app = typer.Typer(
    name="sonartrack",
    help="Underwater target detection, tracking and TMA: reproduce the papers, or run on your own data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _register_commands() -> None:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        if hasattr(mod, "register"):
            mod.register(app)


_register_commands()


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the app, turning :class:`InputError` into a one-line message and exit 2."""
    try:
        app(args=argv, prog_name="sonartrack", standalone_mode=False)
    except InputError as exc:
        typer.echo(f"error: {exc}", err=True)
        return 2
    except KeyboardInterrupt:
        typer.echo("interrupted: finished trials are saved; rerun the same command to resume", err=True)
        return 130
    except SystemExit as exc:  # typer's own exits (--help, usage errors)
        return int(exc.code or 0)
    except Exception as exc:  # click usage errors arrive as ClickException in non-standalone mode
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show()
            return exc.exit_code
        if isinstance(exc, click.exceptions.Abort):
            return 1
        raise
    return 0


def _entry() -> None:  # pragma: no cover
    sys.exit(main())
