"""Run every (material, scene) case of a library into a results directory.

The directory's layout, lock, manifest and tables are ``preform.pipeline.rundir``'s; the
engines are ``preform.pipeline.engines``'; what a status means is ``preform.base.status``.
Here: what a case is (and the hash that says when its result can be reused), how one case runs
and what its status is, and the loop that runs a set of cases so that a case that fails, dies,
hangs or is interrupted costs only itself, and everything that finished is kept.
"""

from __future__ import annotations

import contextlib
import fnmatch
import hashlib
import json
import math
import os
import re
import signal
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

from preform.base import __version__
from preform.base.status import REUSABLE, CaseFailure, CaseStatus
from preform.base.strict_json import clean_json as _clean_json
from preform.library import Library, fabric_from_data
from preform.pipeline.batching import plan_batches, recorded_wall_time_s
from preform.pipeline.engines import (
    CaseTimeout,
    Engine,
    SerialEngine,
    open_engine,
    time_limit,
)
from preform.pipeline.planner import plan
from preform.pipeline.preload import worker_preload
from preform.pipeline.rundir import (
    RunDirectory,
    RunDirectoryError,
    now_utc,
    read_json,
    write_json,
)
from preform.pipeline.scene import Scene, scene_from_data
from preform.plugin_manager import PluginHost
from preform.step import CaseContext

#: Wall-time limit of a case when neither the scene (``limits.case_timeout_s``) nor the
#: command line (``--case-timeout``) sets one [s]. The bundled studies take seconds a case.
DEFAULT_CASE_TIMEOUT_S = 3600.0
#: Extra time the runner allows an engine that cannot stop a case itself (Dask) [s].
TIMEOUT_GRACE_S = 5.0

T = TypeVar("T")


@dataclass(frozen=True)
class Case:
    """One (material, scene) case: everything a worker process needs, and picklable."""

    case_id: str
    material: str
    scene: str
    fabric_data: dict[str, Any]
    scene_data: dict[str, Any]
    scene_base_dir: str
    case_dir: str
    input_hash: str
    #: Plugins to load in a worker besides entry-point discovery: (name, module).
    plugins: tuple[tuple[str, str], ...] = ()
    discover: bool = True
    #: Wall-time limit [s]; None for none.
    timeout_s: float | None = None
    #: The run computing it (set by ``run_cases``; written into its summary.json, so a lost
    #: batch's finished cases can be told from an earlier run's).
    run_id: str = ""
    #: A layup scene's fabrics, (name, data) each (``preform.stack``): its case drapes them all.
    layup_fabrics: tuple[tuple[str, dict[str, Any]], ...] = ()


@dataclass
class CaseResult:
    case_id: str
    material: str
    scene: str
    status: str  # a CaseStatus value
    error: str | None = None
    wall_time_s: float = 0.0
    step_times_s: dict[str, float] = field(default_factory=dict)
    results: dict[str, Any] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)
    #: Why the result is partial (or what stopped it), in words.
    reasons: list[str] = field(default_factory=list)
    #: What the user must know about the result, in words.
    warnings: list[str] = field(default_factory=list)
    #: True when an earlier run's result was kept (this run's "skipped").
    reused: bool = False


# -- folders and hashes ----------------------------------------------------------------------

_SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,79}")
_RESERVED = {"CON", "PRN", "AUX", "NUL", *(f"COM{i}" for i in range(10))}
_RESERVED |= {f"LPT{i}" for i in range(10)}


def folder_name(name: str) -> str:
    """A safe, unique folder name for a fabric or scene name.

    A name that is already a plain file name (letters, digits, ``._-``, not starting with a dot,
    at most 80 characters) is used as it is. Any other name is reduced to such characters and
    given a hash of the full name, so ``a b`` and ``a_b`` get different folders and ``..`` never
    walks out of the results directory.
    """
    if (
        _SAFE_NAME.fullmatch(name)
        and not name.endswith(".")
        and name.split(".")[0].upper() not in _RESERVED
    ):
        return name
    base = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._-")[:60] or "unnamed"
    return f"{base}-{hashlib.sha256(name.encode()).hexdigest()[:8]}"


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 16), b""):
            h.update(block)
    return h.hexdigest()


