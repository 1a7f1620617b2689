"""``python -m sonartrack.cli``: the same as the ``sonartrack`` command."""

from sonartrack.cli import _entry

_entry()
