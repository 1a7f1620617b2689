"""The ``sonartrack`` command line (typer + rich).

Each sub-command lives in its own module in this package and exposes ``register(app)``; the
modules are discovered here, so adding a command means adding a file. Heavy imports stay inside
the command functions so that ``sonartrack --help`` is quick.

User mistakes raise :class:`sonartrack.InputError`; :func:`main` prints its one-line message
(``error: ...``) and exits with status 2, with no traceback; usage errors print the usage and exit
with status 2 too. Any other exception is a bug and is shown in full.
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


#: what an interrupted run prints (exit status 130, as for SIGINT)
INTERRUPTED = "interrupted: finished trials are saved; rerun the same command to resume"


def _exit_status(code) -> int:
    """``SystemExit.code`` as a process status: None is 0, an int itself, anything else (a message) 1."""
    if code is None:
        return 0
    return code if isinstance(code, int) else 1


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the app and return its exit status, with no traceback for a user's mistake.

    typer runs in its standalone mode, which handles its own (bundled click) usage errors whatever
    click it ships: usage text and status 2 for a missing argument, an unknown option or command, and
    no arguments at all; help and ``--print-config`` end with status 0. A user mistake inside a
    command is an :class:`InputError`: its one-line message (``error: ...``), status 2. Ctrl-C is
    status 130 with a note on resuming. A file-system refusal (an output folder that cannot be made, a
    file that cannot be written) is named in one line, status 2. Any other exception is a bug in sonartrack:
    one line naming it and status 1, or, with ``--debug`` anywhere on the command line, the traceback.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    args = [a for a in args if a != "--debug"]
    try:
        app(args=args, prog_name="sonartrack", standalone_mode=True)
    except InputError as exc:
        typer.echo(f"error: {exc}", err=True)
        return 2
    except OSError as exc:
        if debug:
            raise
        where = f": {exc.filename}" if exc.filename else ""
        typer.echo(f"error: {exc.strerror or exc}{where} (check the path and its permissions)", err=True)
        return 2
    except KeyboardInterrupt:
        typer.echo(INTERRUPTED, err=True)
        return 130
    except SystemExit as exc:
        status = _exit_status(exc.code)
        if status == 130:
            typer.echo(INTERRUPTED, err=True)
        return status
    except Exception as exc:  # a bug: say so in one line unless asked for the traceback
        if debug:
            raise
        typer.echo(f"error: internal error ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}) "
                   "- a bug in sonartrack, not in your input as far as it checked; rerun with --debug for the "
                   "traceback and report it", err=True)
        return 1
    return 0


def _entry() -> None:  # pragma: no cover
    sys.exit(main())