def _referenced_files(data: Any, base_dir: Path) -> Iterator[tuple[str, Path]]:
    """Strings in scene data that name an existing regular file (a tool mesh), resolved."""
    if isinstance(data, dict):
        for value in data.values():
            yield from _referenced_files(value, base_dir)
    elif isinstance(data, list):
        for value in data:
            yield from _referenced_files(value, base_dir)
    elif isinstance(data, str) and data and len(data) < 4096 and "\n" not in data:
        path = base_dir / data
        try:
            if path.is_file():
                yield data, path
        except (OSError, ValueError):
            return


def input_hash(
    fabric_data: Mapping[str, Any],
    scene: Scene,
    scene_data: Mapping[str, Any],
    host: PluginHost,
) -> str:
    """The hash of everything that determines a case's result, and nothing else.

    The fabric's and the scene's canonical data (key order does not matter), the content of the
    files the scene references (a tool mesh, by its bytes, not its path), the name and version of
    each step that runs, and the plugin and version providing each of them, the architecture,
    the shear law and the surface. Stable across processes (no set or hash-seed order) and
    across unrelated plugins being installed.
    """
    registry = host.registry
    providers: set[tuple[str, str, str, str]] = set()

    def provider(kind: str, name: Any) -> None:
        entry = registry.entries(kind).get(str(name)) if name is not None else None
        if entry is not None:
            providers.add((kind, entry.name, entry.plugin, entry.version))

    steps = sorted((s.name, s.version) for s in plan(scene, registry))
    for name, _ in steps:
        provider("steps", name)
        provider("exporters", name)
    provider("architectures", fabric_data.get("architecture"))
    law = fabric_data.get("shear_law")
    if isinstance(law, Mapping):
        provider("shear_laws", law.get("law"))
    tool = scene_data.get("tool")
    if isinstance(tool, Mapping):
        provider("surfaces", tool.get("surface"))
    files = sorted(
        (text, _sha256_file(path))
        for text, path in _referenced_files(dict(scene_data), Path(scene.base_dir))
    )
    blob = json.dumps(
        {
            "fabric": fabric_data,
            "scene": scene_data,
            "files": files,
            "steps": steps,
            "providers": sorted(providers),
            "preform": __version__,
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


# -- executing one case (runs in a worker) ---------------------------------------------------

_WORKER_HOSTS: dict[tuple[bool, tuple[tuple[str, str], ...]], PluginHost] = {}


def _worker_host(case: Case) -> PluginHost:
    key = (case.discover, case.plugins)
    if key not in _WORKER_HOSTS:
        warm_worker((key,))
    return _WORKER_HOSTS[key]


def warm_worker(hosts: tuple[tuple[bool, tuple[tuple[str, str], ...]], ...]) -> None:
    """A worker's warm-up (run once when it starts): build the plugin host of each
    (discover, plugins) its cases will ask for, so the first case pays nothing more."""
    for discover, plugins in hosts:
        key = (discover, plugins)
        if key not in _WORKER_HOSTS:
            host = PluginHost()
            if discover:
                host.discover()
            host.add_modules(plugins)
            _WORKER_HOSTS[key] = host


def non_finite_values(data: Any, prefix: str = "") -> list[str]:
    """``key = value`` of every non-finite float in a (nested) result mapping."""
    found: list[str] = []
    if isinstance(data, Mapping):
        for key, value in data.items():
            found += non_finite_values(value, f"{prefix}.{key}" if prefix else str(key))
    elif isinstance(data, list | tuple):
        for i, value in enumerate(data):
            found += non_finite_values(value, f"{prefix}[{i}]")
    elif isinstance(data, float) and not math.isfinite(data):
        found.append(f"{prefix} = {data}")
    elif hasattr(data, "dtype") and hasattr(data, "tolist"):
        found += non_finite_values(data.tolist(), prefix)
    return found


def case_record(case: Case, result: CaseResult) -> dict[str, Any]:
    """The case's summary.json: its identity, status in words, timings, and results."""
    return {
        **result.results,
        "case_id": case.case_id,
        "material": case.material,
        "scene": case.scene,
        "status": result.status,
        "error": result.error,
        "reasons": result.reasons,
        "warnings": result.warnings,
        "input_hash": case.input_hash,
        "finished": now_utc(),
        "wall_time_s": round(result.wall_time_s, 6),
        "step_times_s": result.step_times_s,
        "files": result.files,
        **({"run_id": case.run_id} if case.run_id else {}),
    }


def _error_text(exc: BaseException) -> str:
    tb = traceback.extract_tb(exc.__traceback__)
    where = f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})" if tb else ""
    return f"{type(exc).__name__}: {exc}{where}"


