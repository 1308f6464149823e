"""A results directory: its lock, its manifest and its tables, which describe every case in it.

Layout::

    .preform.lock        held (flock) by the one run writing here; refused to a second run
    manifest.json        every case in the directory (status, folder, input hash, reasons),
                         and a record of each run (settings, inputs, plugins, counts)
    results.csv          one row per case in the directory (results.parquet with pyarrow)
    report.html          the whole folder on one page, written at a run's end (preform.report)
    <scene>/<material>/  summary.json (the case's own record) and the files its scene asked for

A case's ``summary.json`` is its record; the manifest and the tables are rebuilt from the
records, so runs with other scenes or other ``--materials`` into the same directory add to them
instead of replacing them, and a run that died leaves records the next run picks up.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import time
from collections.abc import Iterable, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from preform.base.atomic import atomic_open, atomic_path, remove_stale_temporaries
from preform.base.status import CaseStatus
from preform.base.strict_json import clean_json

LOCK_NAME = ".preform.lock"
MANIFEST = "manifest.json"
#: Runs remembered in the manifest's ``runs`` list (the oldest are dropped).
RUNS_KEPT = 100
#: Least time between two rewrites of the tables while a run goes on [s], once the directory
#: holds more than ``TABLE_EVERY_CASE`` cases (below that they are rewritten after every case,
#: so a run that dies leaves current tables); they are always written at a run's end.
TABLE_INTERVAL_S = 2.0
TABLE_EVERY_CASE = 200

#: Keys of summary.json that describe the case rather than its results.
RECORD_KEYS = (
    "case_id",
    "material",
    "scene",
    "status",
    "error",
    "reasons",
    "warnings",
    "input_hash",
    "finished",
    "wall_time_s",
    "step_times_s",
    "files",
    "run_id",
)


class RunDirectoryError(Exception):
    """The results directory cannot be used (a file, locked by another run, not writable)."""


def _json_default(obj: Any) -> Any:
    if hasattr(obj, "item"):
        return obj.item()
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def write_json(path: Path, obj: Any) -> None:
    """Write strict JSON atomically."""
    with atomic_open(path) as f:
        json.dump(clean_json(obj), f, indent=2, sort_keys=True, default=_json_default)
        f.write("\n")


def read_json(path: Path) -> Any:
    """The JSON in ``path``, or None when it is missing or not JSON."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def now_utc() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def record_case_id(record: Mapping[str, Any]) -> str | None:
    """The case a summary.json belongs to (older summaries lack ``case_id``)."""
    if isinstance(record.get("case_id"), str):
        return str(record["case_id"])
    if isinstance(record.get("scene"), str) and isinstance(record.get("material"), str):
        return f"{record['scene']}/{record['material']}"
    return None


def table_row(record: Mapping[str, Any]) -> dict[str, Any]:
    """One row of results.csv from a case's summary.json: identity, status and reasons in
    words, step times, and the scalar results."""
    row: dict[str, Any] = {
        "material": record.get("material"),
        "scene": record.get("scene"),
        "status": record.get("status"),
        "error": record.get("error") or "",
        "reasons": "; ".join(record.get("reasons") or []),
        "warnings": "; ".join(record.get("warnings") or []),
        "finished": record.get("finished") or "",
        "wall_time_s": record.get("wall_time_s"),
    }
    for step, seconds in (record.get("step_times_s") or {}).items():
        row[f"time_{step}_s"] = seconds
    for key, value in record.items():
        if key in RECORD_KEYS or key in row:
            continue
        if isinstance(value, bool | int | float | str) or value is None:
            row[key] = value
    return row


