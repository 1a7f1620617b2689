"""A table held as equal-length column arrays (a frozen dataclass, one field a column): its length is its row count."""

from __future__ import annotations


class Rows:
    """Base of a dataclass whose fields are columns of one length, the first field a column: ``len`` is the rows.

    A base with empty ``__slots__``, so that ``@dataclass(slots=True)`` subclasses keep theirs.
    """

    __slots__ = ()

    def __len__(self) -> int:
        return len(getattr(self, next(iter(self.__dataclass_fields__))))