def execute_case(
    case: Case,
    host: PluginHost | None = None,
    on_context: Callable[[CaseContext], None] | None = None,
) -> CaseResult:
    """Run one case and write its folder. Never raises for a failure of the case itself.

    ``on_context`` (in-process callers: the Python API) is given the case's context after its
    steps ran or stopped, so the products (the draped net, the search) can be kept in memory.

    The status: ``failed`` on an error, a ``CaseFailure`` or a non-finite number in the results;
    ``timed_out`` past the case's time limit (checked between steps here; the process engine
    also kills a worker that overruns inside a step); else ``partial`` when a step said the
    result covers less than asked; else ``ok``.
    """
    started = time.perf_counter()
    result = CaseResult(case.case_id, case.material, case.scene, CaseStatus.OK.value)
    case_dir = Path(case.case_dir)
    ctx: CaseContext | None = None

    def check_time() -> None:
        if case.timeout_s is not None and time.perf_counter() - started > case.timeout_s:
            raise CaseTimeout()

    try:
        host = host or _worker_host(case)
        registry = host.registry
        fabric = fabric_from_data(case.fabric_data, registry)
        scene = scene_from_data(case.scene_data, case.scene_base_dir, registry)
        case_dir.mkdir(parents=True, exist_ok=True)
        ctx = CaseContext(fabric=fabric, scene=scene, registry=registry, case_dir=case_dir)
        if case.layup_fabrics:
            ctx.products["layup_fabrics"] = {
                name: fabric_from_data(data, registry) for name, data in case.layup_fabrics
            }
        if case.timeout_s is not None:
            ctx.summary["limit_case_timeout_s"] = case.timeout_s
        for step in plan(scene, registry):
            check_time()
            t0 = time.perf_counter()
            out = dict(step.run(ctx))
            missing = [p for p in step.provides if p not in out]
            if missing:
                raise RuntimeError(f"step {step.name!r} did not provide {', '.join(missing)}")
            # a non-finite result fails the case before any exporter writes it into a file
            bad = non_finite_values(ctx.summary)
            if bad:
                raise CaseFailure(
                    f"step {step.name!r} gave non-finite numbers: " + "; ".join(bad[:10])
                )
            ctx.products.update(out)
            if step.writes_files:
                for product in step.provides:
                    value = out[product]
                    ctx.files.extend([value] if isinstance(value, str) else list(value))
            result.step_times_s[step.name] = time.perf_counter() - t0
        check_time()
        result.results = dict(ctx.summary)
        result.files = list(dict.fromkeys(ctx.files))
        result.warnings = list(ctx.warnings)
        if ctx.partial_reasons:
            result.status = CaseStatus.PARTIAL.value
            result.reasons = list(ctx.partial_reasons)
    except CaseTimeout:
        result.status = CaseStatus.TIMED_OUT.value
        result.error = f"stopped at the case time limit of {case.timeout_s:g} s"
    except CaseFailure as exc:
        result.status = CaseStatus.FAILED.value
        result.error = str(exc)
    except (Exception, SystemExit) as exc:  # a plugin's sys.exit() fails its case only
        result.status = CaseStatus.FAILED.value
        result.error = _error_text(exc)
    if ctx is not None and result.status != CaseStatus.OK.value:
        # what the steps said before it stopped still helps to read the failure
        result.warnings = list(ctx.warnings)
        result.reasons = result.reasons or list(ctx.partial_reasons)
    if ctx is not None and on_context is not None:
        on_context(ctx)
    result.wall_time_s = time.perf_counter() - started
    try:
        write_json(case_dir / "summary.json", case_record(case, result))
    except Exception as exc:  # e.g. disk full: the case failed, the run goes on
        result.status = CaseStatus.FAILED.value
        result.error = f"could not write summary.json: {exc}"
    return result


# -- planning a run --------------------------------------------------------------------------


class CaseSetError(ValueError):
    """The cases cannot be laid out in the results directory (two share a folder)."""