def parquet_table(columns: Mapping[str, list[Any]]) -> Any:
    """results.parquet's table (pyarrow) from the table's columns: each column booleans,
    integers (nullable int64), numbers (float64) or text by what its values are; a column that
    mixes kinds (a number in one case, text in another), holds a non-finite number or
    overflows int64 becomes text, which every value can be. None is missing.

    Read through pyarrow's JSON reader with the schema given: building arrays from Python
    values (``pyarrow.array``) imports pandas, which this process otherwise never needs."""
    import io

    import pyarrow
    import pyarrow.json

    fields = []
    values_by_name: dict[str, list[Any]] = {}
    for name, values in columns.items():
        present = [v for v in values if v is not None]
        kinds = {type(v) for v in present}
        kind: Any = pyarrow.string()
        if kinds <= {bool}:
            kind = pyarrow.bool_()
        elif kinds <= {int} and all(-(2**63) <= v < 2**63 for v in present):
            kind = pyarrow.int64()
        elif kinds <= {int, float} and all(math.isfinite(v) for v in present):
            kind = pyarrow.float64()
        if kind == pyarrow.string():
            values = [None if v is None else str(v) for v in values]
        fields.append(pyarrow.field(name, kind))
        values_by_name[name] = values
    names = list(values_by_name)
    if not names or not columns[names[0]]:
        return pyarrow.schema(fields).empty_table()
    lines = (
        json.dumps(dict(zip(names, row, strict=True)), allow_nan=False)
        for row in zip(*values_by_name.values(), strict=True)
    )
    text = "\n".join(lines).encode("utf-8")
    options = pyarrow.json.ParseOptions(explicit_schema=pyarrow.schema(fields))
    return pyarrow.json.read_json(io.BytesIO(text), parse_options=options)


