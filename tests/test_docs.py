"""The docs site (docs/, built by `make docs`, which `make test` runs before the suite): every public module has
its API page with every public function and class defined in it, every tutorial was executed and drew its
figures, and the docstring preprocessor (docs/_ext/plaintext_math.py) turns the house's plain-text equations
into text that reStructuredText reads without an error."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys
from pathlib import Path

import pytest

import sonartrack

ROOT = Path(__file__).resolve().parents[1]
HTML = ROOT / "docs" / "_build" / "html"
TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("plot_*.py"))
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

from plaintext_math import escape_docstring  # noqa: E402


def _built() -> Path:
    if not (HTML / "api.html").is_file():
        pytest.fail(f"the docs are not built in {HTML}: run `make docs` (`make test` does, before the tests)")
    return HTML


def _public_modules() -> list[str]:
    names = ["sonartrack"]
    for info in pkgutil.walk_packages(sonartrack.__path__, "sonartrack."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return names


def _public_objects(module_name: str) -> list[str]:
    """Functions and classes defined in the module (not imported into it) whose names are public."""
    module = importlib.import_module(module_name)
    return [name for name, obj in vars(module).items()
            if not name.startswith("_") and (inspect.isfunction(obj) or inspect.isclass(obj))
            and getattr(obj, "__module__", None) == module_name]


def test_every_public_module_function_and_class_is_in_the_api_reference():
    html = _built()
    modules = _public_modules()
    assert len(modules) > 200  # the walk found the package, not an empty path
    missing_pages = [m for m in modules if not (html / "api" / f"{m}.html").is_file()]
    assert not missing_pages, f"modules without an API page: {missing_pages} (rebuild with `make docs`)"
    missing = []
    for module_name in modules:
        page = (html / "api" / f"{module_name}.html").read_text(encoding="utf-8")
        missing += [f"{module_name}.{name}" for name in _public_objects(module_name)
                    if f'id="{module_name}.{name}"' not in page]
    assert not missing, f"public functions and classes missing from the API reference: {missing}"


def test_the_api_index_links_every_package():
    index = (_built() / "api.html").read_text(encoding="utf-8")
    assert 'href="api/sonartrack.html"' in index
    package_page = (HTML / "api" / "sonartrack.html").read_text(encoding="utf-8")
    for layer in ("acoustics", "tracking", "tma", "systems", "stonesoup", "cli"):
        assert f'href="sonartrack.{layer}.html' in package_page, layer


@pytest.mark.parametrize("tutorial", TUTORIALS, ids=[t.stem for t in TUTORIALS])
def test_every_tutorial_was_executed_with_its_figures(tutorial):
    html = _built()
    page = html / "auto_tutorials" / f"{tutorial.stem}.html"
    assert page.is_file(), f"{tutorial.name} has no page (rebuild with `make docs`)"
    text = page.read_text(encoding="utf-8")
    image = f"sphx_glr_{tutorial.stem}_001.png"
    assert image in text and (html / "_images" / image).is_file(), f"{tutorial.name} drew no figure"
    assert "Traceback" not in text, f"{tutorial.name}'s page shows an error"
    assert page.stat().st_mtime >= tutorial.stat().st_mtime, f"{page} is older than {tutorial.name}"
    assert len(TUTORIALS) >= 5


def _rst_errors(text: str) -> list[str]:
    """The messages docutils gives for a text, as Sphinx would (level WARNING and up)."""
    from docutils.core import publish_doctree
    from docutils.utils import Reporter

    messages = []
    settings = {"report_level": Reporter.WARNING_LEVEL, "halt_level": 5, "warning_stream": False}
    doctree = publish_doctree(text, settings_overrides=settings)
    for node in doctree.traverse():
        if node.tagname == "system_message" and node["level"] >= Reporter.WARNING_LEVEL:
            messages.append(node.astext())
    return messages


DOCSTRING = """Range rate and cone angle of a target.

The range rate is |v| cos(a) where |v| is the speed, and q = (y_+ - y_-) / (2 y_0); ``|x|`` stays a literal and
``Detection``s are plural. The equations:

    r = |p - p_R|,   b = atan2(dx, dy)
          (the second line deeper)

========  ================
name      meaning
========  ================
speed     the speed in m/s
========  ================

Literal::

    |x| stays
"""


def test_plain_text_equations_read_without_errors_after_the_preprocessor():
    assert _rst_errors(DOCSTRING), "the raw text must give errors, or this test shows nothing"
    lines = DOCSTRING.splitlines()
    escape_docstring(lines)
    text = "\n".join(lines)
    assert _rst_errors(text) == []
    assert r"\|v\| cos(a)" in text and r"y\_+ - y\_-" in text and "``|x|``" in text and r"``Detection``\ s" in text
    assert "The equations::" in text  # the indented block is a literal block now
    assert "    r = |p - p_R|," in text and "    |x| stays" in text  # literal blocks as written