def make_cases(
    library: Library,
    scenes: Sequence[tuple[Scene, dict[str, Any]]],
    out_dir: Path,
    host: PluginHost,
    materials_glob: str | Sequence[str] | None = None,
    discover: bool = True,
    timeout_s: float | None = None,
) -> list[Case]:
    """Every (material, scene) case, in a stable order.

    ``materials_glob``: a glob, or several (a fabric matching any of them is run); None or
    empty runs every fabric the scene takes. ``timeout_s`` is the run's case time limit; a scene's ``limits.case_timeout_s`` wins.
    """
    cases = []
    plugin_modules = tuple(
        (name, module)
        for name, module in host.plugin_modules()
        if host.records[name].origin != "entry point"
    )
    folders: dict[str, str] = {}
    globs = [materials_glob] if isinstance(materials_glob, str) else list(materials_glob or ())
    for scene, scene_data in scenes:
        limit = scene.limits.case_timeout_s or timeout_s
        if scene.layup is not None:
            # one case per layup scene: it drapes the fabrics its plies name (preform.stack)
            from preform.pipeline.layup_case import layup_case

            try:
                case = layup_case(library, scene, scene_data, out_dir, host)
            except ValueError as error:
                raise CaseSetError(str(error)) from None
            cases.append(replace(case, plugins=plugin_modules, discover=discover, timeout_s=limit))
            continue
        for fabric in library:
            if globs and not any(fnmatch.fnmatchcase(fabric.name, g) for g in globs):
                continue
            if scene.materials and not fnmatch.fnmatchcase(fabric.name, scene.materials):
                continue
            data = fabric.model_dump(mode="json", exclude_none=True)
            case_id = f"{scene.name}/{fabric.name}"
            folder = f"{folder_name(scene.name)}/{folder_name(fabric.name)}"
            if folders.setdefault(folder, case_id) != case_id:
                raise CaseSetError(
                    f"cases {folders[folder]!r} and {case_id!r} would share the folder "
                    f"{folder!r}; rename one of the fabrics or scenes"
                )
            cases.append(
                Case(
                    case_id=case_id,
                    material=fabric.name,
                    scene=scene.name,
                    fabric_data=data,
                    scene_data=scene_data,
                    scene_base_dir=scene.base_dir,
                    case_dir=str(out_dir / folder),
                    input_hash=input_hash(data, scene, scene_data, host),
                    plugins=plugin_modules,
                    discover=discover,
                    timeout_s=limit,
                )
            )
    return cases


def previous_result(case: Case) -> CaseResult | None:
    """The result of an earlier run of this case, if it is complete (ok or partial) with the
    same inputs and every file it wrote is still there."""
    summary = read_json(Path(case.case_dir) / "summary.json")
    if not isinstance(summary, dict):
        return None
    if summary.get("status") not in REUSABLE or summary.get("input_hash") != case.input_hash:
        return None
    files = summary.get("files", [])
    if not all((Path(case.case_dir) / f).is_file() for f in files):
        return None
    return _recorded_result(case, summary, reused=True)


def _recorded_result(case: Case, summary: dict[str, Any], *, reused: bool = False) -> CaseResult:
    """The result ``case``'s summary.json records (``reused``: from an earlier run)."""
    from preform.pipeline.rundir import RECORD_KEYS

    return CaseResult(
        case.case_id,
        case.material,
        case.scene,
        str(summary.get("status")),
        summary.get("error"),
        float(summary.get("wall_time_s") or 0.0),
        dict(summary.get("step_times_s") or {}),
        {k: v for k, v in summary.items() if k not in RECORD_KEYS},
        list(summary.get("files") or []),
        list(summary.get("reasons") or []),
        list(summary.get("warnings") or []),
        reused=reused,
    )


# -- running ---------------------------------------------------------------------------------


@dataclass
class RunReport:
    out_dir: Path
    #: This run's cases, in order.
    results: list[CaseResult]
    #: True when the run was interrupted (Ctrl-C, SIGTERM) and did not finish.
    interrupted: bool = False
    #: The run's report page (``preform.report``) when one was asked for and written.
    report_file: Path | None = None
    #: Why the report page was not written, in words (the run's results are kept).
    report_error: str | None = None

    @property
    def failed(self) -> list[CaseResult]:
        return [r for r in self.results if r.status == CaseStatus.FAILED]

    def counts(self) -> dict[str, int]:
        """Cases of this run by what happened to them (``skipped``: kept from earlier)."""
        out: dict[str, int] = {}
        for r in self.results:
            key = CaseStatus.SKIPPED.value if r.reused else r.status
            out[key] = out.get(key, 0) + 1
        return out


