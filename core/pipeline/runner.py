"""Run every (material, scene) case of a library into a results directory.

Layout of a run directory::

    manifest.json        inputs and their hashes, versions, settings, status of every case
    results.csv          one row per case: status, error, step wall times, scalar results
    results.parquet      the same, when pyarrow is installed (extra ``preform[parquet]``)
    <scene>/<material>/  summary.json and the files the scene asked for

Every file is written atomically. A case that fails is recorded and the others go on. A rerun
into the same directory skips cases whose inputs are unchanged and that already succeeded.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import re
import time
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

from preform import __version__
from preform.export.atomic import atomic_open, atomic_path
from preform.library import Library, fabric_from_data
from preform.pipeline.engines import SerialExecutor, open_executor
from preform.pipeline.planner import plan
from preform.pipeline.scene import Scene, scene_from_data
from preform.pipeline.step import CaseContext
from preform.plugin_manager import PluginHost


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


@dataclass
class CaseResult:
    case_id: str
    material: str
    scene: str
    status: str  # "ok", "failed" or "skipped" (done in an earlier run)
    error: str | None = None
    wall_time_s: float = 0.0
    step_times_s: dict[str, float] = field(default_factory=dict)
    results: dict[str, Any] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("_") or "unnamed"


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 16), b""):
            h.update(block)
    return h.hexdigest()


def _json_default(obj: Any) -> Any:
    if hasattr(obj, "item"):
        return obj.item()
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _clean_json(obj: Any) -> Any:
    """NaN/inf → None so that every JSON we write is strict JSON."""
    if isinstance(obj, float):
        return obj if obj == obj and abs(obj) != float("inf") else None
    if isinstance(obj, dict):
        return {str(k): _clean_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean_json(v) for v in obj]
    if hasattr(obj, "tolist"):
        return _clean_json(obj.tolist())
    if hasattr(obj, "item"):
        return _clean_json(obj.item())
    return obj


def write_json(path: Path, obj: Any) -> None:
    """Write strict JSON atomically."""
    with atomic_open(path) as f:
        json.dump(_clean_json(obj), f, indent=2, sort_keys=True, default=_json_default)
        f.write("\n")


# -- executing one case (runs in a worker) ---------------------------------------------------

_WORKER_HOSTS: dict[tuple[bool, tuple[tuple[str, str], ...]], PluginHost] = {}


def _worker_host(case: Case) -> PluginHost:
    key = (case.discover, case.plugins)
    host = _WORKER_HOSTS.get(key)
    if host is None:
        host = PluginHost()
        if case.discover:
            host.discover()
        host.add_modules(case.plugins)
        _WORKER_HOSTS[key] = host
    return host


def execute_case(case: Case, host: PluginHost | None = None) -> CaseResult:
    """Run one case and write its folder. Never raises for a failure of the case itself."""
    started = time.perf_counter()
    result = CaseResult(case.case_id, case.material, case.scene, "ok")
    case_dir = Path(case.case_dir)
    try:
        host = host or _worker_host(case)
        registry = host.registry
        fabric = fabric_from_data(case.fabric_data, registry)
        scene = scene_from_data(case.scene_data, case.scene_base_dir, registry)
        case_dir.mkdir(parents=True, exist_ok=True)
        ctx = CaseContext(fabric=fabric, scene=scene, registry=registry, case_dir=case_dir)
        for step in plan(scene, registry):
            t0 = time.perf_counter()
            out = dict(step.run(ctx))
            missing = [p for p in step.provides if p not in out]
            if missing:
                raise RuntimeError(f"step {step.name!r} did not provide {', '.join(missing)}")
            ctx.products.update(out)
            if step.writes_files:
                for product in step.provides:
                    value = out[product]
                    ctx.files.extend([value] if isinstance(value, str) else list(value))
            result.step_times_s[step.name] = time.perf_counter() - t0
        result.results = dict(ctx.summary)
        result.files = list(dict.fromkeys(ctx.files))
    except Exception as exc:
        result.status = "failed"
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})" if tb else ""
        result.error = f"{type(exc).__name__}: {exc}{where}"
    result.wall_time_s = time.perf_counter() - started
    try:
        write_json(
            case_dir / "summary.json",
            {
                "material": case.material,
                "scene": case.scene,
                "status": result.status,
                "error": result.error,
                "input_hash": case.input_hash,
                "wall_time_s": result.wall_time_s,
                "step_times_s": result.step_times_s,
                "files": result.files,
                **result.results,
            },
        )
    except Exception as exc:  # e.g. disk full: the case failed, the run goes on
        result.status = "failed"
        result.error = f"could not write summary.json: {exc}"
    return result


# -- planning a run --------------------------------------------------------------------------


def _input_hash(
    fabric_data: dict[str, Any], scene: Scene, scene_data: dict[str, Any], host: PluginHost
) -> str:
    steps = [(s.name, s.version) for s in plan(scene, host.registry)]
    plugins = sorted((r.name, r.version or "") for r in host.records.values() if not r.error)
    blob = json.dumps(
        {
            "fabric": fabric_data,
            "scene": scene_data,
            "steps": steps,
            "plugins": plugins,
            "preform": __version__,
        },
        sort_keys=True,
        default=_json_default,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def make_cases(
    library: Library,
    scenes: Sequence[tuple[Scene, dict[str, Any]]],
    out_dir: Path,
    host: PluginHost,
    materials_glob: str | None = None,
    discover: bool = True,
) -> list[Case]:
    """Every (material, scene) case, in a stable order."""
    cases = []
    plugin_modules = tuple(
        (name, module)
        for name, module in host.plugin_modules()
        if host.records[name].origin != "entry point"
    )
    for scene, scene_data in scenes:
        for fabric in library:
            if materials_glob and not fnmatch.fnmatchcase(fabric.name, materials_glob):
                continue
            if scene.materials and not fnmatch.fnmatchcase(fabric.name, scene.materials):
                continue
            data = fabric.model_dump(mode="json", exclude_none=True)
            cases.append(
                Case(
                    case_id=f"{scene.name}/{fabric.name}",
                    material=fabric.name,
                    scene=scene.name,
                    fabric_data=data,
                    scene_data=scene_data,
                    scene_base_dir=scene.base_dir,
                    case_dir=str(out_dir / _slug(scene.name) / _slug(fabric.name)),
                    input_hash=_input_hash(data, scene, scene_data, host),
                    plugins=plugin_modules,
                    discover=discover,
                )
            )
    return cases


def previous_result(case: Case) -> CaseResult | None:
    """The result of an earlier run of this case, if it succeeded with the same inputs."""
    path = Path(case.case_dir) / "summary.json"
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if summary.get("status") != "ok" or summary.get("input_hash") != case.input_hash:
        return None
    files = summary.get("files", [])
    if not all((Path(case.case_dir) / f).exists() for f in files):
        return None
    reserved = {
        "material",
        "scene",
        "status",
        "error",
        "input_hash",
        "wall_time_s",
        "step_times_s",
        "files",
    }
    return CaseResult(
        case.case_id,
        case.material,
        case.scene,
        "skipped",
        None,
        float(summary.get("wall_time_s", 0.0)),
        dict(summary.get("step_times_s", {})),
        {k: v for k, v in summary.items() if k not in reserved},
        list(files),
    )


@dataclass
class RunReport:
    out_dir: Path
    results: list[CaseResult]

    @property
    def failed(self) -> list[CaseResult]:
        return [r for r in self.results if r.status == "failed"]


def results_table(results: Sequence[CaseResult]) -> pd.DataFrame:
    """One row per case: identity, status, timings and the scalar results."""
    rows = []
    for r in results:
        row: dict[str, Any] = {
            "material": r.material,
            "scene": r.scene,
            "status": r.status,
            "error": r.error or "",
            "wall_time_s": r.wall_time_s,
        }
        for step, seconds in r.step_times_s.items():
            row[f"time_{step}_s"] = seconds
        for key, value in r.results.items():
            if isinstance(value, bool | int | float | str) or value is None:
                row[key] = value
        rows.append(row)
    return pd.DataFrame(rows)


def _write_tables(out_dir: Path, results: Sequence[CaseResult]) -> None:
    table = results_table(results)
    with atomic_path(out_dir / "results.csv") as tmp:
        table.to_csv(tmp, index=False)
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return
    with atomic_path(out_dir / "results.parquet") as tmp:
        table.to_parquet(tmp, index=False)


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
) -> RunReport:
    """Run the cases on an engine, skipping those already done; write manifest and tables."""
    out_dir.mkdir(parents=True, exist_ok=True)
    for stale in out_dir.rglob(".*.tmp*"):
        stale.unlink(missing_ok=True)  # left by an interrupted earlier run
    manifest: dict[str, Any] = {
        "preform_version": __version__,
        "started": datetime.now(UTC).isoformat(timespec="seconds"),
        "settings": {"engine": engine, "workers": workers, "scheduler": scheduler, "force": force},
        "inputs": inputs or {},
        "plugins": [r.as_json() for r in host.records.values()],
        "cases": {
            c.case_id: {
                "status": "pending",
                "case_dir": str(Path(c.case_dir).relative_to(out_dir)),
                "input_hash": c.input_hash,
            }
            for c in cases
        },
    }
    write_json(out_dir / "manifest.json", manifest)
    results: dict[str, CaseResult] = {}

    def record(result: CaseResult) -> None:
        results[result.case_id] = result
        manifest["cases"][result.case_id].update(
            {
                "status": result.status,
                "error": result.error,
                "wall_time_s": round(result.wall_time_s, 6),
            }
        )
        write_json(out_dir / "manifest.json", manifest)
        if on_done is not None:
            on_done(result)

    todo = []
    for case in cases:
        done = None if force else previous_result(case)
        if done is not None:
            record(done)
        else:
            todo.append(case)
    if todo:
        with open_executor(engine, workers=workers, scheduler=scheduler) as executor:
            futures: dict[Future[CaseResult], Case] = {}
            for case in todo:
                if isinstance(executor, SerialExecutor):
                    # in-process: use this host, so plugins registered by code are seen
                    fut = executor.submit(execute_case, case, host)
                else:
                    fut = executor.submit(execute_case, case)
                futures[fut] = case
            from concurrent.futures import as_completed

            for fut in as_completed(futures):
                case = futures[fut]
                try:
                    res = fut.result()
                except Exception as exc:  # the worker died (killed, out of memory, ...)
                    res = CaseResult(
                        case.case_id,
                        case.material,
                        case.scene,
                        "failed",
                        f"worker failed: {type(exc).__name__}: {exc}",
                    )
                record(res)
    ordered = [results[c.case_id] for c in cases]
    manifest["aggregates"] = _run_aggregates(cases, ordered, out_dir, host)
    manifest["finished"] = datetime.now(UTC).isoformat(timespec="seconds")
    write_json(out_dir / "manifest.json", manifest)
    _write_tables(out_dir, ordered)
    return RunReport(out_dir, ordered)


def _run_aggregates(
    cases: Sequence[Case], results: Sequence[CaseResult], out_dir: Path, host: PluginHost
) -> dict[str, Any]:
    """Run-level outputs of steps that define ``aggregate``, once per scene."""
    written: dict[str, Any] = {}
    by_scene: dict[str, list[tuple[Case, CaseResult]]] = {}
    for case, res in zip(cases, results, strict=True):
        by_scene.setdefault(case.scene, []).append((case, res))
    for scene_name, members in by_scene.items():
        first = members[0][0]
        try:
            scene = scene_from_data(first.scene_data, first.scene_base_dir, host.registry)
            steps = [s for s in plan(scene, host.registry) if s.aggregate is not None]
        except Exception as exc:
            written[scene_name] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        summaries = []
        for case, res in members:
            if res.status in ("ok", "skipped"):
                try:
                    summaries.append(json.loads((Path(case.case_dir) / "summary.json").read_text()))
                except (OSError, ValueError):
                    continue
        folder = out_dir / _slug(scene_name)
        for step in steps:
            assert step.aggregate is not None
            try:
                files = step.aggregate(folder, summaries)
                written.setdefault(scene_name, {})[step.name] = files
            except Exception as exc:  # a run-level figure must not lose the run's results
                written.setdefault(scene_name, {})[step.name] = {
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
    "RunReport",
    "asdict",
    "execute_case",
    "make_cases",
    "run_cases",
]
