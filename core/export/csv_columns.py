"""CSV from columns, without pandas: the per-case cells.csv and the run's results.csv.

A run writes these tables for every case and after every case, and importing pandas costs a
worker (and the ``preform`` process) more than writing them: pandas 3 imports pyarrow's compute
module when pyarrow is installed, about 0.5 s. The text is what ``DataFrame.to_csv(index=False)``
writes for the same values: floats as Python's shortest round-trip ``repr`` (``0.1``, ``1e-05``,
``inf``), integers and booleans as Python prints them, a missing value (None, NaN, a masked
entry) as an empty field, quoting by the csv module's minimal rule (the module pandas uses).
Kept to that on purpose: readers, and earlier results, parse the same text.

Two differences: a column of integers with a missing value keeps its integers (``32``; pandas
turns such a column into floats, ``32.0``; both read back as the same numbers), and a field
holding a carriage return is quoted (the csv module leaves a lone "\\r" bare when lines end
in "\\n", and readers then split the row there).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from preform.base.atomic import atomic_open

#: A column: a numpy array (float, integer or bool), a numpy masked array (masked entries are
#: missing: a nullable column), or a sequence of Python scalars (str, int, float, bool, None).
Column = np.ndarray | np.ma.MaskedArray | Sequence[Any]


def format_value(value: Any) -> str:
    """One field's text: '' for a missing value (None, NaN), ``repr`` for a float, ``str``
    for anything else (numpy scalars as their Python value)."""
    if value is None:
        return ""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return str(value)


def format_column(values: Column) -> list[str]:
    """The fields of one column, in order (module docstring)."""
    if isinstance(values, np.ma.MaskedArray):
        missing = np.ma.getmaskarray(values).ravel()
        fields = format_column(np.ma.getdata(values).ravel())
        for k in np.flatnonzero(missing).tolist():
            fields[k] = ""
        return fields
    if isinstance(values, np.ndarray):
        flat = values.ravel()
        kind = flat.dtype.kind
        if kind == "f":
            # float64's repr is Python's shortest round-trip text, as pandas writes it;
            # tolist() gives Python floats, so the work is one C-level repr a value
            present = ~np.isnan(flat)
            text = np.full(flat.size, "", dtype=object)
            text[present] = list(map(repr, flat[present].astype(np.float64, copy=False).tolist()))
            return list(text.tolist())
        if kind in "iub":
            return list(map(str, flat.tolist()))
        return [format_value(v) for v in flat.tolist()]
    return [format_value(v) for v in values]


def quoted(field: str) -> str:
    """``field`` as the csv module's minimal quoting writes it: in double quotes, its quotes
    doubled, when it holds a comma, a quote or a line break ("\\r" too: module docstring)."""
    if "," in field or '"' in field or "\n" in field or "\r" in field:
        return '"' + field.replace('"', '""') + '"'
    return field


def csv_text(columns: Mapping[str, Column]) -> str:
    """The CSV text of ``columns`` (all of one length): a header, then one line a row.

    Joined here rather than by ``csv.writer`` (4x slower on a cells table): only text columns
    can need quotes, so only they go through ``quoted``."""
    fields = []
    for values in columns.values():
        column = format_column(values)
        numeric = isinstance(values, np.ndarray) and values.dtype.kind in "fiub"
        fields.append(column if numeric else [quoted(f) for f in column])
    lengths = {len(f) for f in fields}
    if len(lengths) > 1:
        sizes = ", ".join(f"{name}: {len(f)}" for name, f in zip(columns, fields, strict=True))
        raise ValueError(f"the columns of a table must have one length; got {sizes}")
    header = ",".join(quoted(str(name)) for name in columns)
    if len(fields) == 1:  # the csv module writes a lone empty field as "" (else a blank line)
        fields = [['""' if f == "" else f for f in fields[0]]]
        header = header or '""'
    lines = [header, *map(",".join, zip(*fields, strict=True))]
    return "\n".join(lines) + "\n"


def write_csv_columns(columns: Mapping[str, Column], path: str | os.PathLike[str]) -> None:
    """Write ``columns`` (name -> values, in column order) to ``path`` as CSV with a header,
    atomically (a reader never sees half a file), "\\n" line ends."""
    text = csv_text(columns)
    with atomic_open(path, "w", encoding="utf-8") as handle:
        handle.write(text)


def rows_to_columns(rows: Sequence[Mapping[str, Any]]) -> dict[str, list[Any]]:
    """Columns from row records: every key any row has, in order of first appearance (as
    ``pandas.DataFrame(rows)`` orders them); None where a row lacks the key."""
    names: dict[str, None] = {}
    for row in rows:
        names.update(dict.fromkeys(row))
    return {name: [row.get(name) for row in rows] for name in names}
