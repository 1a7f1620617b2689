"""The ``sonartrack`` command line (typer + rich).

Each sub-command lives in its own module in this package: ``cli/NAME.py`` defines ``NAME_cmd``, registered
here as the command ``NAME`` (or exposes ``register(app)`` to register its commands itself); the modules are
discovered here, so adding a command means adding a file. A command line imports only
the module named like its command (``sonartrack studies`` imports ``cli/studies.py``, not the
settings of every other command), and all of them for ``--help`` or a name no module has; a module
may register more commands than its own, found that way. Heavy imports stay inside the command
functions so that the start is quick (tests/cli/test_startup.py, benchmarks/bench_cli_start.py).

User mistakes raise :class:`sonartrack.InputError`; :func:`main` prints its one-line message
(``error: ...``) and exits with status 2, with no traceback; usage errors print the usage and exit
with status 2 too. Any other exception is a bug and is shown in full.
"""

from __future__ import annotations

import contextlib
import importlib
import pkgutil
import signal
import sys
import threading

import typer

from sonartrack._launch import EARLY_INTERRUPTED
from sonartrack.core.errors import InputError

#: how the app is made (also the listing app of :func:`_listing_app`, which must print the same help)
_APP_OPTIONS = dict(
    name="sonartrack",
    help="Underwater target detection, tracking and TMA: reproduce the papers, or run on your own data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app = typer.Typer(**_APP_OPTIONS)


def _root() -> None:
    # a callback keeps the app a group of commands when one module registered one command: typer would
    # otherwise run that lone command directly and read its name as an argument
    pass


app.callback()(_root)


#: the app that :func:`load_commands` fills (tests may swap :data:`app` for a stand-in)
_APP = app
_LOADED: set[str] = set()


def command_modules() -> list[str]:
    """Names of the command modules of this package (every module whose name does not start with ``_``)."""
    return sorted(info.name for info in pkgutil.iter_modules(__path__) if not info.name.startswith("_"))


def load_commands(names: list[str] | None = None) -> typer.Typer:
    """Import the command modules ``names`` (None: all) and register their commands on the app, once each.

    Parameters
    ----------
    names : list of str, optional
        Module names from :func:`command_modules`.

    Returns
    -------
    typer.Typer
        The app, its commands in module order whatever order they were loaded in.
    """
    order = {name: i for i, name in enumerate(command_modules())}
    for name in order if names is None else names:
        if name not in _LOADED:
            mod = importlib.import_module(f"{__name__}.{name}")
            _LOADED.add(name)
            if hasattr(mod, "register"):
                mod.register(_APP)
            elif hasattr(mod, f"{name}_cmd"):  # the convention: cli/NAME.py defines NAME_cmd, the command NAME
                _APP.command(name.replace("_", "-"))(getattr(mod, f"{name}_cmd"))
    _APP.registered_commands.sort(key=lambda c: order.get(c.callback.__module__.rpartition(".")[2], len(order)))
    return _APP


def _modules_for(args: list[str]) -> list[str] | None:
    """The command modules a command line needs: the one named like its command, or None (all) for help, no
    command, or a command that no module is named after."""
    command = next((a for a in args if not a.startswith("-")), None)
    module = command.replace("-", "_") if command else None
    if module is None or module not in command_modules():
        return None
    load_commands([module])
    return [module] if command in {c.name for c in _APP.registered_commands} else None


def _command_docs() -> list[tuple[str, str]] | None:
    """(name, docstring) of every command, in module order, read from the command modules' source.

    Reading instead of importing keeps the settings trees that a command module imports for its options out
    of ``sonartrack --help``. Only the forms the modules use are read: a module ``NAME`` without ``register``
    defining ``NAME_cmd`` (the convention), or ``register`` made of statements ``app.command("name")(function)``
    with ``function`` defined in the same module; anything else (or a module without its source) returns None,
    and the caller imports the modules instead.
    """
    import ast
    from pathlib import Path

    docs = []
    for module in command_modules():
        path = Path(__path__[0]) / f"{module}.py"
        if not path.is_file():
            return None
        tree = ast.parse(path.read_text(encoding="utf-8"))
        functions = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
        if "register" not in functions and f"{module}_cmd" in functions:
            docs.append((module.replace("_", "-"), ast.get_docstring(functions[f"{module}_cmd"]) or ""))
            continue
        for stmt in getattr(functions.get("register"), "body", []):
            call = stmt.value if isinstance(stmt, ast.Expr) else None
            maker = call.func if isinstance(call, ast.Call) else None
            if not (isinstance(maker, ast.Call) and isinstance(maker.func, ast.Attribute)
                    and maker.func.attr == "command" and not maker.keywords and len(maker.args) == 1
                    and isinstance(maker.args[0], ast.Constant) and isinstance(maker.args[0].value, str)
                    and len(call.args) == 1 and not call.keywords and isinstance(call.args[0], ast.Name)
                    and call.args[0].id in functions):
                return None
            docs.append((maker.args[0].value, ast.get_docstring(functions[call.args[0].id]) or ""))
    return docs


def _listing_app(args: list[str]) -> typer.Typer | None:
    """For a command line naming no command (``--help``, or nothing): an app like :data:`app` whose commands
    have their names and help but no options, enough to print the list; None otherwise, or when the help
    cannot be read from the source (:func:`_command_docs`) or the commands are loaded already."""
    if any(not a.startswith("-") for a in args) or set(command_modules()) <= _LOADED:
        return None
    docs = _command_docs()
    if docs is None:
        return None
    listing = typer.Typer(**_APP_OPTIONS)
    listing.callback()(_root)
    for name, doc in docs:
        listing.command(name, help=doc)(_root)
    return listing


#: what an interrupted command prints when it has no account of its own (status 130 for SIGINT, 143 for SIGTERM);
#: a command that keeps partial work (reproduce's trials, survey's recordings) says what it kept in its own words
INTERRUPTED = EARLY_INTERRUPTED  # (sonartrack/_launch.py: the same line before this module is imported)

#: the signal that stopped the running command, once one has arrived (None before): an exception raised after it,
#: whatever its type, is that interrupt's doing (a signal handler's exception raised inside compiled code, numba's
#: for one, comes out as a SystemError that need not chain the KeyboardInterrupt)
_SIGNAL_RECEIVED: int | None = None


class Interrupted(KeyboardInterrupt):
    """SIGINT (Ctrl-C) or SIGTERM, raised in the main thread; a command may re-raise it with its own
    one-line ``message`` (e.g. how many trials were kept). :func:`main` prints the message and returns
    128 + the signal number, the shell's convention for a process ended by that signal."""

    def __init__(self, signum: int = signal.SIGINT, message: str | None = None):
        super().__init__(message or "")
        self.signum = int(signum)
        self.message = message


def _raise_interrupted(signum, frame) -> None:
    """Signal handler: stop the command once; further SIGINT/SIGTERM are ignored so that the clean-up
    (stopping workers, counting what was kept) is not itself interrupted into a traceback."""
    global _SIGNAL_RECEIVED
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    _SIGNAL_RECEIVED = int(signum)
    raise Interrupted(signum)


def _interrupt_again_if_swallowed(unraisable) -> None:
    """``sys.unraisablehook`` while a command runs: an :class:`Interrupted` raised inside a finaliser (``__del__``,
    a weakref callback: Python cannot propagate it and would print its traceback and go on, the signal lost
    and the next ones ignored) is raised again in the main flow: the handler is put back and the signal sent
    once more from another thread a moment later, so that it arrives after the finaliser (sent from here, its
    handler would run inside this hook, which cannot propagate it either). Anything else goes to the default
    hook."""
    if isinstance(unraisable.exc_value, Interrupted):
        import os
        import time

        signum = unraisable.exc_value.signum
        signal.signal(signum, _raise_interrupted)
        threading.Thread(target=lambda: (time.sleep(0.01), os.kill(os.getpid(), signum)), daemon=True).start()
        return
    sys.__unraisablehook__(unraisable)


@contextlib.contextmanager
def _stop_signals_raise():
    """SIGINT and SIGTERM raise :class:`Interrupted` while the app runs, then the old handlers return.

    A signal ignored on entry stays ignored (a job started in the background by a non-interactive
    shell ignores SIGINT on purpose). Signal handlers can only be set from the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    global _SIGNAL_RECEIVED
    _SIGNAL_RECEIVED = None
    old = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    for sig, handler in old.items():
        if handler is not signal.SIG_IGN:
            signal.signal(sig, _raise_interrupted)
    old_hook, sys.unraisablehook = sys.unraisablehook, _interrupt_again_if_swallowed
    try:
        yield
    finally:
        sys.unraisablehook = old_hook
        for sig, handler in old.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)


def interrupt_of(exc: BaseException | None) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt behind ``exc`` (typer turns one into ``Exit(130)``), if any; once a signal was
    received (:data:`_SIGNAL_RECEIVED`), an :class:`Interrupted` of it whatever ``exc`` is (a command that words its own
    interrupt catches BaseException and asks this)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return Interrupted(_SIGNAL_RECEIVED) if _SIGNAL_RECEIVED is not None else None


def _report_interrupt(exc: BaseException | None) -> int:
    """Print the interrupted command's one line; the status is 128 + the signal number (130 for SIGINT)."""
    intr = interrupt_of(exc)
    typer.echo(getattr(intr, "message", None) or INTERRUPTED, err=True)
    return 128 + getattr(intr, "signum", _SIGNAL_RECEIVED or signal.SIGINT)


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
    command is an :class:`InputError`: its one-line message (``error: ...``), status 2. Ctrl-C (SIGINT)
    and SIGTERM raise :class:`Interrupted` in the command; it ends with one line, the command's own
    account or the generic note on resuming, and status 130 (SIGINT) or 143 (SIGTERM). A file-system
    refusal (an output folder that cannot be made, a file that cannot be written) is named in one line,
    status 2. Any other exception is a bug in sonartrack:
    one line naming it and status 1, or, with ``--debug`` anywhere on the command line, the traceback.
    """
    global _SIGNAL_RECEIVED
    _SIGNAL_RECEIVED = None  # (a test may call main again in the same process)
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    args = [a for a in args if a != "--debug"]
    try:
        run = app
        if app is _APP:
            run = _listing_app(args) or app
            if run is app:
                load_commands(_modules_for(args))
        with _stop_signals_raise():
            run(args=args, prog_name="sonartrack", standalone_mode=True)
    except InputError as exc:
        if _SIGNAL_RECEIVED is not None:
            return _report_interrupt(exc)
        typer.echo(f"error: {exc}", err=True)
        return 2
    except OSError as exc:
        if _SIGNAL_RECEIVED is not None and not debug:  # a write cut short by the interrupt
            return _report_interrupt(exc)
        if debug:
            raise
        where = f": {exc.filename}" if exc.filename else ""
        typer.echo(f"error: {exc.strerror or exc}{where} (check the path and its permissions)", err=True)
        return 2
    except KeyboardInterrupt as exc:
        return _report_interrupt(exc)
    except SystemExit as exc:
        status = _exit_status(exc.code)
        return _report_interrupt(exc) if status == 130 else status
    except Exception as exc:  # a bug: say so in one line unless asked for the traceback
        if _SIGNAL_RECEIVED is not None and not debug:  # the interrupt, surfacing as another exception type
            return _report_interrupt(exc)
        if debug:
            raise
        typer.echo(f"error: internal error ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}) "
                   "- a bug in sonartrack, not in your input as far as it checked; rerun with --debug for the "
                   "traceback and report it", err=True)
        return 1
    return 0


def _entry() -> None:  # pragma: no cover
    status = main()
    # the command is over (its outputs written or removed): a signal during the interpreter's shutdown must not
    # turn a finished run into one killed by that signal
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    sys.exit(status)
