"""The ``sonartrack`` entry point: usage errors, user mistakes, interrupts and bugs end the way they should.

typer ships its own copy of click, so the entry point must not depend on which click's exception
classes arrive: these tests go through :func:`sonartrack.cli.main` exactly as the console script does.
"""

import subprocess
import sys

import pytest
import typer

import sonartrack.cli as cli
from sonartrack.cli import main
from sonartrack.core.errors import InputError


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("args, needle", [
    ([], "Commands"),                                   # no arguments at all: the usage and the commands
    (["reproduce"], "Missing argument 'study'"),        # a missing required argument
    (["tl", "--bogus"], "No such option: --bogus"),     # an unknown option
    (["no-such-command"], "No such command"),           # an unknown command
    (["tl", "--freq", "abc"], "Invalid value for '--freq'"),  # a value of the wrong type
])
def test_usage_errors_print_usage_and_exit_2(capsys, monkeypatch, args, needle):
    monkeypatch.setenv("COLUMNS", "200")  # rich wraps its error panel at the terminal width
    code, out, err = run(capsys, *args)
    assert code == 2
    assert needle in out + err and "Usage: sonartrack" in out + err
    assert "Traceback" not in out + err


def test_an_option_without_its_value_is_a_usage_error(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    code, out, err = run(capsys, "bearings", "--spacing")
    assert code == 2 and "Option '--spacing' requires an argument" in err and "Traceback" not in err


def test_help_and_print_config_exit_0(capsys):
    assert run(capsys, "--help")[0] == 0
    assert run(capsys, "tl", "--help")[0] == 0
    assert run(capsys, "tl", "--print-config")[0] == 0


@pytest.fixture
def toy_app(monkeypatch):
    """A stand-in app whose commands fail in each way the entry point must handle."""
    app = typer.Typer(add_completion=False, pretty_exceptions_enable=False)

    @app.command("mistake")
    def mistake():
        raise InputError("the spacing is negative: give it in metres, positive")

    @app.command("interrupt")
    def interrupt():
        raise KeyboardInterrupt

    @app.command("signal-in-compiled-code")
    def signal_in_compiled_code():
        # a signal whose handler raised inside compiled code (numba's dispatcher): the interrupt comes back as a
        # SystemError that does not chain the KeyboardInterrupt
        import os
        import signal

        try:
            os.kill(os.getpid(), signal.SIGTERM)
            signal.pthread_sigmask(signal.SIG_BLOCK, [])  # a call that lets Python run the pending handler
        except KeyboardInterrupt:
            pass
        raise SystemError("CPUDispatcher(<function f>) returned a result with an exception set") from None

    @app.command("signal-in-finaliser")
    def signal_in_finaliser():
        # the signal's handler runs inside a __del__, where Python cannot propagate its exception
        import os
        import signal
        import time

        class Resource:
            def __del__(self):
                os.kill(os.getpid(), signal.SIGINT)
                for _ in range(1000):  # bytecodes, so that the pending handler runs here
                    time.monotonic()

        Resource()
        for _ in range(3000):  # the rest of the work (30 s; the interrupt ends it within ms): must not run
            time.sleep(0.01)
        typer.echo("finished")

    @app.command("bug")
    def bug():
        raise ZeroDivisionError("a bug")

    @app.command("exit3")
    def exit3():
        raise typer.Exit(3)

    monkeypatch.setattr(cli, "app", app)
    return app


def test_input_error_is_one_line_and_status_2(toy_app, capsys):
    code, out, err = run(capsys, "mistake")
    assert code == 2 and err == "error: the spacing is negative: give it in metres, positive\n" and out == ""


def test_interrupt_is_status_130_with_the_resume_note(toy_app, capsys):
    code, _, err = run(capsys, "interrupt")
    assert code == 130 and err.startswith("interrupted:") and "rerun the same command" in err
    assert "trials" not in err  # the generic line claims no trials: a command that keeps some says so itself


def test_a_signal_surfacing_as_another_exception_is_the_interrupt_not_a_bug(toy_app, capsys):
    code, out, err = run(capsys, "signal-in-compiled-code")
    assert code == 143 and err.startswith("interrupted:") and err.count("\n") == 1
    assert "internal error" not in err and "Traceback" not in err + out
    assert run(capsys, "bug")[0] == 1  # the flag is per run: a later bug is a bug again


def test_a_signal_arriving_inside_a_finaliser_still_stops_the_command(toy_app, capsys):
    code, out, err = run(capsys, "signal-in-finaliser")
    assert code == 130 and "finished" not in out
    assert err.startswith("interrupted:") and err.count("\n") == 1 and "Traceback" not in err and "ignored" not in err


def test_a_bug_is_not_hidden(toy_app, capsys):
    assert main(["bug"]) == 1 and "internal error (ZeroDivisionError" in capsys.readouterr().err
    with pytest.raises(ZeroDivisionError):
        main(["bug", "--debug"])


def test_exit_status_of_a_command_is_kept(toy_app, capsys):
    assert run(capsys, "exit3")[0] == 3


def test_console_script_no_arguments_exits_2_without_traceback():
    res = subprocess.run([sys.executable, "-m", "sonartrack.cli"], capture_output=True, text=True)
    assert res.returncode == 2 and "Usage" in res.stdout + res.stderr and "Traceback" not in res.stderr
    res = subprocess.run([sys.executable, "-m", "sonartrack.cli", "bearings", "--spacing"], capture_output=True,
                         text=True)
    assert res.returncode == 2 and "Traceback" not in res.stderr


def test_an_internal_error_is_one_line_and_debug_shows_the_traceback(monkeypatch, capsys):
    from sonartrack import cli

    def boom(*args, **kwargs):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(cli, "app", boom)
    assert cli.main(["studies"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error (ZeroDivisionError: a bug)" in err and "--debug" in err
    with pytest.raises(ZeroDivisionError):
        cli.main(["studies", "--debug"])


def test_an_output_folder_that_cannot_be_made_is_one_line(tmp_path, capsys):
    from sonartrack import cli

    blocker = tmp_path / "file"
    blocker.write_text("x")
    code = cli.main(["reproduce", "mftd", "--quick", "--runs", "1", "--out", str(blocker / "sub")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err


def test_negative_seed_is_refused(capsys):
    from sonartrack import cli

    assert cli.main(["reproduce", "mftd", "--quick", "--seed", "-1"]) == 2
    assert "--seed" in capsys.readouterr().err


def test_help_lists_every_command_in_module_order_whatever_was_loaded_first(capsys, monkeypatch):
    """A command line loads only its command's module (cli/__init__.py); help still lists all of them, in order."""
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["studies"]) == 0
    capsys.readouterr()
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    names = [c.name for c in cli.load_commands().registered_commands]
    assert names.index("reproduce") < names.index("studies") < names.index("tl")  # module order
    positions = [out.index(f"\u2502 {name} ") for name in names]  # the first column of rich's command table
    assert positions == sorted(positions)


def test_a_run_that_fails_after_its_first_output_leaves_nothing(tmp_path, monkeypatch, capsys):
    """detect writes its table, then its picture: an interrupt in between removes the table (all or nothing),
    while files that were in the folder before the run stay."""
    import numpy as np

    import sonartrack.report.figures.detection as figures

    frames = tmp_path / "frames.npy"
    np.save(frames, np.random.default_rng(1).normal(size=(4, 8, 16)) ** 2)
    out = tmp_path / "out"
    out.mkdir()
    (out / "older.txt").write_text("kept")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(figures, "detection_png", interrupted)
    assert main(["detect", "--frames", str(frames), "--threshold", "1", "--out", str(out)]) == 130
    assert sorted(p.name for p in out.iterdir()) == ["older.txt"]
    monkeypatch.undo()
    # and a clean run keeps its outputs
    assert main(["detect", "--frames", str(frames), "--threshold", "1", "--out", str(out)]) == 0
    assert {"detection.csv", "detection.png", "older.txt"} <= {p.name for p in out.iterdir()}


@pytest.mark.parametrize("signum, status", [(2, 130), (15, 143)])
def test_a_signal_before_the_command_line_is_imported_is_one_line(signum, status):
    """The console script's launcher (sonartrack/_launch.py) holds the interrupt from its first line: a signal that
    arrives while the command line's modules are still being imported ends the process with the interrupted line
    and 128 + the signal (before it: Python's KeyboardInterrupt traceback, or a silent death by SIGTERM)."""
    code = ("import os, signal; from sonartrack import _launch; _launch.install(); "
            f"os.kill(os.getpid(), {signum}); import sonartrack.cli; print('imported')")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == status and "imported" not in res.stdout
    assert res.stderr == "interrupted: nothing half-written was kept; rerun the same command\n"
