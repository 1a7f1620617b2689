"""Shape rules of the package that review alone used to keep (and did not): checked on every run.

- no function over 60 lines, except numba kernels and the factories that build them (100): a function
  must be readable against the equation it implements;
- studies are simulate -> estimate -> summarize -> claims: no plotting in studies/, every study has
  its figures module in report/figures/;
- one atomic-write helper: ``os.replace`` appears only in io/atomic.py;
- units in one place: conversion constants are defined only in core/units.py;
- faces stay thin: cli/ defines no numerical code (no numpy-heavy helpers; checked by size).
"""

from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "src" / "sonartrack"
MAX_LINES = 60
MAX_KERNEL_LINES = 100


def _sources():
    for path in sorted(PKG.rglob("*.py")):
        yield path, path.read_text()


def _is_kernel(node: ast.FunctionDef) -> bool:
    decorators = " ".join(ast.unparse(d) for d in node.decorator_list)
    return "njit" in decorators or "jit" in decorators or node.name.startswith("_build")


def test_functions_are_short():
    long = []
    for path, text in _sources():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1
                limit = MAX_KERNEL_LINES if _is_kernel(node) else MAX_LINES
                if n > limit:
                    long.append(f"{path.relative_to(PKG)}:{node.lineno} {node.name} ({n} lines > {limit})")
    assert not long, "functions too long to read against their equations:\n" + "\n".join(long)


def test_studies_do_not_plot_and_every_study_has_figures():
    from sonartrack.report.figures import STUDY_FIGURES
    from sonartrack.studies import STUDIES

    for path in (PKG / "studies").glob("*.py"):
        text = path.read_text()
        assert not re.search(r"^\s*(import|from) matplotlib", text, re.MULTILINE), \
            f"studies/{path.name} plots: move it to report/figures/"
        assert "def figures" not in text, f"studies/{path.name} defines figures: move it to report/figures/"
    for sid in STUDIES:
        assert sid in STUDY_FIGURES, f"study {sid} has no figures module in report/figures/"
        assert importlib.util.find_spec(STUDY_FIGURES[sid]) is not None, STUDY_FIGURES[sid]


def test_one_atomic_write_helper():
    offenders = [str(p.relative_to(PKG)) for p, t in _sources()
                 if "os.replace" in t and p.relative_to(PKG).as_posix() != "io/atomic.py"]
    assert not offenders, f"hand-rolled temp-file + rename (use sonartrack.io.atomic): {offenders}"


def test_unit_constants_defined_once():
    pattern = re.compile(r"^(KNOT_MPS|KM_M|NMI_M)\s*=", re.MULTILINE)
    offenders = [str(p.relative_to(PKG)) for p, t in _sources()
                 if pattern.search(t) and p.relative_to(PKG).as_posix() != "core/units.py"]
    assert not offenders, f"unit constants redefined (import them from sonartrack.core.units): {offenders}"


def test_plotting_only_in_report():
    drawing = re.compile(r"plt\.(subplots|figure|plot|imshow)\(|\.add_subplot\(|\.pcolormesh\(")
    offenders = [str(p.relative_to(PKG)) for p, t in _sources()
                 if drawing.search(t) and p.relative_to(PKG).parts[0] != "report"]
    assert not offenders, f"plotting outside report/figures/: {offenders}"


def test_every_setting_has_a_doc_and_a_unit_entry():
    import importlib
    import pkgutil

    import sonartrack
    from sonartrack.core.settings import Settings

    has_stonesoup = importlib.util.find_spec("stonesoup") is not None
    for info in pkgutil.walk_packages(sonartrack.__path__, "sonartrack.", onerror=lambda name: None):
        if ".cli" in info.name or info.name.endswith("__main__"):
            continue
        if info.name.startswith("sonartrack.stonesoup") and not has_stonesoup:
            continue  # the optional extra: its own tests skip without it
        importlib.import_module(info.name)

    def subclasses(cls):
        for sub in cls.__subclasses__():
            yield sub
            yield from subclasses(sub)

    missing = []
    classes = [c for c in subclasses(Settings) if c.__module__.startswith("sonartrack.")]
    assert len(classes) >= 10  # the walk found the package's settings
    for cls in classes:
        for name, f in cls.model_fields.items():
            extra = f.json_schema_extra if isinstance(f.json_schema_extra, dict) else {}
            if not f.description or "unit" not in extra:
                missing.append(f"{cls.__module__}.{cls.__name__}.{name}")
    assert not missing, "settings declared without setting(default, doc, unit=...):\n" + "\n".join(missing)