class RunDirectory:
    """Hold a results directory for one run: lock, stale temporaries, manifest and tables.

    Use as a context manager; entering refuses a path that is a file or a directory another
    run holds, and removes the temporary files that killed writers left (only preform's own,
    and only those no live process holds, whether it took the run lock or not).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._lock_fd: int | None = None
        #: summary.json records of every case in the directory, by case id.
        self.records: dict[str, dict[str, Any]] = {}
        #: The manifest's view of every case, by case id.
        self.cases: dict[str, dict[str, Any]] = {}
        self.runs: list[dict[str, Any]] = []
        self._tables_written_at = 0.0

    # -- holding the directory --------------------------------------------------------------
    def __enter__(self) -> RunDirectory:
        if self.path.exists() and not self.path.is_dir():
            raise RunDirectoryError(
                f"--out {self.path} is a file, not a directory; give a directory for the results"
            )
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RunDirectoryError(
                f"cannot create the results directory {self.path}: {exc.strerror or exc}"
            ) from None
        self._lock()
        try:
            remove_stale_temporaries(self.path)
            self._load()
        except BaseException:
            self._unlock()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        try:
            # a worker stopped mid-write (interrupt, time limit) leaves its temporary file; a
            # live writer's (a `preform export` beside the run, which takes no run lock) is
            # locked by it and kept (preform.base.atomic)
            remove_stale_temporaries(self.path)
        finally:
            self._unlock()

    def _lock(self) -> None:
        import fcntl

        lock_path = self.path / LOCK_NAME
        try:
            fd = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise RunDirectoryError(
                f"cannot write into the results directory {self.path}: {exc.strerror or exc}"
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = ""
            with contextlib.suppress(OSError):
                holder = os.read(fd, 200).decode(errors="replace").strip()
            os.close(fd)
            if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise RunDirectoryError(
                    f"another preform run is writing into {self.path} ({holder or 'unknown'}); "
                    "wait for it to finish, or give another --out"
                ) from None
            raise RunDirectoryError(f"cannot lock {lock_path}: {exc.strerror or exc}") from None
        # the lock is the flock; the text only tells a refused run who holds it
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()}, since {now_utc()}\n".encode())
        self._lock_fd = fd

    def _unlock(self) -> None:
        if self._lock_fd is not None:
            os.close(self._lock_fd)  # releases the flock
            self._lock_fd = None

    # -- what is in it ----------------------------------------------------------------------
    def _load(self) -> None:
        manifest = read_json(self.path / MANIFEST)
        if manifest is not None and not isinstance(manifest, dict):
            manifest = None
        if manifest is None and (self.path / MANIFEST).exists():
            # unreadable (a foreign file, or hand-edited): keep it for the user, start anew
            aside = self.path / f"manifest.unreadable-{int(time.time())}.json"
            os.replace(self.path / MANIFEST, aside)
        if manifest:
            cases = manifest.get("cases")
            self.cases = dict(cases) if isinstance(cases, dict) else {}
            runs = manifest.get("runs")
            self.runs = list(runs) if isinstance(runs, list) else []
        for summary_path in sorted(self.path.glob("*/*/summary.json")):
            record = read_json(summary_path)
            if not isinstance(record, dict):
                continue
            case_id = record_case_id(record)
            if case_id is None:
                continue
            folder = str(summary_path.parent.relative_to(self.path))
            known = self.cases.get(case_id, {}).get("case_dir")
            if known not in (None, folder):
                continue  # a stale folder of a case that now lives elsewhere
            self.records[case_id] = {**record, "case_id": case_id}
            self.cases.setdefault(case_id, {})["case_dir"] = folder
            self.cases[case_id].update(self._manifest_entry(record))
        # cases the manifest names whose folder (or record) is gone are not in the directory
        for case_id in [c for c in self.cases if c not in self.records]:
            entry = self.cases[case_id]
            if entry.get("status") != CaseStatus.PENDING:
                del self.cases[case_id]

    @staticmethod
    def _manifest_entry(record: Mapping[str, Any]) -> dict[str, Any]:
        return {
            "status": record.get("status"),
            "error": record.get("error"),
            "reasons": list(record.get("reasons") or []),
            "warnings": list(record.get("warnings") or []),
            "input_hash": record.get("input_hash"),
            "finished": record.get("finished"),
            "wall_time_s": record.get("wall_time_s"),
        }

    # -- recording ----------------------------------------------------------------------------
    def expect(self, case_id: str, case_dir: Path, input_hash: str) -> None:
        """A case of this run; ``pending`` until it is recorded (unless a record is kept)."""
        entry = self.cases.setdefault(case_id, {})
        entry["case_dir"] = str(case_dir.relative_to(self.path))
        if case_id not in self.records or entry.get("input_hash") != input_hash:
            entry.update({"status": CaseStatus.PENDING.value, "input_hash": input_hash})

    def record(self, record: dict[str, Any], case_dir: Path) -> None:
        """A case's summary.json record (already written), into the manifest and tables."""
        case_id = record_case_id(record)
        assert case_id is not None
        self.records[case_id] = record
        entry = self.cases.setdefault(case_id, {})
        entry["case_dir"] = str(case_dir.relative_to(self.path))
        entry.update(self._manifest_entry(record))

    def write_manifest(self, run: dict[str, Any] | None = None) -> None:
        """The manifest: every case in the directory and the runs (``run`` is the current one,
        whose settings are also repeated at the top level)."""
        runs = [r for r in self.runs if run is None or r.get("id") != run.get("id")]
        if run is not None:
            runs.append(run)
        runs = runs[-RUNS_KEPT:]
        manifest: dict[str, Any] = {"cases": dict(sorted(self.cases.items())), "runs": runs}
        if run is not None:
            manifest.update(
                {k: v for k, v in run.items() if k not in ("id", "cases", "counts", "status")}
            )
        write_json(self.path / MANIFEST, manifest)

    def write_tables(self, *, force: bool = True) -> None:
        """results.csv (and results.parquet with pyarrow): one row per case in the directory,
        sorted by case id. Without ``force``, a large directory's tables are rewritten at most
        every ``TABLE_INTERVAL_S``."""
        now = time.monotonic()
        throttled = len(self.records) > TABLE_EVERY_CASE
        if not force and throttled and now - self._tables_written_at < TABLE_INTERVAL_S:
            return
        self._tables_written_at = now
        from preform.export.csv_columns import rows_to_columns, write_csv_columns

        # without pandas: a run's `preform` process would import it only for these tables
        # (about 0.5 s, with pyarrow's compute module), on a core its workers need
        rows = [table_row(self.records[c]) for c in sorted(self.records)]
        columns = rows_to_columns(rows)
        write_csv_columns(columns, self.path / "results.csv")
        try:
            import pyarrow.parquet
        except ImportError:
            return
        table = parquet_table(columns)
        with atomic_path(self.path / "results.parquet") as tmp:
            pyarrow.parquet.write_table(table, tmp)

    def summaries(self, case_ids: Iterable[str]) -> list[dict[str, Any]]:
        """The records of these cases, those that have one."""
        return [self.records[c] for c in case_ids if c in self.records]