def _engine_failure(case: Case, exc: BaseException, timeout_s: float | None) -> CaseResult:
    """The result of a case whose worker did not return one."""
    result = CaseResult(case.case_id, case.material, case.scene, CaseStatus.FAILED.value)
    if isinstance(exc, TimeoutError | CaseTimeout):
        result.status = CaseStatus.TIMED_OUT.value
        result.error = f"stopped at the case time limit of {timeout_s:g} s"
        return result
    code = getattr(exc, "exitcode", None)
    if code is not None:  # pebble.ProcessExpired: the worker process died
        how = f"exit code {code}"
        if code < 0:
            try:
                how = f"killed by {signal.Signals(-code).name}"
            except ValueError:
                how = f"killed by signal {-code}"
            if code == -signal.SIGKILL:
                how += " (out of memory? the OOM killer sends it)"
        result.error = f"the worker process running this case died ({how})"
    elif type(exc).__name__ == "KilledWorker":  # Dask's word for a worker that died
        result.error = "the worker process running this case died (Dask: KilledWorker)"
    else:
        result.error = f"worker failed: {type(exc).__name__}: {exc}"
    return result


def _raise_interrupt(_signum: int, _frame: Any) -> None:
    raise KeyboardInterrupt


def run_cases(
    cases: Sequence[Case],
    out_dir: Path,
    host: PluginHost,
    *,
    engine: str = "process",
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    inputs: dict[str, Any] | None = None,
    on_done: Callable[[CaseResult], None] | None = None,
    batch_size: int | None = None,
    report_page: Callable[[Path], Path] | None = None,
) -> RunReport:
    """Run the cases on an engine, keeping finished ones; keep manifest and tables current.

    A case that fails, whose worker dies, or that passes its time limit is recorded and the
    others go on. On Ctrl-C or SIGTERM the engine is stopped at once, what finished is kept,
    the rest is recorded ``interrupted``, and the report says so. Raises ``RunDirectoryError``
    when ``out_dir`` cannot be used (a file, or another run holds it).

    Cases start longest first where an earlier run recorded their time, and small ones travel
    in batches of ``batch_size`` cases (None: ``preform.pipeline.batching.plan_batches``
    chooses; 1: none). A batch whose worker dies or overruns keeps the cases it finished; the
    others are run again, each on its own. The run-level outputs run on the engine too.

    ``report_page``: writes the folder's page when the run ends uninterrupted (given the
    folder, returns the file: ``preform.report.write_report``, which sits above the pipeline);
    a page that cannot be written is said in ``report_error``, never fails the run.
    """
    from preform.pipeline.main_guard import refuse_unguarded_run

    # before anything starts: a worker re-running an unguarded script must not run it again
    refuse_unguarded_run(starts_workers=engine == "process" or (engine == "dask" and not scheduler))
    # workers start now (a fork server imports what they need) while this process reads the
    # directory and imports its table writers; a pre-lock look, so a run with nothing to do
    # starts none (the list that counts is taken under the lock below)
    maybe_todo = [c for c in cases if force or previous_result(c) is None]
    with _EngineSession(maybe_todo, host, engine, workers, scheduler) as session:
        # the table writers' imports, now rather than at the first finished case: a Ctrl-C
        # that lands inside a half-done import would leave the module broken for the run
        import preform.export.csv_columns  # noqa: F401

        with contextlib.suppress(ImportError):
            import pyarrow.parquet  # noqa: F401
        return _run_in_directory(
            cases,
            out_dir,
            host,
            session,
            engine,
            workers,
            scheduler,
            force,
            inputs,
            on_done,
            batch_size,
            report_page,
        )


