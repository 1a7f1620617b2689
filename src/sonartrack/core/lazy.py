"""A package's public names loaded on first use (PEP 562), so that importing the package stays light."""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_exports(package: str, exports: dict[str, str]) -> tuple[Callable[[str], object], list[str]]:
    """The ``__getattr__`` and ``__all__`` of a package whose names load from their modules on first use.

    Parameters
    ----------
    package : str
        The package's name (``__name__``), as an unknown name's error says.
    exports : dict of str to str
        Each public name and the module that defines it.

    Returns
    -------
    __getattr__ : callable
        The module-level ``__getattr__`` (name -> the object; AttributeError for a name not exported).
    __all__ : list of str
        The names, sorted.
    """

    def __getattr__(name: str):
        if name in exports:
            return getattr(importlib.import_module(exports[name]), name)
        raise AttributeError(f"module '{package}' has no attribute {name!r}")

    return __getattr__, sorted(exports)
