"""The ``Claim`` record: one published result restated as a check on our numbers.

Each study's ``claims(summary, config)`` returns a list of these; the runner stores them in
``summary.json`` (``Claim.as_dict``) and the report shows them as a table (paper vs ours, holds).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True, slots=True)
class Claim:
    """One paper claim checked on our numbers."""

    id: str  #: short stable identifier, e.g. "exp1-imm-best"
    paper: str  #: what the paper says (and where: figure, table, section)
    text: str  #: the check as applied to our numbers
    ours: str  #: our numbers, formatted for the report
    holds: bool  #: whether the check passes
    tolerance: str = "-"  #: the tolerance used and why

    def __post_init__(self):
        object.__setattr__(self, "holds", bool(self.holds))

    def as_dict(self) -> dict:
        """The claim as a plain dict (for ``summary.json``).

        Returns
        -------
        dict
            Its fields by name.
        """
        return asdict(self)


def as_dicts(claims) -> list[dict]:
    """Claims (records or already dicts) as plain dicts, for JSON.

    Parameters
    ----------
    claims : iterable of Claim or dict
        The claims.

    Returns
    -------
    list of dict
        One dict per claim.
    """
    return [c.as_dict() if isinstance(c, Claim) else dict(c) for c in claims]
