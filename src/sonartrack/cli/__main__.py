"""``python -m sonartrack.cli``: the same as the ``sonartrack`` command."""

from sonartrack.cli import _entry

if __name__ == "__main__":
    _entry()
