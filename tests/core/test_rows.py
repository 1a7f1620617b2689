"""core/rows.py: a column-array record's length is its first column's, and slots stay slots."""

from dataclasses import dataclass

import numpy as np

from sonartrack.core.rows import Rows


@dataclass(frozen=True, slots=True)
class _Two(Rows):
    a: np.ndarray
    b: np.ndarray


def test_length_is_the_first_columns():
    assert len(_Two(np.arange(5), np.arange(5))) == 5
    assert len(_Two(np.zeros(0), np.zeros(0))) == 0
    assert len(_Two(np.zeros((3, 4)), np.zeros(3))) == 3  # rows, not elements


def test_slots_are_kept():
    rows = _Two(np.arange(2), np.arange(2))
    assert not hasattr(rows, "__dict__")  # the base's empty __slots__ leaves the subclass slotted
    assert _Two.__slots__ == ("a", "b")
