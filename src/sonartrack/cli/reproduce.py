"""``sonartrack reproduce``: run the papers' experiments (``sonartrack studies`` lists them, cli/studies.py)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from sonartrack.core.errors import require


def _interrupted(exc: KeyboardInterrupt, mods, configs, seed: int, out: Path) -> KeyboardInterrupt:
    """The interrupt, carrying its one line: trials of this run complete on disk (all studies), of how many."""
    import signal

    from sonartrack.cli import Interrupted
    from sonartrack.experiment.runner import stored_trials

    kept = sum(stored_trials(m, c, seed, out) for m, c in zip(mods, configs, strict=True))
    total = sum(int(c.runs) for c in configs)
    return Interrupted(getattr(exc, "signum", signal.SIGINT),
                       f"interrupted: {kept} trials kept (of {total}) in {out}; run the same command to resume")


def reproduce_cmd(
    study: Annotated[str, typer.Argument(help="Study id (see `sonartrack studies`) or 'all'.")],
    runs: Annotated[int | None, typer.Option(help="Monte Carlo runs (default: the paper's, or the quick "
                                                   "preset's).")] = None,
    quick: Annotated[bool, typer.Option("--quick", help="Small preset for a fast check (CI, demo).")] = False,
    workers: Annotated[int, typer.Option(help="Local worker processes.")] = 2,
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address, e.g. tcp://host:8786.")] = None,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("results"),
    seed: Annotated[int, typer.Option(help="Master seed: trial i uses child i of SeedSequence(seed).")] = 2017,
    config: Annotated[Path | None, typer.Option(help="TOML file overriding config values (one study only).")] = None,
) -> None:
    """Reproduce a paper's experiment: run (or resume) its Monte Carlo trials, check its claims, write the report."""
    from sonartrack import studies
    from sonartrack.cli._progress import TrialProgress, console, make_progress
    from sonartrack.experiment import pipeline, runner
    from sonartrack.io import toml as toml_io
    from sonartrack.report.figures import study_figures

    require(seed >= 0, f"--seed must be a non-negative integer (got {seed}): seeds index SeedSequence streams")
    require(runs is None or runs >= 1, f"--runs must be at least 1 (got {runs})")
    require(workers >= 1, f"--workers must be at least 1 (got {workers})")
    ids = studies.available() if study == "all" else [study]
    mods = [studies.load(s) for s in ids]  # unknown ids fail here, before any work
    overrides = None
    if config is not None:
        require(len(mods) == 1, "--config applies to one study: name it instead of 'all'")
        overrides = toml_io.load(config)
    configs = [pipeline.resolve_config(m, quick=quick, runs=runs, overrides=overrides) for m in mods]
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    results, seconds = [], []
    try:
        # one pool of workers for all the studies: each worker imports its libraries once, not once per study
        with make_progress() as prog, runner.WorkerPool(workers) as pool:
            bar = TrialProgress(prog)
            for mod, cfg in zip(mods, configs, strict=True):
                seconds.append(time.perf_counter())
                results.append(pipeline.reproduce(mod, cfg, seed=seed, out=out, workers=workers, pool=pool,
                                                  scheduler=scheduler, progress=bar, figures=study_figures))
                seconds[-1] = time.perf_counter() - seconds[-1]
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: the workers are stopped by now; say what was kept
        raise _interrupted(exc, mods, configs, seed, out) from None
    from sonartrack.report.html import write_report

    report = write_report(out)
    for r, took in zip(results, seconds, strict=True):
        # one line per study even in a narrow terminal or a log (rich would wrap it mid-number)
        console.print(f"{r.study_id}: {r.runs} runs ({r.computed} computed, {r.runs - r.computed} from disk), "
                      f"claims holding {r.n_holding}/{r.n_claims}, {took:.1f} s", soft_wrap=True)
    n_claims = sum(r.n_claims for r in results)
    n_hold = sum(r.n_holding for r in results)
    typer.echo(f"done in {time.perf_counter() - t0:.1f} s: {len(results)} studies, {n_hold}/{n_claims} claims hold; "
               f"report: {report}")