def _run_in_directory(
    cases: Sequence[Case],
    out_dir: Path,
    host: PluginHost,
    session: _EngineSession,
    engine: str,
    workers: int | None,
    scheduler: str | None,
    force: bool,
    inputs: dict[str, Any] | None,
    on_done: Callable[[CaseResult], None] | None,
    batch_size: int | None,
    report_page: Callable[[Path], Path] | None = None,
) -> RunReport:
    with RunDirectory(out_dir) as rundir:
        run: dict[str, Any] = {
            "id": f"{now_utc()}-{os.getpid()}-{os.urandom(3).hex()}",
            "preform_version": __version__,
            "started": now_utc(),
            "settings": {
                "engine": engine,
                "workers": workers,
                "scheduler": scheduler,
                "force": force,
                "case_timeout_s": sorted({c.timeout_s for c in cases}, key=str),
                "batch_size": batch_size,
            },
            "inputs": inputs or {},
            "plugins": [r.as_json() for r in host.records.values()],
            "cases": [c.case_id for c in cases],
        }
        for case in cases:
            rundir.expect(case.case_id, Path(case.case_dir), case.input_hash)
        rundir.write_manifest(run)
        results: dict[str, CaseResult] = {}

        def record(
            case: Case, result: CaseResult, *, write: bool = False, flush: bool = True
        ) -> None:
            if write:  # the worker could not write it (it died, or was stopped)
                write_json(Path(case.case_dir) / "summary.json", case_record(case, result))
            rec = read_json(Path(case.case_dir) / "summary.json")
            if not isinstance(rec, dict) or rec.get("case_id") != case.case_id:
                rec = case_record(case, result)
            rundir.record(rec, Path(case.case_dir))
            # only once the directory knows it: an interrupt before leaves it to be recorded
            # again (from its summary.json), not pending
            results[case.case_id] = result
            if flush:  # a batch's results are written together, after its last one
                rundir.write_manifest(run)
                rundir.write_tables(force=False)
            if on_done is not None:
                on_done(result)

        todo = []
        for case in cases:
            done = None if force else previous_result(case)
            if done is not None:
                record(case, done)
            else:
                todo.append(replace(case, run_id=run["id"]))
        interrupted = False
        if todo:
            interrupted = session.run(todo, record, batch_size)
        for case in cases:
            if case.case_id not in results:
                res = CaseResult(
                    case.case_id,
                    case.material,
                    case.scene,
                    CaseStatus.INTERRUPTED.value,
                    "the run was interrupted before this case finished; rerun to compute it",
                )
                record(case, res, write=True)
        ordered = [results[c.case_id] for c in cases]
        report = RunReport(out_dir, ordered, interrupted)
        if not interrupted:
            try:
                run["aggregates"] = _run_aggregates(cases, rundir, host, session)
            except KeyboardInterrupt:  # every case is recorded; only run-level figures are lost
                session.stop()
                interrupted = True
                report.interrupted = True
        run["finished"] = now_utc()
        run["status"] = "interrupted" if interrupted else "finished"
        run["counts"] = report.counts()
        rundir.write_manifest(run)
        rundir.write_tables()
        if report_page is not None and not interrupted:
            try:  # the folder's page, under the run's lock, from the files just written
                report.report_file = report_page(report.out_dir)
            except Exception as exc:  # a page must not lose the run's results
                report.report_error = f"{type(exc).__name__}: {exc}"
            except KeyboardInterrupt:  # every case is recorded: only the page is left to write
                report.report_error = "interrupted; `preform report DIR` writes it"
        return report


def execute_batch(cases: Sequence[Case]) -> list[CaseResult]:
    """Run small cases one after another in one task (a worker). Each is ``execute_case``,
    each within its own time limit where the worker can stop itself (``time_limit``: a
    process pool's worker; a Dask worker's thread cannot, and relies on the runner)."""
    results = []
    for case in cases:
        with time_limit(case.timeout_s):
            results.append(execute_case(case))
    return results


def finished_in_run(case: Case) -> CaseResult | None:
    """The result this run's worker wrote for ``case`` before its batch was lost (the worker
    died or overran): its summary.json, if it carries this run's id."""
    summary = read_json(Path(case.case_dir) / "summary.json")
    if not isinstance(summary, dict) or not case.run_id:
        return None
    if summary.get("run_id") != case.run_id or summary.get("case_id") != case.case_id:
        return None
    return _recorded_result(case, summary)


