"""`sonartrack studies` / `reproduce` from the command line: outputs, report, and bad input.

Each command runs in-process through :func:`sonartrack.cli.main` (tests/cli/test_entry.py checks the process).
"""

import json
from types import SimpleNamespace

import pytest

from sonartrack.cli import main


@pytest.fixture
def run(capsys, monkeypatch):
    """``sonartrack ARGS...`` in-process: its exit status, stdout and stderr."""
    monkeypatch.setenv("COLUMNS", "200")  # typer's usage text, as wide as in a terminal

    def call(*args):
        code = main(list(args))
        out = capsys.readouterr()
        return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)
    return call


def assert_one_line_error(res, *words):
    assert res.returncode == 2, res.stderr
    lines = [ln for ln in res.stderr.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.stderr
    assert "Traceback" not in res.stderr
    for w in words:
        assert w in lines[0]


def test_studies_lists_p4(run):
    res = run("studies")
    assert res.returncode == 0
    assert "bistatic-imm-ipda" in res.stdout


def test_unknown_study(tmp_path, run):
    res = run("reproduce", "no-such-study", "--out", str(tmp_path / "o"))
    assert_one_line_error(res, "unknown study", "bistatic-imm-ipda")
    assert not (tmp_path / "o").exists()


def test_zero_runs(tmp_path, run):
    res = run("reproduce", "bistatic-imm-ipda", "--runs", "0", "--out", str(tmp_path / "o"))
    assert_one_line_error(res, "--runs")
    assert not (tmp_path / "o").exists()


def test_bad_config_value(tmp_path, run):
    cfg = tmp_path / "c.toml"
    cfg.write_text("pd = 1.5\n")
    res = run("reproduce", "bistatic-imm-ipda", "--config", str(cfg), "--out", str(tmp_path / "o"))
    assert_one_line_error(res, "pd")


def test_reproduce_writes_outputs_and_report(tmp_path, run):
    cfg = tmp_path / "c.toml"
    cfg.write_text("n_scans = 60\nturn_start_s = 900.0\n")
    # one worker: the trials in this process (tests/experiment/test_runner.py checks a pool gives the same trials)
    res = run("reproduce", "bistatic-imm-ipda", "--runs", "3", "--workers", "1", "--out", str(tmp_path / "o"),
              "--config", str(cfg))
    assert res.returncode == 0, res.stderr
    assert "claims hold" in res.stdout
    folder = tmp_path / "o" / "bistatic-imm-ipda"
    doc = json.loads((folder / "summary.json").read_text())
    assert doc["runs"] == 3 and doc["claims"]
    assert {"id", "text", "paper", "ours", "tolerance", "holds"} <= doc["claims"][0].keys()
    for name in doc["figures"]:
        assert (folder / f"{name}.png").stat().st_size > 1000
    assert "n_scans = 60" in (folder / "config.toml").read_text()
    page = (tmp_path / "o" / "report.html").read_text()
    assert 'id="bistatic-imm-ipda"' in page and "data:image/png;base64," in page
    assert not list(folder.glob(".*tmp*"))


def test_help_everywhere(run):
    for cmd in ([], ["reproduce"], ["track"], ["studies"]):
        res = run(*cmd, "--help")
        assert res.returncode == 0 and "Usage" in res.stdout
