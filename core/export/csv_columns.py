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

Fast because each distinct number is formatted once (``distinct_fields``): the text is still
Python's own, value by value, so the file is byte for byte what formatting every field would
write (tests/export/test_csv_columns.py checks it against that, hypothesis-drawn).
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


def distinct_fields(flat: np.ndarray) -> np.ndarray:
    """The fields of a 1-D numeric array (float, integer or bool) as an object array of str:
    each distinct value formatted once (``repr`` of a float, ``str`` of an integer or bool, as
    Python prints them) and gathered by numpy, a NaN as ''.

    A cells table repeats most of its values (a symmetric drape, a uniform thickness, 0 and 1
    shares, integer indices), and Python's float formatting is the costly part of writing it:
    formatted once a value it is not repeated. Floats are told apart by their bits, so ``-0.0``
    keeps its sign and no two values that print differently share a text."""
    if flat.dtype.kind == "f":
        values = flat.astype(np.float64, copy=False)
        present = ~np.isnan(values)
        bits = values[present].view(np.uint64)
        # a value and its negative share a text but for the sign (Python writes the sign
        # first, ``repr(-x) == "-" + repr(x)``, -0.0 and -inf too): formatted once for both,
        # which halves the work on a tool symmetric about an axis
        negative = bits >> np.uint64(63)
        distinct, where = np.unique(bits & ~(np.uint64(1) << np.uint64(63)), return_inverse=True)
        n = distinct.size
        text = np.empty(2 * n + 1, dtype=object)  # [+x …, -x …, '' for NaN]
        text[:n] = list(map(repr, distinct.view(np.float64).tolist()))
        text[n : 2 * n] = ["-" + t for t in text[:n].tolist()]
        text[-1] = ""
        index = np.full(values.size, 2 * n, dtype=np.intp)
        index[present] = where + n * negative.astype(np.intp)
        return text[index]
    distinct, where = np.unique(flat, return_inverse=True)
    text = np.empty(distinct.size, dtype=object)
    text[:] = list(map(str, distinct.tolist()))
    return text[where.ravel()]


def format_column(values: Column) -> list[str]:
    """The fields of one column, in order (module docstring)."""
    if isinstance(values, np.ma.MaskedArray):
        missing = np.ma.getmaskarray(values).ravel()
        data = np.ma.getdata(values).ravel()
        if data.dtype.kind not in "fiub":
            fields = format_column(data)
            for k in np.flatnonzero(missing).tolist():
                fields[k] = ""
            return fields
        text = distinct_fields(data)
        text[missing] = ""
        return list(text.tolist())
    if isinstance(values, np.ndarray):
        flat = values.ravel()
        if flat.dtype.kind in "fiub":
            return list(distinct_fields(flat).tolist())
        return [format_value(v) for v in flat.tolist()]
    if all(type(v) is str for v in values):  # a text column: its fields already
        return list(values)
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
        if not numeric:  # quoted once a distinct text (a status column repeats a few)
            once = {f: quoted(f) for f in set(column)}
            column = list(map(once.__getitem__, column))
        fields.append(column)
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