class _EngineSession:
    """The engine of one run, opened when the run starts (so its workers start while this
    process prepares) and closed, or stopped at once on an interrupt, when the run ends;
    SIGTERM is an interrupt meanwhile. No engine is opened for a run with nothing to do."""

    def __init__(
        self,
        todo: Sequence[Case],
        host: PluginHost,
        engine_name: str,
        workers: int | None,
        scheduler: str | None,
    ) -> None:
        self.host = host
        self.engine_name = engine_name
        self.workers = workers
        self.scheduler = scheduler
        self._todo = list(todo)
        self.engine: Engine | None = None
        self._previous_term: Any = None

    def __enter__(self) -> _EngineSession:
        if threading.current_thread() is threading.main_thread():
            self._previous_term = signal.signal(signal.SIGTERM, _raise_interrupt)
        try:
            if self._todo:
                self._open(self._todo)
        except BaseException:
            self._restore()
            raise
        return self

    def _open(self, todo: Sequence[Case]) -> Engine:
        hosts = tuple(dict.fromkeys((c.discover, c.plugins) for c in todo))
        self.engine = open_engine(
            self.engine_name,
            workers=self.workers,
            scheduler=self.scheduler,
            preload=worker_preload(),
            warm_up=("preform.pipeline.runner:warm_worker", (hosts,)),
        )
        return self.engine

    def __exit__(self, exc_type: Any, *_: object) -> None:
        try:
            if self.engine is not None:
                if exc_type is None:
                    self.engine.close()
                else:
                    self.engine.stop()
                self.engine = None
        finally:
            self._restore()

    def _restore(self) -> None:
        if self._previous_term is not None:
            signal.signal(signal.SIGTERM, self._previous_term)
            self._previous_term = None

    def stop(self) -> None:
        """Stop every running and queued task now (interrupt)."""
        if self.engine is not None:
            self.engine.stop()
            self.engine = None

    def submit(self, fn: Callable[..., T], *args: Any, timeout_s: float | None = None) -> Future[T]:
        """A run-level task on the run's engine; in this process when it has none."""
        if self.engine is None:
            return SerialEngine().submit(fn, *args, timeout_s=timeout_s)
        return self.engine.submit(fn, *args, timeout_s=timeout_s)

    def run(
        self,
        todo: Sequence[Case],
        record: Callable[..., None],
        batch_size: int | None = None,
    ) -> bool:
        """Run ``todo``, recording each case as it ends; True if interrupted."""
        recorded: set[str] = set()

        def record_once(case: Case, result: CaseResult, **how: Any) -> None:
            record(case, result, **how)
            recorded.add(case.case_id)  # after: an interrupt inside leaves it to the harvest

        try:
            engine = self.engine or self._open(todo)
            self._run(engine, todo, record_once, batch_size)
        except KeyboardInterrupt:
            self.stop()
            # a worker may have finished cases whose results had not come back: they are kept
            for case in todo:
                done = None if case.case_id in recorded else finished_in_run(case)
                if done is not None:
                    record_once(case, done)
            return True
        return False

    def _run(
        self,
        engine: Engine,
        todo: Sequence[Case],
        record: Callable[..., None],
        batch_size: int | None,
    ) -> None:
        serial = self.engine_name == "serial"
        estimates = {c.case_id: recorded_wall_time_s(c.case_dir) for c in todo}
        queue = plan_batches(
            todo,
            lambda c: estimates[c.case_id],
            workers=engine.workers,
            batch_size=1 if serial else batch_size,  # in-process: nothing to save
        )
        pending: dict[Future[Any], tuple[list[Case], float]] = {}
        while queue or pending:
            while queue and len(pending) < engine.capacity:
                batch = queue.pop(0)
                limit = _batch_timeout(batch)
                if serial:
                    # in-process: use this host, so plugins registered by code are seen
                    fut: Future[Any] = engine.submit(
                        execute_case, batch[0], self.host, timeout_s=limit
                    )
                elif len(batch) == 1:
                    fut = engine.submit(execute_case, batch[0], timeout_s=limit)
                else:
                    fut = engine.submit(execute_batch, batch, timeout_s=limit)
                pending[fut] = (batch, time.monotonic())
            done, _ = wait(list(pending), timeout=0.5, return_when=FIRST_COMPLETED)
            for fut in done:
                batch, _started = pending.pop(fut)
                try:
                    returned = fut.result()
                except (Exception, CaseTimeout) as exc:  # the worker did not return a result
                    queue[:0] = self._lost(batch, exc, record)
                    continue
                for i, result in enumerate(returned if isinstance(returned, list) else [returned]):
                    record(batch[i], result, flush=i == len(batch) - 1)
            if not engine.enforces_timeout:
                now = time.monotonic()
                for fut, (batch, started) in list(pending.items()):
                    limit = _batch_timeout(batch)
                    if limit is not None and now - started > limit + TIMEOUT_GRACE_S:
                        engine.abandon(fut)
                        del pending[fut]
                        queue[:0] = self._lost(batch, CaseTimeout(), record)

    @staticmethod
    def _lost(
        batch: list[Case], exc: BaseException, record: Callable[..., None]
    ) -> list[list[Case]]:
        """A task that returned no result: one case is failed or timed out in words; a batch
        keeps the cases it finished, and gives back the others to run again, each alone."""
        if len(batch) == 1:
            case = batch[0]
            record(case, _engine_failure(case, exc, case.timeout_s), write=True)
            return []
        again = []
        for case in batch:
            done = finished_in_run(case)
            if done is not None:
                record(case, done)
            else:
                again.append([case])
        return again


