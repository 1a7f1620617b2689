"""Layering: every import in the package (function-level ones included) points down the layer stack.

The stack is DESIGN.md's picture (``sonartrack/__init__.py`` repeats it)::

    cli, stonesoup              faces (cli may use report)
    report                      HTML report and figures
    studies                     one module per paper
    experiment                  Monte Carlo runner, store, claims
    systems                     end-to-end pipelines, one sub-package per system (passive, track, tma,
                                detect, simulate): one settings tree and one run function each
    io                          user data in and out
    tracking, tma, detection    trackers, TMA, MFTD
    association                 gating, PDA, JPDA, IPDA
    filters                     KF, EKF, MGEKF, IMM
    sim                         platforms and sensor simulators (not imported by estimators)
    acoustics                   sound speed, propagation, bearings
    models                      motion and measurement models
    core                        angles, Gaussians, settings, units
    metrics                     beside the algorithms: imports core and models only

A module may import its own layer's package and any layer below it. Imports inside functions count:
they are how layers used to be crossed without a top-of-file check noticing. The systems are estimators
(they never import sim/), except ``systems.simulate``, whose job is the simulator.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[2] / "src" / "sonartrack"

#: rank of each top-level subpackage; a module may import packages of rank <= its own, and never a
#: sibling of the same rank unless it is itself (tracking / tma / detection stay independent).
RANK = {
    "core": 0, "models": 1, "acoustics": 2, "sim": 3, "filters": 4, "association": 5,
    "tracking": 6, "tma": 6, "detection": 6, "io": 7, "systems": 7.5, "experiment": 8, "studies": 9,
    "report": 10, "console": 10, "cli": 11, "stonesoup": 11,
}
#: metrics/ sits beside the algorithm layers: it may import core/ and models/ only, and anyone above
#: models may import it.
METRICS_MAY_IMPORT = {"core", "models", "metrics"}
METRICS_RANK = 1.5
#: estimators never depend on simulators: sim/ makes data, the estimators consume it (a simulator's
#: helper that an estimator needs belongs in models/).
ESTIMATORS = {"filters", "association", "tracking", "tma", "detection", "systems"}
#: sub-packages of an estimator layer that may import sim/ all the same
SIM_ALLOWED = {"systems.simulate"}


def _layer_of(module_path: Path) -> str:
    """The module's layer: its top-level subpackage, qualified by the system for systems/ ("systems.passive");
    "" for the package's own __init__ and top files."""
    rel = module_path.relative_to(PKG)
    if len(rel.parts) > 2 and rel.parts[0] == "systems":
        return f"systems.{rel.parts[1]}"
    return rel.parts[0] if len(rel.parts) > 1 else ""


def _imported_layers(tree: ast.AST, module_path: Path):
    pkg_parts = module_path.relative_to(PKG.parent).with_suffix("").parts
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "sonartrack" and len(parts) > 1:
                    yield node.lineno, parts[1]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import: resolve against this module's package
                # from a module the package is its parent; from an __init__.py the package itself
                base = list(pkg_parts[:len(pkg_parts) - node.level])
                parts = base + (node.module.split(".") if node.module else [])
            else:
                parts = (node.module or "").split(".")
            if parts and parts[0] == "sonartrack":
                if len(parts) > 1:
                    yield node.lineno, parts[1]
                else:  # from sonartrack import x
                    for alias in node.names:
                        yield node.lineno, alias.name


def _allowed(src: str, dst: str) -> bool:
    if dst not in RANK and dst != "metrics":
        return True  # sonartrack.__version__, InputError re-export and the like
    if dst == "sim" and src in SIM_ALLOWED:
        return True
    src = src.split(".")[0]
    if src == "" or src == dst:
        return True
    if src == "metrics":
        return dst in METRICS_MAY_IMPORT
    if dst == "metrics":
        return RANK.get(src, 0) > METRICS_RANK
    if src not in RANK:
        return True
    if dst == "sim" and src in ESTIMATORS:
        return False
    if RANK[dst] == RANK[src]:
        return False
    return RANK[dst] < RANK[src]


def _violations():
    bad = []
    for path in sorted(PKG.rglob("*.py")):
        src = _layer_of(path)
        tree = ast.parse(path.read_text(), filename=str(path))
        for lineno, dst in _imported_layers(tree, path):
            if not _allowed(src, dst):
                bad.append(f"{path.relative_to(PKG)}:{lineno}: {src} imports {dst}")
    return bad


def test_no_upward_imports():
    bad = _violations()
    assert not bad, "upward or sideways imports:\n" + "\n".join(bad)


def test_every_subpackage_has_a_layer():
    dirs = {p.name for p in PKG.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    unknown = dirs - set(RANK) - {"metrics"}
    assert not unknown, f"subpackages without a layer in RANK: {sorted(unknown)} (add them to DESIGN.md too)"


@pytest.mark.parametrize(("src", "dst", "ok"), [
    ("tracking", "association", True), ("association", "tracking", False), ("tracking", "tma", False),
    ("acoustics", "io", False), ("metrics", "filters", False), ("studies", "metrics", True),
    ("models", "metrics", False), ("cli", "report", True), ("report", "cli", False),
    ("detection", "sim", False), ("studies", "sim", True), ("sim", "models", True),
    ("systems.passive", "io", True), ("systems.passive", "sim", False), ("systems", "sim", False),
    ("systems.simulate", "sim", True), ("systems.simulate", "studies", False), ("io", "systems", False),
    ("studies", "systems", True), ("systems.passive", "experiment", False), ("systems.track", "systems", True),
])
def test_rule_itself(src, dst, ok):
    # the checker must be able to fail: a known upward import is refused, a downward one allowed
    assert _allowed(src, dst) is ok
