"""The end of a run in words, on the console: a summary line, then at most one line per case.

Quiet by default (issue 26): every warning is kept in full in each case's summary.json and in
results.csv; the console names each case that is not plainly ``ok`` once, its causes grouped
and counted (``CaseContext.warn``'s ``cause``), the worst case and the worst cause first.
Warnings about angles a search only sampled (``scan``) are details: ``-v`` prints them, with
every other warning in full. ``-q`` keeps the summary line and the cases that failed, timed out
or were interrupted.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from preform.base.status import MEANING, CaseStatus
from preform.step import WARNING_CAUSES

if TYPE_CHECKING:
    from preform.pipeline.runner import CaseResult, RunReport

#: Console verbosity: ``-q``, the default, ``-v``.
QUIET, NORMAL, VERBOSE = -1, 0, 1

#: Line prefixes of cases that have no result; they go to stderr (``cli``).
PROBLEM_PREFIXES = ("FAILED", "TIMED OUT", "INTERRUPTED")

#: Rank of a status on the console, the worst first.
_STATUS_RANK = {
    CaseStatus.FAILED: 0,
    CaseStatus.TIMED_OUT: 1,
    CaseStatus.INTERRUPTED: 2,
    CaseStatus.PARTIAL: 3,
}

#: Rank of a warning's cause, the worst first: where the fabric would wrinkle, then energy
#: resting on no measurement, then what a step names otherwise; locking (the tows touch and
#: the fabric stiffens, it does not wrinkle) last.
_CAUSE_RANK = {
    "past jamming": 0,
    "past stitch failure": 0,
    "beyond the law's data": 1,
    "past locking": 3,
}
_OTHER_CAUSE_RANK = 2


@dataclass(frozen=True)
class Cause:
    """The warnings of one case that share a cause: how many, and the largest shares."""

    name: str
    count: int
    area_share: float | None
    energy_share: float | None
    #: The warning itself when the cause has one and no share to state: its words say more
    #: than the cause's name ("tool mesh: re-wound 12 triangles ...", not "tool mesh").
    only: str | None = None

    @property
    def rank(self) -> tuple[int, float]:
        return (_CAUSE_RANK.get(self.name, _OTHER_CAUSE_RANK), -(self.area_share or 0.0))

    def words(self) -> str:
        """ "8.3 % of the part past jamming (39 % of its energy)"."""
        if self.only is not None and self.area_share is None and self.energy_share is None:
            return self.only
        text = self.name
        if self.area_share is not None:
            text = f"{_percent(self.area_share)} % of the part {self.name}"
        if self.energy_share is not None:
            text += f" ({_percent(self.energy_share)} % of its energy)"
        if self.count > 1:
            text += f" ({self.count} warnings)"
        return text


def _percent(share: float) -> str:
    """A share in per cent with as many digits as tell it from zero: 8.3, 0.026."""
    percent = 100.0 * share
    return f"{percent:.1f}" if percent >= 0.1 or percent == 0 else f"{percent:.2g}"


def case_causes(warnings: list[str], results: Mapping[str, Any]) -> tuple[list[Cause], int, int]:
    """A case's warnings grouped by cause, the worst first; how many have no cause (a step
    that names none: counted, shown in full with ``-v``); how many are about sampled angles.
    """
    notes = {
        int(n["warning"]): n
        for n in results.get(WARNING_CAUSES) or []
        if isinstance(n, Mapping) and isinstance(n.get("warning"), int)
    }
    grouped: dict[str, list[Mapping[str, Any]]] = {}
    texts: dict[str, list[str]] = {}
    unnamed = scanned = 0
    for index, warning in enumerate(warnings):
        note = notes.get(index, {})
        if note.get("scan"):
            scanned += 1
        elif note.get("cause"):
            grouped.setdefault(str(note["cause"]), []).append(note)
            texts.setdefault(str(note["cause"]), []).append(str(warning))
        else:
            unnamed += 1
    causes = [
        Cause(
            name,
            len(group),
            _largest(group, "area_share"),
            _largest(group, "energy_share"),
            only=texts[name][0] if len(group) == 1 else None,
        )
        for name, group in grouped.items()
    ]
    return sorted(causes, key=lambda c: c.rank), unnamed, scanned


def _largest(notes: Iterable[Mapping[str, Any]], key: str) -> float | None:
    values = [float(n[key]) for n in notes if isinstance(n.get(key), int | float)]
    return max(values) if values else None


def _case_line(result: CaseResult, label: str) -> str | None:
    """One line for a case that is not plainly ok, or None for a plainly ok one."""
    kept = " (kept from an earlier run)" if result.reused else ""
    status = CaseStatus(result.status)
    if status == CaseStatus.FAILED:
        return f"FAILED {result.case_id}: {result.error}"
    if status == CaseStatus.TIMED_OUT:
        return f"TIMED OUT {result.case_id}: {result.error}"
    if status == CaseStatus.INTERRUPTED:
        return f"INTERRUPTED {result.case_id}: not finished; rerun to compute it"
    causes, unnamed, _ = case_causes(result.warnings, result.results)
    said = [c.words() for c in causes]
    if unnamed:
        said.append(f"{unnamed} other warning(s)")
    if status == CaseStatus.PARTIAL:
        covered = result.results.get("covered_fraction")
        share = f" covers {100 * covered:.1f} % of what the scene asked;" if covered else ""
        also = f"; also {', '.join(said)}" if said else ""
        return f"PARTIAL {result.case_id}{kept}:{share} " + "; ".join(result.reasons) + also
    if not said:
        return None
    return f"{label}{kept}: ok; " + ", ".join(said)


def _severity(result: CaseResult) -> tuple[int, tuple[int, float]]:
    status = CaseStatus(result.status)
    causes, unnamed, _ = case_causes(result.warnings, result.results)
    worst = causes[0].rank if causes else ((_OTHER_CAUSE_RANK, 0.0) if unnamed else (9, 0.0))
    return (_STATUS_RANK.get(status, 4), worst)


def run_report_lines(report: RunReport, verbosity: int = NORMAL) -> list[str]:
    """The end of a run in words: the counts by status, then at most one line per case
    (``verbosity`` NORMAL), the worst first; ``QUIET`` keeps the counts and the cases without a
    result; ``VERBOSE`` gives every case's warnings in full and the status legend."""
    counts = report.counts()
    summary = f"{len(report.results)} case(s) -> {report.out_dir}/: " + ", ".join(
        f"{n} {s}" for s, n in sorted(counts.items())
    )
    scenes = {r.scene for r in report.results}
    ordered = sorted(report.results, key=_severity)
    if verbosity >= VERBOSE:
        return [summary, *_verbose_lines(report, ordered)]
    lines = []
    for r in ordered:
        line = _case_line(r, r.material if len(scenes) == 1 else r.case_id)
        if line is None or (verbosity <= QUIET and not line.startswith(PROBLEM_PREFIXES)):
            continue
        lines.append(line)
    shown = sorted({CaseStatus(r.status) for r in report.results} - {CaseStatus.OK})
    if shown and verbosity > QUIET:  # what a status means, on the summary line: no extra line
        summary += " (" + "; ".join(f"{s.value} = {MEANING[s]}" for s in shown) + ")"
    if verbosity > QUIET:
        warned = sum(1 for line in lines if not line.startswith((*PROBLEM_PREFIXES, "PARTIAL")))
        if warned:
            summary += (
                f"; {warned} with warnings, the worst first (in full: -v, each case's "
                "summary.json, results.csv)"
            )
    if report.interrupted:
        lines.append(
            "INTERRUPTED: finished cases are kept; run the same command again to do the rest."
        )
    return [summary, *lines]


def _verbose_lines(report: RunReport, ordered: list[CaseResult]) -> list[str]:
    """Every case without a plain ``ok`` in words, every warning in full (those about sampled
    angles too), and the status legend (``-v``: the console before issue 26, ordered)."""
    lines = []
    for r in ordered:
        if r.status != CaseStatus.OK:
            lines.append(str(_case_line(r, r.case_id)))
        kept = " (kept from an earlier run)" if r.reused else ""
        for warning in r.warnings:
            lines.append(f"WARNING {r.case_id}{kept}: {warning}")
    shown = sorted({CaseStatus(r.status) for r in report.results} - {CaseStatus.OK})
    if shown:
        lines.append("status: " + "; ".join(f"{s.value} = {MEANING[s]}" for s in shown))
    if report.interrupted:
        lines.append(
            "INTERRUPTED: finished cases are kept; run the same command again to do the rest."
        )
    return lines
