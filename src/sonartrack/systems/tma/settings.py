"""The tma system's settings: one tree, the TMA library's own (tma/settings.py).

``sonartrack tma --print-config`` prints it; the root holds the method and the measurement noise, the groups
``[imm]``, ``[sequential]``, ``[batch]`` (with the em-map environment ``env``, source level and window),
``[em_map]``, ``[inputs]`` and ``[verdict]`` (when a range is reported as not determined) hold what is their
own. The system overrides no library default, so the tree is the library's class itself.
"""

from __future__ import annotations

from sonartrack.tma.settings import BatchSettings, TmaSettings

__all__ = ["BatchSettings", "TmaSettings"]
