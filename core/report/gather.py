"""What a run folder holds, read for the report: the run, every case's row and record, and the
files a page can show (pictures, the draped net, shear curves).

Reads only the folder (``manifest.json``, ``results.csv``, each case's ``summary.json`` and the
files it lists), so ``preform report DIR`` rebuilds the page the run wrote. A file that is
missing or unreadable is not an error of the report: the case says what is missing, in words.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from preform.base.status import REUSABLE, CaseStatus
from preform.pipeline.rundir import read_json

#: The order cases are shown in: what needs reading first (no result, then an incomplete one).
STATUS_ORDER: tuple[str, ...] = (
    CaseStatus.FAILED.value,
    CaseStatus.TIMED_OUT.value,
    CaseStatus.INTERRUPTED.value,
    CaseStatus.PARTIAL.value,
    CaseStatus.PENDING.value,
    CaseStatus.OK.value,
)
#: Pictures a case may hold that the page shows inline, by file name: (caption, MIME type).
PICTURES: dict[str, tuple[str, str]] = {
    "fibre_pattern.png": ("fibre pattern (top view with tows, 3-D view by shear)", "image/png"),
    "cut_pattern.svg": ("cut pattern (mm; seam allowance, fibre marks)", "image/svg+xml"),
    "flat_pattern.svg": ("flat pattern (mm)", "image/svg+xml"),
    "unit_cell.png": ("unit cell", "image/png"),
}
#: A picture larger than this is linked, not embedded, so one huge file cannot bloat the page
#: [bytes].
PICTURE_MAX_BYTES = 3_000_000
#: Cells of a draped net the 3-D view keeps at most: the net is thinned to every k-th cell in
#: both fibre directions until it fits. About 4 000 cells of a 10-case report add some 2 MB.
NET_MAX_CELLS = 4000
#: Marked cells (wrinkle, fold, past a limit) of one net at most.
MARKS_MAX = 2000
#: From this many cases on, the cells tables are parsed by pandas' C reader: a default-study
#: cells.csv (20 736 rows) takes ~17 ms there against ~120 ms by the csv module, for pandas'
#: import, ~0.4 s once (measured 2026-12-03 on the two-core machine; benchmarks/README.md,
#: section (r)). Below it the csv module, so a one-case run does not pay the import.
PANDAS_FROM_CASES = 4


def status_rank(status: str) -> int:
    """Where a status sorts: failed first, ok last, an unknown word just before ok."""
    return STATUS_ORDER.index(status) if status in STATUS_ORDER else len(STATUS_ORDER) - 1


@dataclass
class Net:
    """A draped net thinned for the 3-D view, from cells.csv's cell centres [mm].

    ``triangles`` join the centres of neighbouring kept cells (each quad of the thinned grid in
    two), so the surface runs through the cell centres, half a cell inside the net's edge.
    """

    x_mm: list[float]
    y_mm: list[float]
    z_mm: list[float]
    shear_deg: list[float]
    #: Vertex indices [a, b, c] of each triangle.
    triangles: list[list[int]]
    #: Every k-th cell kept in each fibre direction.
    stride: int
    cells_total: int
    #: Cells past a limit of the fabric or folded: x, y, z [mm] and why, in words.
    marks: list[tuple[float, float, float, str]] = field(default_factory=list)
    marks_total: int = 0


@dataclass
class CaseData:
    case_id: str
    scene: str
    material: str
    status: str
    #: The case's folder, relative to the run folder ('' when the folder is unknown).
    folder: str
    #: results.csv's row, as the text in the file.
    row: dict[str, str]
    #: summary.json (empty when missing).
    summary: dict[str, Any]
    error: str
    reasons: list[str]
    warnings: list[str]
    files: list[str]
    #: (file name, caption, MIME type, bytes) of the pictures to embed.
    pictures: list[tuple[str, str, str, bytes]] = field(default_factory=list)
    net: Net | None = None
    #: Why there is no 3-D view, in words (when ``net`` is None).
    net_note: str = ""
    shear_curve: dict[str, Any] | None = None
    #: Things the page could not read, in words.
    problems: list[str] = field(default_factory=list)


@dataclass
class Run:
    name: str
    manifest: dict[str, Any]
    #: The last run recorded in the manifest (settings, inputs, plugins, times, counts).
    last_run: dict[str, Any]
    columns: list[str]
    cases: list[CaseData]
    #: preform bench tradeoff's table when the folder holds one: its columns and rows (text).
    tradeoff: tuple[list[str], list[dict[str, str]]] | None = None
    problems: list[str] = field(default_factory=list)

    def counts(self) -> dict[str, int]:
        """Cases in the folder by status."""
        out: dict[str, int] = {}
        for case in self.cases:
            out[case.status] = out.get(case.status, 0) + 1
        return dict(sorted(out.items(), key=lambda kv: status_rank(kv[0])))

    def scenes(self) -> list[str]:
        return sorted({c.scene for c in self.cases})


def read_table(path: Path) -> tuple[list[str], list[dict[str, str]]] | None:
    """A CSV file's header and rows as text, or None when it is missing or unreadable."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            rows = [dict(r) for r in reader]
            return list(reader.fieldnames or []), rows
    except (OSError, csv.Error, UnicodeDecodeError):
        return None


