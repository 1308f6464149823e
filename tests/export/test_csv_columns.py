"""The pandas-free CSV writer against pandas' own ``to_csv``: the same text, byte for byte
(an independent implementation: pandas formats and quotes on its own)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.export.csv_columns import (
    csv_text,
    format_column,
    rows_to_columns,
    write_csv_columns,
)
from preform.export.tables import cell_columns, cells_table, write_table

floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
# no "\r": the csv module (so pandas) leaves a lone "\r" unquoted, which readers take for a
# line end; ours quotes it (test_a_carriage_return_is_quoted_and_read_back)
texts = st.text(alphabet=st.sampled_from(list('ab ,"\n;xé')), max_size=6)


def pandas_text(frame: pd.DataFrame, tmp_path) -> str:
    write_table(frame, tmp_path / "pandas.csv")  # the pandas path preform writes other tables with
    return (tmp_path / "pandas.csv").read_text(encoding="utf-8")


def ours_text(columns, tmp_path) -> str:
    write_csv_columns(columns, tmp_path / "ours.csv")
    return (tmp_path / "ours.csv").read_text(encoding="utf-8")


@settings(max_examples=60, deadline=None)
@given(
    values=st.lists(floats, min_size=1, max_size=25),
    ints=st.data(),
)
def test_float_int_bool_and_text_columns_match_pandas(tmp_path_factory, values, ints):
    n = len(values)
    tmp_path = tmp_path_factory.mktemp("csv")
    x = np.array(values, dtype=float)
    i = np.array(ints.draw(st.lists(st.integers(-(2**62), 2**62), min_size=n, max_size=n)))
    b = np.array(ints.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    mask = np.array(ints.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    words = ints.draw(st.lists(texts, min_size=n, max_size=n))
    columns = {
        "x_mm": x,
        "i": i,
        "flag": b,
        "maybe": np.ma.MaskedArray(b, mask=mask),
        "words": words,
    }
    frame = pd.DataFrame(
        {
            "x_mm": x,
            "i": i,
            "flag": b,
            "maybe": pd.arrays.BooleanArray(b, mask),
            "words": pd.array(words, dtype="string"),
        }
    )
    assert ours_text(columns, tmp_path) == pandas_text(frame, tmp_path)


@pytest.mark.parametrize(
    "value, text",
    [
        (0.1, "0.1"),
        (1e-05, "1e-05"),
        (1e16, "1e+16"),
        (-0.0, "-0.0"),
        (math.inf, "inf"),
        (-math.inf, "-inf"),
        (math.nan, ""),
        (5e-324, "5e-324"),
        (1.7976931348623157e308, "1.7976931348623157e+308"),
    ],
)
def test_floats_are_shortest_round_trip_text(value, text):
    assert format_column(np.array([value])) == [text]
    if text:
        assert float(text) == value


@settings(max_examples=30, deadline=None)
@given(words=st.lists(st.one_of(st.none(), texts), min_size=1, max_size=6))
def test_a_lone_text_column_matches_pandas(tmp_path_factory, words):
    """One column: the csv module quotes a lone empty field (a blank line would be no row)."""
    tmp_path = tmp_path_factory.mktemp("csv")
    frame = pd.DataFrame({"name, quoted": pd.array(words, dtype="string")})
    assert ours_text({"name, quoted": words}, tmp_path) == pandas_text(frame, tmp_path)


def test_cells_csv_is_what_the_pandas_table_wrote(tmp_path, damaged_net, make_energy):
    """cells.csv written from the arrays is the same file the DataFrame path wrote."""
    energy = make_energy(damaged_net)
    for args in [(damaged_net, energy), (damaged_net,)]:
        columns = cell_columns(*args)
        assert ours_text(columns, tmp_path) == pandas_text(cells_table(*args), tmp_path)


def test_rows_with_mixed_and_missing_values(tmp_path):
    rows = [
        {"material": "a,b", "status": "ok", "search_drapes": 32, "energy_J": 0.5},
        {"material": 'say "x"', "status": "failed", "error": "boom\nline 2", "energy_J": None},
    ]
    columns = rows_to_columns(rows)
    assert list(columns) == ["material", "status", "search_drapes", "energy_J", "error"]
    text = ours_text(columns, tmp_path)
    assert text == (
        "material,status,search_drapes,energy_J,error\n"
        '"a,b",ok,32,0.5,\n'
        '"say ""x""",failed,,,"boom\nline 2"\n'
    )
    back = pd.read_csv(tmp_path / "ours.csv")
    assert back["search_drapes"].tolist()[0] == 32
    assert math.isnan(back["energy_J"][1]) and back["error"][1] == "boom\nline 2"


