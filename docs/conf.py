"""Sphinx configuration of the sonartrack site: `make docs` builds it into docs/_build/html, warnings as errors.

Pages: index and architecture (sections of README.md included, not copied), the user guide (README.md's
chapters), the API reference (autosummary over every public module, autodoc + numpydoc) and the tutorials
(docs/tutorials/plot_*.py, executed by sphinx-gallery at every build).
"""

from __future__ import annotations

import os
import sys
import types
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent / "src"))  # the worktree's sonartrack, also when not installed editable

import sonartrack  # noqa: E402

project = "sonartrack"
author = "the sonartrack developers"
copyright = "the sonartrack developers, MIT licence"  # noqa: A001 (Sphinx's name)
release = version = sonartrack.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "plaintext_math",  # docs/_ext: the docstrings' plain-text equations read as text
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}  # Markdown: guide.md, which includes README.md
templates_path = ["_templates"]
exclude_patterns = ["_build", "tutorials/README.rst"]
root_doc = "index"
html_theme = "alabaster"
# wide pages: the docstrings' equations and tables are wide
html_theme_options = {"description": "underwater detection, tracking and TMA", "fixed_sidebar": True,
                      "page_width": "min(1400px, 96vw)", "sidebar_width": "230px", "body_max_width": "none"}
highlight_language = "none"  # a docstring's literal block is a plain-text equation; code blocks name their language
html_sidebars = {"**": ["about.html", "navigation.html", "searchbox.html"]}
html_show_sourcelink = False
html_copy_source = False

# API reference: one page per public module (autosummary, recursive; _templates/autosummary/module.rst), each
# documenting the functions, classes and data defined in that module (not the names it imports, which have their
# own page). Every public member is listed, documented or not.
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
# signatures without annotations: the numpydoc sections give each parameter's type, shape and unit as prose, and
# formatting the annotations of 5000 objects cost 14 s of a 65 s build (measured, 2 cores)
autodoc_typehints = "none"
numpydoc_show_class_members = False  # the members follow on the same page
numpydoc_xref_param_type = False  # our types are prose ("array_like, shape (n,)"), not references
numpydoc_validation_checks: set[str] = set()

# `python -m sonartrack.cli` runs the command line when imported; autosummary imports every submodule to find
# members, so it gets an empty stand-in (it has no members to document)
sys.modules.setdefault("sonartrack.cli.__main__", types.ModuleType("sonartrack.cli.__main__"))
# numpydoc reads the docstrings of the Stone Soup classes ours subclass, and says so about their sections
warnings.filterwarnings("ignore", message="Unknown section", category=UserWarning, module="numpydoc")

# MyST: README.md's Markdown (headings of its chapters start at level 2 in the included parts)
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

# Tutorials: executed at every build (run_stale_examples), so a change of sonartrack that breaks one fails the
# build; each writes into a temporary folder and removes it. Seeds are fixed in the scripts.
sphinx_gallery_conf = {
    "examples_dirs": "tutorials",
    "gallery_dirs": "auto_tutorials",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "sphinx_gallery.sorting.FileNameSortKey",
    "run_stale_examples": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "reset_modules": ("matplotlib",),
    "image_scrapers": ("matplotlib",),
    "capture_repr": ("_repr_html_", "__repr__"),
    "show_memory": False,
    "min_reported_time": 1,
    "line_numbers": False,
}
os.environ.setdefault("NUMBA_CACHE_DIR", str(HERE.parent / ".numba-cache"))  # shared with the tests


def _skip_alias(app, what, name, obj, skip, options):  # noqa: ARG001 (Sphinx's signature)
    """Skip module-level type aliases (``Steering = tuple[...]``): not objects a user calls, and autodoc fails
    to format their signature."""
    return True if isinstance(obj, types.GenericAlias) else None


def setup(app):
    app.connect("autodoc-skip-member", _skip_alias)