def _batch_timeout(batch: Sequence[Case]) -> float | None:
    """The engine's time limit of a task [s]: a case's own limit; for a batch, the largest of
    its cases' limits plus ``TIMEOUT_GRACE_S`` (None if a case has none). Inside a batch each
    case is stopped at its own limit where the worker can stop itself; this bound catches what
    it cannot (a call into compiled code that never returns): past it the batch is stopped and
    its unfinished cases run again, each alone. Batches hold small cases, so a sound one ends
    far below it."""
    limits = [c.timeout_s for c in batch]
    if any(limit is None for limit in limits):
        return None
    longest = max(limit for limit in limits if limit is not None)
    return longest if len(batch) == 1 else longest + TIMEOUT_GRACE_S


def _run_aggregates(
    cases: Sequence[Case], rundir: RunDirectory, host: PluginHost, session: _EngineSession
) -> dict[str, Any]:
    """Run-level outputs of steps that define ``aggregate``, once per scene of this run, over
    every complete case of that scene in the directory (earlier runs' too). They run on the
    run's engine (a warm worker has the figure libraries loaded; this process need not)."""
    written: dict[str, Any] = {}
    first_of_scene: dict[str, Case] = {}
    for case in cases:
        first_of_scene.setdefault(case.scene, case)
    tasks: list[tuple[str, str, Future[list[str]]]] = []
    for scene_name, first in first_of_scene.items():
        try:
            scene = scene_from_data(first.scene_data, first.scene_base_dir, host.registry)
            steps = [s for s in plan(scene, host.registry) if s.aggregate is not None]
        except Exception as exc:
            written[scene_name] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        summaries: list[Mapping[str, Any]] = [
            rec
            for rec in rundir.records.values()
            if rec.get("scene") == scene_name and rec.get("status") in REUSABLE
        ]
        summaries.sort(key=lambda rec: str(rec.get("material")))
        folder = Path(first.case_dir).parent
        for step in steps:
            assert step.aggregate is not None
            # steps are module-level functions (the registry checks): a worker imports it
            future = session.submit(step.aggregate, folder, summaries)
            tasks.append((scene_name, step.name, future))
    for scene_name, step_name, future in tasks:
        try:
            written.setdefault(scene_name, {})[step_name] = future.result()
        except Exception as exc:  # a run-level figure must not lose the run's results
            written.setdefault(scene_name, {})[step_name] = {
                "error": f"{type(exc).__name__}: {exc}"
            }
    return written


def input_files_record(paths: Sequence[Path]) -> list[dict[str, str]]:
    """Paths and SHA-256 of input files (for the manifest)."""
    out = []
    for p in paths:
        files = sorted(q for q in p.rglob("*.y*ml")) if p.is_dir() else [p]
        out += [{"path": str(f), "sha256": _sha256_file(f)} for f in files if f.is_file()]
    return out


__all__ = [
    "Case",
    "CaseResult",
    "CaseSetError",
    "RunDirectoryError",
    "RunReport",
    "_clean_json",
    "asdict",
    "execute_case",
    "folder_name",
    "input_hash",
    "make_cases",
    "run_cases",
    "write_json",
]
