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