def test_a_carriage_return_is_quoted_and_read_back(tmp_path):
    columns = {"error": ["line 1\rline 2", "plain"], "n": np.array([1, 2])}
    write_csv_columns(columns, tmp_path / "t.csv")
    back = pd.read_csv(tmp_path / "t.csv")
    assert back["error"].tolist() == ["line 1\rline 2", "plain"]
    assert back["n"].tolist() == [1, 2]


def test_columns_of_different_lengths_are_refused():
    with pytest.raises(ValueError, match=r"one length.*a: 2, b: 3"):
        csv_text({"a": [1, 2], "b": [1, 2, 3]})


def test_a_failed_write_leaves_the_old_file(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("old\n")
    with pytest.raises(ValueError):
        write_csv_columns({"a": [1, 2], "b": [1]}, path)
    assert path.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def one_by_one(values: np.ndarray) -> list[str]:
    """A second implementation of a numeric column's fields: Python's own text of each value in
    turn (``repr`` of a float, '' for NaN, ``str`` of an int or bool), no sharing of texts."""
    out = []
    for v in values.tolist():
        if isinstance(v, float):
            out.append("" if math.isnan(v) else repr(v))
        else:
            out.append(str(v))
    return out


# the floats whose text is hard: signed zeros, subnormals, the extremes, NaN and infinities,
# values one ulp apart (their texts differ), repeated values and their negatives
edge_floats = st.sampled_from(
    [
        0.0,
        -0.0,
        5e-324,
        -5e-324,
        2.2250738585072014e-308,
        1.7976931348623157e308,
        1e16,
        9999999999999998.0,
        1e-5,
        0.0001,
        0.1,
        0.30000000000000004,
        math.inf,
        -math.inf,
        math.nan,
    ]
)


@settings(max_examples=200, deadline=None)
@given(
    values=st.lists(
        st.one_of(floats, edge_floats, st.floats(width=32), st.floats(-1e-300, 1e-300)),
        min_size=1,
        max_size=40,
    ),
    repeat=st.integers(1, 3),
    negate=st.booleans(),
)
def test_float_fields_are_each_values_own_text(values, repeat, negate):
    """Each distinct value formatted once and gathered (``distinct_fields``) gives, field by
    field, what formatting every value on its own gives; with repeats and negatives mixed in,
    the sharing the gather does."""
    x = np.array(values * repeat, dtype=float)
    if negate:
        x = np.concatenate([x, -x[::2]])
    fields = format_column(x)
    assert fields == one_by_one(x)
    # the round trip is exact: each text reads back as the value's bits (NaN: empty)
    for field, v in zip(fields, x.tolist(), strict=True):
        if field:
            assert np.float64(float(field)).view(np.uint64) == np.float64(v).view(np.uint64)


@settings(max_examples=100, deadline=None)
@given(
    ints=st.lists(st.integers(-(2**63), 2**63 - 1), min_size=1, max_size=30),
    flags=st.data(),
)
def test_integer_bool_and_masked_fields_are_each_values_own_text(ints, flags):
    i = np.array(ints, dtype=np.int64)
    b = np.array(flags.draw(st.lists(st.booleans(), min_size=len(ints), max_size=len(ints))))
    mask = np.array(flags.draw(st.lists(st.booleans(), min_size=len(ints), max_size=len(ints))))
    assert format_column(i) == one_by_one(i)
    assert format_column(i.astype(np.uint8)) == one_by_one(i.astype(np.uint8))
    assert format_column(b) == one_by_one(b)
    expected = ["" if m else t for t, m in zip(one_by_one(b), mask.tolist(), strict=True)]
    assert format_column(np.ma.MaskedArray(b, mask=mask)) == expected
    x = np.ma.MaskedArray(i.astype(float), mask=mask)
    expected = ["" if m else t for t, m in zip(one_by_one(i.astype(float)), mask, strict=True)]
    assert format_column(x) == expected
