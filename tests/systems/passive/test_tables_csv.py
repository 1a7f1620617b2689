"""The passive tables written without pandas (systems/passive/tables.py ``csv_text``): the same bytes as pandas'
``DataFrame.to_csv(index=False)`` -- the reference implementation -- for every kind of column the tables hold and
the awkward values (NaN, infinities, -0.0, the extremes of float64 and float32, text with separators, quotes and
line ends, missing integers), with and without a float format; and the whole table set of a chain run is the one
the DataFrames give."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from sonartrack.systems.passive.tables import csv_text, stack_column, write_columns_csv

FLOATS = np.array([0.0, -0.0, 0.1, -1.5, 1e-300, 5e-324, 1.7976931348623157e308, np.inf, -np.inf, np.nan, 1e16,
                   123456.789, 2.0 / 3.0, 1e22, 1.0000000000000002])
FLOATS32 = np.array([0.0, -0.0, 0.1, -1.5, 1e-45, 1e-38, 3.4028235e38, np.inf, -np.inf, np.nan, 1e16, 123456.789,
                     2.0 / 3.0], dtype=np.float32)


def _pandas(columns: dict, float_format=None) -> str:
    frame = pd.DataFrame(columns)
    for name, values in columns.items():  # a column of ints and Nones is a nullable integer column in the tables
        if isinstance(values, np.ndarray) and values.dtype == object and all(
                v is None or isinstance(v, int) for v in values):
            frame[name] = pd.array(list(values), dtype="Int64")
    buf = io.StringIO()
    frame.to_csv(buf, index=False, float_format=float_format)
    return buf.getvalue()


CASES = {
    "float64": {"x": FLOATS},
    "float32": {"x": FLOATS32, "y": np.linspace(-3, 3, FLOATS32.size, dtype=np.float32) / 7},
    "ints and bools": {"i": np.arange(-3, 3) * 10**15, "b": np.array([True, False] * 3),
                       "u": np.arange(6, dtype=np.uint8)},
    "text": {"s": np.array(["plain", "a, comma", 'a "quote"', "line\nend", "", " spaced "]),
             "o": np.array(["x", None, np.nan, "y", "3", "z"], dtype=object)},
    "nullable ints": {"t": np.array([1, None, 3, None], dtype=object), "f": np.array([0.5, np.nan, 2.0, 3.0])},
    "random": {"a": np.random.default_rng(3).normal(0, 1e4, 500),
               "b": np.random.default_rng(4).uniform(-1, 1, 500) * 10.0 ** np.random.default_rng(5).integers(
                   -30, 30, 500)},
}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("float_format", [None, "%.2f", "%.10g"])
def test_csv_text_is_what_pandas_writes(name, float_format):
    columns = CASES[name]
    assert csv_text(columns, float_format) == _pandas(columns, float_format)


def test_empty_tables_are_their_header_line():
    columns = {"a": np.array([], dtype=object), "b": np.array([], dtype=float)}
    assert csv_text(columns) == "a,b\n" == pd.DataFrame(columns=["a", "b"]).to_csv(index=False)


def test_stacked_blocks_take_the_type_a_concatenation_gives():
    ints, floats = np.array([1, 2]), np.array([0.5, np.nan])
    blocks = [({"c": ints}, {"c": floats}), ({"c": np.array([True])}, {"c": np.array([False])}),
              ({"c": np.array(["ab"])}, {"c": np.array(["c, d"])}), ({"c": ints}, {"c": np.array(["x"])})]
    for a, b in blocks:
        ours = csv_text({"c": stack_column([a["c"], b["c"]])})
        ref = pd.concat([pd.DataFrame(a), pd.DataFrame(b)], ignore_index=True).to_csv(index=False)
        assert ours == ref


def test_written_atomically_with_the_same_bytes(tmp_path):
    path = write_columns_csv(CASES["text"], tmp_path / "t.csv")
    assert path.read_bytes() == _pandas(CASES["text"]).encode()
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
