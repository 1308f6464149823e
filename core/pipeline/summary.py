"""A run in one JSON document: what ``preform pipeline run --json`` prints and what
``preform.run(...).summary`` holds, so a script and a notebook read the same thing."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from preform.pipeline.runner import CaseResult, RunReport


def case_summary(result: CaseResult) -> dict[str, Any]:
    """One case: its identity, status in words and why (reasons, warnings, error)."""
    from preform.base.status import CaseStatus

    return {
        "case_id": result.case_id,
        "material": result.material,
        "scene": result.scene,
        "status": result.status,
        "kept_from_earlier_run": result.reused,
        "covered_fraction": result.results.get("covered_fraction")
        if result.status == CaseStatus.PARTIAL
        else None,
        "reasons": list(result.reasons),
        "warnings": list(result.warnings),
        "error": result.error,
        "wall_time_s": round(result.wall_time_s, 6),
        "files": list(result.files),
    }


def run_summary(report: RunReport) -> dict[str, Any]:
    """The run: its directory, counts by status (``skipped``: kept from an earlier run), the
    exit code the command line gives it, and every case of this run."""
    from preform.base.status import MEANING, CaseStatus

    failed = any(r.status in ("failed", "timed_out") for r in report.results)
    statuses = sorted({CaseStatus(r.status) for r in report.results})
    return {
        "out_dir": str(report.out_dir),
        "interrupted": report.interrupted,
        "counts": report.counts(),
        "exit_code": 130 if report.interrupted else (1 if failed else 0),
        "status_meaning": {s.value: MEANING[s] for s in statuses},
        "cases": [case_summary(r) for r in report.results],
    }