def _strings(value: Any) -> list[str]:
    return [str(v) for v in value] if isinstance(value, list) else []


def csv_columns(
    path: Path, numbers: set[str], texts: set[str], by_pandas: bool = False
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Of a CSV file's columns, those named in ``numbers`` as floats (an empty field NaN) and
    those in ``texts`` as text; only the ones the file has. Parsed by the csv module, or with
    ``by_pandas`` by pandas' C reader (``PANDAS_FROM_CASES``), to the same arrays. Raises
    OSError, ValueError (a field that is not a number) or UnicodeDecodeError."""
    if by_pandas:
        import pandas as pd

        if path.stat().st_size == 0:  # no header: no column, as the csv module reads it
            return {}, {}
        frame = pd.read_csv(
            path,
            usecols=lambda name: name in numbers or name in texts,
            dtype=dict.fromkeys(texts, str),
            keep_default_na=False,  # only an empty number is missing; a text stays as written
            na_values={name: [""] for name in numbers},
            encoding="utf-8",
        )
        for name in numbers.intersection(frame.columns):
            if frame[name].dtype.kind == "b":  # pandas reads True/False as numbers; we do not
                raise ValueError(f"{path.name}: column {name} holds True/False, not numbers")
        return (
            {n: frame[n].to_numpy(dtype=float) for n in frame.columns if n in numbers},
            {n: frame[n].to_numpy(dtype=str) for n in frame.columns if n in texts},
        )
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = next(reader, [])
        columns = list(zip(*reader, strict=False)) or [() for _ in header]
    nan = float("nan")
    found_numbers = {
        name: np.array([float(v) if v else nan for v in columns[k]], dtype=float)
        for k, name in enumerate(header)
        if name in numbers and k < len(columns)
    }
    found_texts = {
        name: np.array(columns[k], dtype=str)
        for k, name in enumerate(header)
        if name in texts and k < len(columns)
    }
    return found_numbers, found_texts


def read_net(path: Path, by_pandas: bool = False) -> tuple[Net | None, str]:
    """The draped net of a case's cells.csv, thinned to at most ``NET_MAX_CELLS`` cells; or
    None and why (``by_pandas``: ``csv_columns``)."""
    needed = ("i", "j", "x_mm", "y_mm", "z_mm", "shear_deg")
    flags = {"wrinkling": "wrinkling", "past_jamming": "past jamming"}
    flags["past_failure"] = "past stitch failure"
    try:
        numbers, table = csv_columns(path, set(needed), {*flags, "status"}, by_pandas)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        return None, f"{path.name} could not be read ({type(exc).__name__})"
    missing = [k for k in needed if k not in numbers]
    if missing:
        return None, f"{path.name} lacks the columns {', '.join(missing)}"
    i, j, x, y, z, g = (numbers[k] for k in needed)
    placed = np.isfinite(i) & np.isfinite(j) & np.isfinite(x) & np.isfinite(y)
    placed &= np.isfinite(z) & np.isfinite(g) & (i >= 0) & (j >= 0)
    if not placed.any():
        return None, f"{path.name} holds no placed cell"
    labels: list[np.ndarray] = []
    names: list[str] = []
    if "status" in table:
        labels.append(table["status"] == "FOLDED")
        names.append("folded")
    for key, label in flags.items():
        if key in table:
            labels.append(table[key] == "True")
            names.append(label)
    hits = np.stack(labels, axis=1) if labels else np.zeros((len(i), 0), dtype=bool)
    why = np.full(len(i), "", dtype=object)
    for k in np.flatnonzero(hits.any(axis=1)):  # few: the cells past a limit
        why[k] = ", ".join(n for n, hit in zip(names, hits[k], strict=True) if hit)
    ii, jj = i[placed].astype(np.int64), j[placed].astype(np.int64)
    total = int(placed.sum())
    stride = max(1, math.ceil(math.sqrt(total / NET_MAX_CELLS)))
    kept = (ii % stride == 0) & (jj % stride == 0)
    # the kept cells on a grid of their own, in (i, j) order: -1 where no cell is kept
    order = np.lexsort((jj[kept], ii[kept]))
    gi, gj = ii[kept][order] // stride, jj[kept][order] // stride
    grid = np.full((int(gi.max()) + 2, int(gj.max()) + 2), -1, dtype=np.int64)
    grid[gi, gj] = np.arange(len(gi))
    a, b = grid[:-1, :-1], grid[1:, :-1]
    c, d = grid[1:, 1:], grid[:-1, 1:]
    # each quad of kept cells in two triangles; a quad missing its far corner keeps one
    tris = [
        np.stack([a, b, c], axis=-1)[(a >= 0) & (b >= 0) & (c >= 0)],
        np.stack([a, c, d], axis=-1)[(a >= 0) & (c >= 0) & (d >= 0)],
        np.stack([a, b, d], axis=-1)[(a >= 0) & (b >= 0) & (d >= 0) & (c < 0)],
    ]
    triangles = np.concatenate(tris).tolist()

    def rounded(values: np.ndarray) -> list[float]:
        return [float(v) for v in np.round(values[placed][kept][order], 2)]

    flagged = np.flatnonzero(placed & (why != ""))
    step = max(1, math.ceil(len(flagged) / MARKS_MAX))
    marks = [
        (round(float(x[k]), 2), round(float(y[k]), 2), round(float(z[k]), 2), str(why[k]))
        for k in flagged[::step]
    ]
    net = Net(
        rounded(x), rounded(y), rounded(z), rounded(g), triangles, stride, total, marks,
        len(flagged),
    )  # fmt: skip
    return net, ""


def _case_folder(record: dict[str, Any], manifest_cases: dict[str, Any], case_id: str) -> str:
    entry = manifest_cases.get(case_id)
    if isinstance(entry, dict) and isinstance(entry.get("case_dir"), str):
        return str(entry["case_dir"])
    from preform.pipeline.runner import folder_name

    return f"{folder_name(str(record.get('scene')))}/{folder_name(str(record.get('material')))}"


def _inside(root: Path, relative: str) -> Path | None:
    """``root / relative`` when it stays inside ``root`` (a record's file list is data)."""
    path = (root / relative).resolve()
    try:
        path.relative_to(root.resolve())
    except ValueError:
        return None
    return path


def read_case(
    root: Path, row: dict[str, str], manifest_cases: dict[str, Any], by_pandas: bool = False
) -> CaseData:
    case_id = f"{row.get('scene', '')}/{row.get('material', '')}"
    folder = _case_folder(row, manifest_cases, case_id)
    case_dir = _inside(root, folder) if folder else None
    summary = read_json(case_dir / "summary.json") if case_dir else None
    problems = []
    if not isinstance(summary, dict):
        problems.append(f"{folder}/summary.json is missing or unreadable")
        summary = {}
    case = CaseData(
        case_id=case_id,
        scene=row.get("scene", ""),
        material=row.get("material", ""),
        status=row.get("status", "") or "unknown",
        folder=folder,
        row=row,
        summary=summary,
        error=row.get("error", ""),
        reasons=_strings(summary.get("reasons"))
        or [r for r in row.get("reasons", "").split("; ") if r],
        warnings=_strings(summary.get("warnings"))
        or [w for w in row.get("warnings", "").split("; ") if w],
        files=_strings(summary.get("files")),
        problems=problems,
    )
    if case_dir is None:
        return case
    for name in case.files:
        path = _inside(case_dir, name)
        if path is None:
            continue
        if name in PICTURES:
            caption, mime = PICTURES[name]
            try:
                size = path.stat().st_size
                if size <= PICTURE_MAX_BYTES:
                    case.pictures.append((name, caption, mime, path.read_bytes()))
            except OSError:
                case.problems.append(f"{name} is listed but cannot be read")
        elif name == "shear_curve.json":
            curve = read_json(path)
            if isinstance(curve, dict):
                case.shear_curve = curve
            else:
                case.problems.append(f"{name} is missing or unreadable")
    if "cells.csv" in case.files:
        case.net, case.net_note = read_net(case_dir / "cells.csv", by_pandas)
    else:
        case.net_note = (
            "no 3-D view: the scene did not ask for cells.csv (output cells_csv)"
            if case.status in REUSABLE
            else f"no 3-D view: the case ended {case.status} without a drape"
        )
    return case


def _pending_cases(manifest_cases: dict[str, Any], known: set[str]) -> list[CaseData]:
    """Cases the manifest names that have no row yet (a run still going, or one that died)."""
    out = []
    for case_id, entry in sorted(manifest_cases.items()):
        if case_id in known or not isinstance(entry, dict):
            continue
        scene, _, material = case_id.partition("/")
        out.append(
            CaseData(
                case_id=case_id,
                scene=scene,
                material=material,
                status=str(entry.get("status") or CaseStatus.PENDING.value),
                folder=str(entry.get("case_dir") or ""),
                row={},
                summary={},
                error=str(entry.get("error") or ""),
                reasons=_strings(entry.get("reasons")),
                warnings=_strings(entry.get("warnings")),
                files=[],
            )
        )
    return out


def read_run(root: Path) -> Run:
    """Everything the report shows of the run folder ``root``, cases failed first."""
    root = Path(root)
    problems = []
    manifest = read_json(root / "manifest.json")
    if not isinstance(manifest, dict):
        problems.append("manifest.json is missing or unreadable: the run's settings are unknown")
        manifest = {}
    runs = manifest.get("runs")
    last_run = runs[-1] if isinstance(runs, list) and runs and isinstance(runs[-1], dict) else {}
    manifest_cases = manifest.get("cases") if isinstance(manifest.get("cases"), dict) else {}
    assert isinstance(manifest_cases, dict)
    table = read_table(root / "results.csv")
    if table is None:
        problems.append("results.csv is missing or unreadable: no case can be shown")
        table = ([], [])
    columns, rows = table
    by_pandas = len(rows) >= PANDAS_FROM_CASES
    cases = [read_case(root, row, manifest_cases, by_pandas) for row in rows]
    cases += _pending_cases(manifest_cases, {c.case_id for c in cases})
    cases.sort(key=lambda c: (status_rank(c.status), c.case_id))
    tradeoff = read_table(root / "tradeoff.csv")
    return Run(root.resolve().name, manifest, last_run, columns, cases, tradeoff, problems)


#: Numbers, with their sign, decimals and exponent, in a warning's words.
_NUMBER = re.compile(r"[-−+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def cause_of(text: str) -> str:
    """A warning's cause: its words up to the first colon or parenthesis, numbers as '#', so
    the same warning of many cases (with their own numbers) groups under one heading."""
    head = re.split(r"[:(]", text, maxsplit=1)[0]
    head = _NUMBER.sub("#", head)
    head = re.sub(r"#°?(?:, #°?)+(?: and # more)?", "#…", head)
    return re.sub(r"\s+", " ", head).strip(" ,;")


def warnings_by_cause(cases: list[CaseData]) -> dict[str, list[tuple[str, str]]]:
    """(case id, warning) of every case grouped by ``cause_of``, causes by how many cases
    they touch, then alphabetically."""
    groups: dict[str, list[tuple[str, str]]] = {}
    for case in cases:
        for warning in case.warnings:
            groups.setdefault(cause_of(warning), []).append((case.case_id, warning))
    return dict(sorted(groups.items(), key=lambda kv: (-len(kv[1]), kv[0])))
