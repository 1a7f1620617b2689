"""The one exception for user mistakes.

Anything a user can get wrong (a malformed file, NaNs, a unit mix-up, an unknown study name, a
non-positive count) raises :class:`InputError` with a one-line message that names the problem and
the fix. The command line prints the message alone (no traceback) and exits with status 2; any
other exception is a bug in sonartrack and is shown in full.
"""


class InputError(ValueError):
    """Bad input from the user: the message is one line saying what is wrong and how to fix it."""


def require(condition: bool, message: str) -> None:
    """Raise :class:`InputError` with ``message`` unless ``condition`` holds.

    Parameters
    ----------
    condition : bool
        What must be true of the user's input.
    message : str
        One line naming the problem and the fix.

    Raises
    ------
    InputError
        When ``condition`` is false.
    """
    if not condition:
        raise InputError(message)
