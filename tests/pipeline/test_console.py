"""The end of a run on the console (issue 26): the counts, then at most one line per case, the
worst first; every warning in full only with -v; -q keeps the counts and the failures."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from preform.pipeline.console import NORMAL, QUIET, VERBOSE, case_causes, run_report_lines
from preform.pipeline.runner import CaseResult, RunReport
from preform.step import WARNING_CAUSES


def _case(name: str, status: str = "ok", **kw: Any) -> CaseResult:
    return CaseResult(f"scene/{name}", name, "scene", status, **kw)


def _noted(*notes: tuple[str, dict[str, Any]]) -> dict[str, Any]:
    """``warnings`` and ``results`` of a case whose warnings carry these notes."""
    return {
        "warnings": [message for message, _ in notes],
        "results": {WARNING_CAUSES: [{"warning": i, **n} for i, (_, n) in enumerate(notes)]},
    }


def _report(tmp_path: Path) -> RunReport:
    return RunReport(
        tmp_path,
        [
            _case("clean"),
            _case("scanned", **_noted(("at angles 30°..", {"scan": True, "cause": None}))),
            _case(
                "locked",
                **_noted(("past locking words", {"cause": "past locking", "area_share": 0.4})),
            ),
            _case(
                "jammed",
                **_noted(
                    ("locking words", {"cause": "past locking", "area_share": 0.25}),
                    ("jam 1", {"cause": "past jamming", "area_share": 0.02, "energy_share": 0.1}),
                    ("jam 2", {"cause": "past jamming", "area_share": 0.05, "energy_share": 0.3}),
                ),
            ),
            _case("plugin", warnings=["a plugin says so, naming no cause"]),
            _case(
                "half", "partial", reasons=["the net stopped"], results={"covered_fraction": 0.5}
            ),
            _case("gone", "failed", error="the drape placed no cell"),
        ],
    )


def test_one_line_per_case_that_is_not_plainly_ok_worst_first(tmp_path: Path) -> None:
    summary, *lines = run_report_lines(_report(tmp_path), NORMAL)
    assert summary.startswith(f"7 case(s) -> {tmp_path}/: 1 failed, 5 ok, 1 partial")
    assert "partial = finite, but covers less" in summary and "3 with warnings" in summary
    assert lines == [
        "FAILED scene/gone: the drape placed no cell",
        "PARTIAL scene/half: covers 50.0 % of what the scene asked; the net stopped",
        # two warnings of one cause: counted once, at the larger share, before locking
        "jammed: ok; 5.0 % of the part past jamming (30.0 % of its energy) (2 warnings), "
        "25.0 % of the part past locking",
        "plugin: ok; 1 other warning(s)",
        "locked: ok; 40.0 % of the part past locking",
    ]


def test_quiet_keeps_the_counts_and_the_failures(tmp_path: Path) -> None:
    lines = run_report_lines(_report(tmp_path), QUIET)
    assert lines == [
        f"7 case(s) -> {tmp_path}/: 1 failed, 5 ok, 1 partial",
        "FAILED scene/gone: the drape placed no cell",
    ]


def test_verbose_gives_every_warning_in_full(tmp_path: Path) -> None:
    lines = run_report_lines(_report(tmp_path), VERBOSE)
    for warning in ("at angles 30°..", "jam 1", "jam 2", "a plugin says so, naming no cause"):
        assert sum(line.endswith(f": {warning}") for line in lines) == 1
    assert lines[-1].startswith("status: failed = no result")


def test_causes_group_count_and_keep_scans_apart() -> None:
    data = _noted(
        ("a", {"cause": "past locking", "area_share": 0.1}),
        ("b", {"scan": True}),
        ("c", {"cause": "past locking", "area_share": 0.3}),
    )
    causes, unnamed, scanned = case_causes([*data["warnings"], "d"], data["results"])
    assert [(c.name, c.count, c.area_share) for c in causes] == [("past locking", 2, 0.3)]
    assert (unnamed, scanned) == (1, 1)


@pytest.fixture(scope="module")
def draft_study(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str]]:
    """The default study at draft fidelity (a few seconds), its results folder and console."""
    out = tmp_path_factory.mktemp("study") / "results"
    proc = _preform("pipeline", "run", "--fidelity", "draft", "--workers", "1", "--out", out)
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout.splitlines()


def _preform(*args: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "preform", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_the_default_study_prints_at_most_a_line_per_fabric(
    draft_study: tuple[Path, list[str]],
) -> None:
    out, (summary, *lines) = draft_study
    fabrics = json.loads(_preform("materials", "list", "--json").stdout)
    assert summary.startswith(f"{len(fabrics)} case(s) -> {out}/: {len(fabrics)} ok")
    assert 0 < len(lines) <= len(fabrics)
    # each line is one fabric's, the fabrics whose result (not a sampled angle) was warned of
    records = {p.parent.name: json.loads(p.read_text()) for p in out.glob("*/*/summary.json")}
    warned = {
        name
        for name, record in records.items()
        if any(not note["scan"] for note in record.get(WARNING_CAUSES, []))
        or len(record["warnings"]) > len(record.get(WARNING_CAUSES, []))
    }
    assert sorted(line.split(":")[0] for line in lines) == sorted(warned)
    assert not any("generator angle(s)" in line for line in lines)  # sampled angles: details
    # a share on the console is the one in summary.json (wrinkling's own number)
    for line in lines:
        name = line.split(":")[0]
        share = records[name].get("wrinkle_past_jamming_area_share")
        if share:
            shown = float(line.split(" % of the part past jamming")[0].split()[-1])
            assert shown == pytest.approx(100 * share, rel=0.05, abs=0.05)


def test_quiet_and_verbose_on_the_same_results(draft_study: tuple[Path, list[str]]) -> None:
    out, _ = draft_study
    quiet = _preform("-q", "pipeline", "run", "--fidelity", "draft", "--out", out)
    cases = len(list(out.glob("*/*/summary.json")))
    assert quiet.returncode == 0 and quiet.stdout.splitlines() == [
        f"{cases} case(s) -> {out}/: {cases} skipped"
    ]
    verbose = _preform("pipeline", "run", "-v", "--fidelity", "draft", "--out", out)
    every = [w for p in out.glob("*/*/summary.json") for w in json.loads(p.read_text())["warnings"]]
    assert len(verbose.stdout.splitlines()) == 1 + len(every)
    assert "generator angle(s)" in verbose.stdout
    both = _preform("-q", "pipeline", "run", "-v", "--out", out, "--fidelity", "draft")
    assert both.returncode == 0 and len(both.stdout.splitlines()) == 1 + len(every)  # -v wins
