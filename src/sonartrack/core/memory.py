"""The working memory a run plans for: settings whose arrays would need more are refused, the largest named.

A system lists its largest working arrays as ``needs``: (bytes, what holds them and the settings that size them,
how to make them smaller), estimated from the settings before anything is allocated, so that a run that cannot fit
fails at once in one line instead of after minutes, or by the operating system's hand.
"""

from __future__ import annotations

from sonartrack.core.errors import InputError

#: working memory a run may plan for (bytes): settings asking for more are refused with the figure
MEMORY_LIMIT_BYTES = 2 * 1024**3


def over_limit(needs, limit_bytes: float = MEMORY_LIMIT_BYTES) -> tuple[float, tuple[float, str, str]] | None:
    """Whether ``needs``, held at once, exceed the limit.

    Parameters
    ----------
    needs : list of (float, str, str)
        Bytes, what needs them, and the fix (module doc).
    limit_bytes : float
        The limit (bytes).

    Returns
    -------
    (float, (float, str, str)) or None
        None when the needs fit; else their total (bytes) and the largest need.
    """
    total = sum(need for need, _, _ in needs)
    return None if total <= limit_bytes else (total, max(needs, key=lambda n: n[0]))


def refuse_over_limit(needs, whose: str) -> None:
    """Refuse ``needs`` that together exceed :data:`MEMORY_LIMIT_BYTES`, naming the total, the largest and its fix.

    Parameters
    ----------
    needs : list of (float, str, str)
        Bytes, what needs them, and the fix (module doc).
    whose : str
        Whose working arrays, as the message starts (e.g. "the chain's").

    Raises
    ------
    InputError
        When the needs exceed the limit.
    """
    over = over_limit(needs)
    if over is not None:
        total, (need, what, fix) = over
        raise InputError(f"{whose} working arrays would take {total / 1e9:.3g} GB of memory, more than the "
                         f"{MEMORY_LIMIT_BYTES / 1e9:.3g} GB it plans for; the largest, {what}, {need / 1e9:.3g} GB: "
                         f"{fix}")
