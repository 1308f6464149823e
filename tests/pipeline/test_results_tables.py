"""The run's results tables (results.csv, results.parquet) written without pandas, and a
default-study case that never imports pandas (its import cost more than the tables)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.export.csv_columns import rows_to_columns
from preform.pipeline.rundir import parquet_table

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.floats(allow_nan=False, allow_infinity=False),
    st.text(max_size=5),
)


def kind_of(values):
    """The column kind written out by hand: the type every present value shares."""
    present = [v for v in values if v is not None]
    if all(type(v) is bool for v in present):
        return pa.bool_()
    if all(type(v) is int for v in present) and all(-(2**63) <= v < 2**63 for v in present):
        return pa.int64()
    if all(type(v) in (int, float) for v in present):
        return pa.float64()
    return pa.string()


@settings(max_examples=60, deadline=None)
@given(st.lists(st.dictionaries(st.sampled_from("abcde"), scalars, max_size=5), min_size=1))
def test_parquet_columns_keep_each_value_with_its_kind(tmp_path_factory, rows):
    columns = rows_to_columns(rows)
    path = tmp_path_factory.mktemp("pq") / "results.parquet"
    pq.write_table(parquet_table(columns), path)
    back = pq.read_table(path)
    assert back.column_names == list(columns)
    for name, values in columns.items():
        kind = kind_of(values)
        assert back.schema.field(name).type == kind, name
        got = back.column(name).to_pylist()
        if kind == pa.string():
            values = [None if v is None else str(v) for v in values]
        elif kind == pa.float64():
            values = [None if v is None else float(v) for v in values]
        assert got == values, name


def test_parquet_of_no_rows_is_an_empty_table():
    assert parquet_table({}).num_rows == 0


def test_pandas_reads_the_tables_a_run_writes(tmp_path):
    rows = [
        {"material": "a", "status": "ok", "search_drapes": 32, "energy_J": 0.5, "complete": True},
        {"material": "b", "status": "failed", "error": "boom, twice", "complete": None},
    ]
    columns = rows_to_columns(rows)
    pq.write_table(parquet_table(columns), tmp_path / "r.parquet")
    frame = pd.read_parquet(tmp_path / "r.parquet")
    assert frame["search_drapes"].iloc[0] == 32 and pd.isna(frame["search_drapes"].iloc[1])
    assert frame["error"].iloc[1] == "boom, twice"
    assert frame["complete"].iloc[0] == True  # noqa: E712 (a numpy/pandas bool)


def test_a_default_study_case_imports_no_pandas(tmp_path):
    """The default scene's outputs (figures, cells.csv, tables) need no pandas: a worker and the
    `preform` process would pay its import (~0.5 s with pyarrow's compute module) per run."""
    script = textwrap.dedent(
        f"""
        import sys
        from preform.cli import main
        sys.argv = ["preform", "pipeline", "run", "--out", {str(tmp_path / "out")!r},
                    "--engine", "serial", "--materials", "plain-weave-150"]
        try:
            main()
        except SystemExit as exc:
            assert not exc.code, exc.code
        print("PANDAS", "pandas" in sys.modules)
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "PANDAS False" in done.stdout, done.stdout
    assert (tmp_path / "out" / "results.csv").exists()
    assert (tmp_path / "out" / "hemisphere-min-energy" / "plain-weave-150" / "cells.csv").exists()
