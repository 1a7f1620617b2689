"""The console page's files, read once from the package into a fixed name -> (bytes, content type) map.

The server answers a request only with an entry of this map, looked up by the exact request path: no part of
a request ever becomes a file-system path. The files ship as package data (pyproject.toml,
``[tool.setuptools.package-data]``); nothing is loaded from the internet.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

#: URL path -> (file in assets/, content type)
ASSET_FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/index.html": ("index.html", "text/html; charset=utf-8"),
    "/console.js": ("console.js", "text/javascript; charset=utf-8"),
    "/console.css": ("console.css", "text/css; charset=utf-8"),
}


@cache
def asset_map() -> dict[str, tuple[bytes, str]]:
    """URL path -> (body, content type) of every asset, read once from the installed package."""
    folder = resources.files("sonartrack.console") / "assets"
    return {path: ((folder / name).read_bytes(), ctype) for path, (name, ctype) in ASSET_FILES.items()}
