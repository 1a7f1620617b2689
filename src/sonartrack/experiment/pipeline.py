"""Reproduce one study end to end: run (or resume) its trials, then summarise and store.

Output, under ``<out>/<study>/``: ``trials.parquet`` (all trials), ``summary.json`` (summary and
claims, as data), ``config.toml`` (the resolved configuration), one PNG per figure. Each file is
written to a temporary name and renamed, so a folder never holds a half-written output.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.experiment import runner, store
from sonartrack.experiment.claims import as_dicts
from sonartrack.io import toml as toml_io
from sonartrack.io.atomic import save_figure, write_text

#: ``figures(study_id, summary, config) -> {name: matplotlib Figure}``: the face (cli/, report/) passes
#: its figure maker in, so that this layer never imports the plotting layer above it.
FigureMaker = Callable[[str, dict, object], dict]


@dataclass(frozen=True, slots=True)
class StudyResult:
    """What :func:`reproduce` did: the study, its output folder, the runs asked for, the claims and how many
    hold, and the number of trials computed this time (the rest came from the store).
    """
    study_id: str
    out_dir: Path
    runs: int
    n_claims: int
    n_holding: int
    computed: int


def resolve_config(study_mod, quick: bool = False, runs: int | None = None, overrides: dict | None = None):
    """The study's config: defaults (or the quick preset), then a TOML override dict, then ``runs``.

    Parameters
    ----------
    study_mod : module
        The study module (``Config``, ``STUDY_ID``).
    quick : bool, default False
        Start from ``Config.quick()`` instead of the defaults.
    runs : int, optional
        Number of Monte Carlo runs, overriding the config's.
    overrides : dict, optional
        Nested values (e.g. a parsed ``--config`` TOML file) merged over the base.

    Returns
    -------
    Config
        The validated config of the study.

    Raises
    ------
    InputError
        If the merged values do not validate.
    """
    base = study_mod.Config.quick() if quick else study_mod.Config()
    data = base.model_dump(mode="json")
    if overrides:
        data = _deep_update(data, overrides)
    if runs is not None:
        data["runs"] = runs
    return toml_io.validate(study_mod.Config, data, source=f"{study_mod.STUDY_ID} config")


def _deep_update(base: dict, new: dict) -> dict:
    out = dict(base)
    for k, v in new.items():
        out[k] = _deep_update(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if np.isfinite(v) else None
    return x


def finish(study_mod, config, trials: dict[str, np.ndarray], out: Path,
           figures: FigureMaker | None = None) -> tuple[dict, list[dict]]:
    """Summarise stored trials and write summary.json, config.toml, the figures and trials.parquet (atomically).

    Parameters
    ----------
    study_mod : module
        The study module (``summarize``, ``claims``, ``STUDY_ID``, ``TITLE``, ``PAPER``).
    config : Config
        The study's resolved config.
    trials : dict of str to ndarray
        All trials' outputs, stacked over the runs.
    out : path-like
        Output root; files go to ``<out>/<study>/``.
    figures : callable, optional
        ``figures(study_id, summary, config) -> {name: Figure}``; None: no PNGs.

    Returns
    -------
    summary : dict
        The JSON-ready summary (non-finite numbers become None).
    claims : list of dict
        The claims, as dicts.
    """
    folder = Path(out) / study_mod.STUDY_ID
    folder.mkdir(parents=True, exist_ok=True)
    summary = _jsonable(study_mod.summarize(trials, config))
    claims = _jsonable(as_dicts(study_mod.claims(summary, config)))
    names = []
    if figures is not None:
        for name, fig in figures(study_mod.STUDY_ID, summary, config).items():
            save_figure(fig, folder / f"{name}.png", dpi=110, bbox_inches="tight")
            names.append(name)
    store.write_trials_file(folder / "trials.parquet", trials)
    write_text(folder / "config.toml", toml_io.dumps(config.model_dump(mode="json")))
    doc = {"study": study_mod.STUDY_ID, "title": study_mod.TITLE, "paper": study_mod.PAPER,
           "runs": int(config.runs), "figures": names, "summary": summary, "claims": claims}
    write_text(folder / "summary.json", json.dumps(doc, indent=1, allow_nan=False))
    return summary, claims


def reproduce(study_mod, config, *, seed: int, out: Path, workers: int = 1, scheduler: str | None = None,
              progress=None, figures: FigureMaker | None = None, pool: runner.WorkerPool | None = None) -> StudyResult:
    """Run or resume a study's trials and write its outputs (module docstring).

    Parameters
    ----------
    study_mod : module
        The study module.
    config : Config
        Its resolved config (``config.runs`` trials).
    seed : int
        Master seed (trial i draws from ``trial_rng(seed, i)``).
    out : path-like
        Output root.
    workers : int, default 1
        Local worker processes.
    scheduler : str, optional
        Address of a Dask scheduler (instead of local processes).
    progress : optional
        Progress bar with ``start(study_id, total, done)`` and ``advance(n)``.
    figures : callable, optional
        Figure maker (e.g. :func:`sonartrack.report.figures.study_figures`) that draws the PNGs.
    pool : runner.WorkerPool, optional
        Local workers shared with the other studies of the same command (None: a pool for this study).

    Returns
    -------
    StudyResult
        Output folder, runs, claims and how many hold, trials computed this time.
    """
    plan = runner.plan_run(study_mod, config, config.runs, seed, out)
    if plan.n_todo and hasattr(study_mod, "prepare"):
        # shared, expensive inputs (e.g. transmission-loss fields) computed once here and cached on
        # disk, so that the workers load them instead of each computing them
        study_mod.prepare(config)
    if progress is not None:
        progress.start(plan.study_id, plan.runs, plan.runs - plan.n_todo)
    trials = runner.execute(plan, config, workers=workers, scheduler=scheduler, pool=pool,
                            on_chunk=(progress.advance if progress is not None else None))
    _, claims = finish(study_mod, config, trials, out, figures=figures)
    held = sum(1 for c in claims if c.get("holds"))
    return StudyResult(plan.study_id, Path(out) / plan.study_id, plan.runs, len(claims), held, plan.n_todo)
