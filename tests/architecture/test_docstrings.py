"""Every public name of the library and systems layers says what it is: a maintainer reads the docstring, not the code.

Public: a module-level function or class (also inside module-level ``if``/``try`` blocks) whose name does not start
with ``_``, in a module and folder whose names do not start with ``_`` (``__init__.py`` included), and every public
method (properties included) of a public class. Checked in src/sonartrack/ except cli/, studies/ and report/ (the
faces and the studies above the library and systems layers). Only presence is checked here, not the numpydoc
sections (a docstring may be short where the signature says it all).
"""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "src" / "sonartrack"
EXCLUDED = {"cli", "studies", "report"}


def _module_stmts(body):
    for s in body:
        if isinstance(s, ast.If):
            yield from _module_stmts(s.body)
            yield from _module_stmts(s.orelse)
        elif isinstance(s, ast.Try):
            yield from _module_stmts(s.body)
            for h in s.handlers:
                yield from _module_stmts(h.body)
            yield from _module_stmts(s.orelse)
            yield from _module_stmts(s.finalbody)
        else:
            yield s


def _is_overload(fn) -> bool:
    for d in fn.decorator_list:
        d = d.func if isinstance(d, ast.Call) else d
        if (d.attr if isinstance(d, ast.Attribute) else getattr(d, "id", "")) == "overload":
            return True
    return False


def _undocumented(path: Path):
    """Yield the qualified names of the public functions, classes and methods of one module without a docstring."""
    defs = (ast.FunctionDef, ast.AsyncFunctionDef)
    for s in _module_stmts(ast.parse(path.read_text(), str(path)).body):
        if not isinstance(s, (*defs, ast.ClassDef)) or s.name.startswith("_"):
            continue
        if not ast.get_docstring(s) and not (isinstance(s, defs) and _is_overload(s)):
            yield s.name
        if isinstance(s, ast.ClassDef):
            for m in s.body:
                if isinstance(m, defs) and not m.name.startswith("_") and not ast.get_docstring(m) \
                        and not _is_overload(m):
                    yield f"{s.name}.{m.name}"


def _public_modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG)
        if len(rel.parts) < 2 or rel.parts[0] in EXCLUDED:
            continue
        if any(p.startswith("_") and p != "__init__.py" for p in rel.parts):
            continue
        yield path, rel


def test_the_checker_sees_a_missing_docstring(tmp_path):
    src = tmp_path / "m.py"
    src.write_text('def f():\n    """Doc."""\n\n\ndef g():\n    pass\n\n\nclass C:\n    """Doc."""\n\n'
                   '    def m(self):\n        pass\n\n    def _private(self):\n        pass\n\n\n'
                   'if True:\n    def h():\n        return 1\n')
    assert list(_undocumented(src)) == ["g", "C.m", "h"]


def test_public_functions_classes_and_methods_have_docstrings():
    offenders = [f"{rel}: {name}" for path, rel in _public_modules() for name in _undocumented(path)]
    assert not offenders, f"{len(offenders)} public names without a docstring:\n" + "\n".join(offenders)
