"""The run report as one self-contained HTML page: run, cases that need reading, warnings by
cause, the results table, per-scene curves, per-case 3-D drape and pictures, the trade study.

Everything is inside the page (plotly.js once, pictures as data: URIs, figures as JSON), and
its Content-Security-Policy forbids any request, so it opens offline and can be sent as one
file. The same folder gives the same text: no clock, no random ids, ordered input.
"""

from __future__ import annotations

import base64
import html
import json
import math
import re
from collections.abc import Iterable
from importlib import resources
from typing import Any
from urllib.parse import quote

from preform.base import __version__
from preform.base.status import MEANING, CaseStatus
from preform.report import figures
from preform.report.gather import CaseData, Run, cause_of, warnings_by_cause

#: Columns of the results table (those results.csv has), in this order; every column is in
#: each case's own table.
KEY_COLUMNS = (
    "material",
    "scene",
    "status",
    "covered_fraction",
    "optimum_generator_angle_deg",
    "optimum_energy_J",
    "total_energy_J",
    "max_abs_shear_deg",
    "wrinkle_area_share",
    "locking_angle_deg",
    "wall_time_s",
)
#: Rows of a case's trade table shown: the summary's columns of the search, in this order.
TRADE_COLUMNS = (
    "generator_angle_deg",
    "energy_J",
    "coverage",
    "wrinkle_area_share",
    "wrinkle_energy_share",
    "max_abs_shear_deg",
    "makeable",
)
#: No request of any kind: scripts and styles are inline, pictures are data: URIs.
CSP = (
    "default-src 'none'; script-src 'unsafe-inline' 'unsafe-eval'; "
    "style-src 'unsafe-inline'; img-src data:; font-src data:"
)

_esc = html.escape


def case_anchor(case_id: str) -> str:
    """The page's id of a case's section (letters, digits, '-', '_' and '.')."""
    return "case-" + re.sub(r"[^A-Za-z0-9_.-]", "-", case_id.replace("/", "--"))


def display_number(text: str) -> str:
    """A table cell's text: numbers to 4 significant digits (integers whole), the rest as it
    is. The cell's ``data-value`` keeps the file's text."""
    if text in ("", "True", "False"):
        return text
    try:
        value = float(text)
    except ValueError:
        return text
    if re.fullmatch(r"[-+]?\d+", text.strip()):
        return text.strip()
    shown = f"{value:.4g}"
    # rounding up past the largest float would read back as infinity: keep the full value
    return shown if math.isfinite(float(shown)) or not math.isfinite(value) else repr(value)


def _cell(column: str, text: str, *, sort_key: str | None = None, inner: str = "") -> str:
    key = f' data-key="{_esc(sort_key)}"' if sort_key is not None else ""
    body = inner or _esc(display_number(text))
    return f'<td data-col="{_esc(column)}" data-value="{_esc(text)}"{key}>{body}</td>'


def _script_json(obj: Any) -> str:
    """JSON safe inside a <script> element (no '</script>', no HTML comment opener)."""
    text = json.dumps(obj, ensure_ascii=False, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


class _Figures:
    """The page's figures: each a placeholder div and its specification, drawn by page.js
    when it scrolls into view (a closed case's 3-D view is released again)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.count = 0

    def place(self, spec: dict[str, Any] | None, kind: str) -> str:
        if spec is None:
            return ""
        if not self.enabled:
            return (
                '<p class="note">This interactive figure needs plotly.js, which was not '
                "installed when the page was written: <code>pip install 'preform[report]'"
                "</code>, then <code>preform report DIR</code>.</p>"
            )
        self.count += 1
        fig_id = f"fig-{self.count}"
        return (
            f'<div class="plot plot-{kind}" data-spec="{fig_id}"></div>'
            f'<script type="application/json" id="{fig_id}">{_script_json(spec)}</script>'
        )


def _run_section(run: Run) -> str:
    last = run.last_run
    settings = last.get("settings") if isinstance(last.get("settings"), dict) else {}
    assert isinstance(settings, dict)
    inputs = last.get("inputs") if isinstance(last.get("inputs"), dict) else {}
    assert isinstance(inputs, dict)
    fidelities = sorted({c.row.get("fidelity", "") for c in run.cases} - {""})
    facts = [
        ("folder", run.name),
        ("runs into it", str(len(run.manifest.get("runs") or []))),
        ("last run started", str(last.get("started", "unknown"))),
        ("last run finished", str(last.get("finished", "not finished"))),
        ("last run's status", str(last.get("status", "unknown"))),
        ("preform (run)", str(last.get("preform_version", "unknown"))),
        ("engine", str(settings.get("engine", "unknown"))),
        ("workers", str(settings.get("workers") or "all cores")),
        ("fidelity", ", ".join(fidelities) or "not recorded"),
    ]
    if inputs.get("fidelity_override"):
        facts.append(("fidelity override", str(inputs["fidelity_override"])))
    if settings.get("scheduler"):
        facts.append(("scheduler", str(settings["scheduler"])))
    rows = "".join(f"<tr><th>{_esc(k)}</th><td>{_esc(v)}</td></tr>" for k, v in facts)
    counts = run.counts()
    badges = " ".join(
        f'<span class="badge st-{_esc(s)}">{n} {_esc(s)}</span>' for s, n in counts.items()
    )
    this_run = last.get("counts") if isinstance(last.get("counts"), dict) else {}
    assert isinstance(this_run, dict)
    this_run_text = ", ".join(f"{n} {s}" for s, n in sorted(this_run.items()))
    files = []
    for kind in ("libraries", "scenes"):
        for item in inputs.get(kind) or []:
            if isinstance(item, dict):
                digest = str(item.get("sha256", ""))
                files.append(
                    f"<tr><td>{_esc(kind[:-1] if kind == 'scenes' else 'library')}</td>"
                    f"<td>{_esc(str(item.get('path', '')))}</td>"
                    f'<td><code title="sha256 {_esc(digest)}">{_esc(digest[:16])}</code></td></tr>'
                )
    bundled = inputs.get("bundled_library")
    plugins = [
        f"{p.get('name')} {p.get('version')}"
        + (f" (failed: {p.get('error')})" if p.get("error") else "")
        for p in last.get("plugins") or []
        if isinstance(p, dict)
    ]
    legend = "; ".join(
        f"<b>{_esc(s.value)}</b> = {_esc(MEANING[s])}" for s in CaseStatus if s.value in counts
    )
    return (
        '<section id="run"><h2>The run</h2>'
        f'<table class="facts">{rows}</table>'
        f'<p class="counts">Cases in this folder: {badges}'
        + (f" (the last run: {_esc(this_run_text)})" if this_run_text else "")
        + "</p>"
        + (f'<p class="legend">{legend}</p>' if legend else "")
        + (
            '<h3>Inputs of the last run</h3><table class="inputs"><tr><th>kind</th><th>path</th>'
            f"<th>SHA-256</th></tr>{''.join(files)}</table>"
            if files
            else ""
        )
        + (
            f"<p>Bundled library {'included' if bundled else 'left out'}.</p>"
            if bundled is not None
            else ""
        )
        + (f"<p>Plugins: {_esc(', '.join(plugins))}</p>" if plugins else "")
        + "".join(f'<p class="problem">{_esc(p)}</p>' for p in run.problems)
        + "</section>"
    )


def _attention_section(cases: list[CaseData]) -> str:
    """Cases that are not plainly ok, failed first, with why."""
    items = []
    for case in cases:
        if case.status == CaseStatus.OK.value:
            continue
        why = [case.error] if case.error else []
        why += case.reasons
        share = case.row.get("covered_fraction", "")
        if case.status == CaseStatus.PARTIAL.value and share:
            why.insert(0, f"covers {100 * float(share):.1f} % of what the scene asked")
        known = case.status in {s.value for s in CaseStatus}
        text = "; ".join(why) or (MEANING[CaseStatus(case.status)] if known else "")
        items.append(
            f'<li class="st-{_esc(case.status)}"><span class="badge st-{_esc(case.status)}">'
            f'{_esc(case.status)}</span> <a href="#{case_anchor(case.case_id)}">'
            f"{_esc(case.case_id)}</a>: {_esc(text)}</li>"
        )
    if not items:
        return ""
    return (
        '<section id="attention"><h2>Cases that need reading</h2>'
        f'<ul class="attention">{"".join(items)}</ul></section>'
    )


def _warnings_section(cases: list[CaseData]) -> str:
    groups = warnings_by_cause(cases)
    if not groups:
        return ""
    parts = []
    for cause, items in groups.items():
        n_cases = len({c for c, _ in items})
        lines = "".join(
            f'<li><a href="#{case_anchor(c)}">{_esc(c)}</a>: {_esc(w)}</li>' for c, w in items
        )
        parts.append(
            f'<details><summary>{_esc(cause)} <span class="n">({n_cases} case'
            f"{'s' if n_cases != 1 else ''})</span></summary><ul>{lines}</ul></details>"
        )
    return f'<section id="warnings"><h2>Warnings, by cause</h2>{"".join(parts)}</section>'


def _results_section(run: Run) -> str:
    columns = [c for c in KEY_COLUMNS if c in run.columns]
    head = "".join(f"<th>{_esc(c)}</th>" for c in [*columns, "reasons / error"])
    body = []
    for rank, case in enumerate(run.cases):
        cells = []
        for col in columns:
            text = case.row.get(col, "") if case.row else ""
            if col == "material":
                link = f'<a href="#{case_anchor(case.case_id)}">{_esc(text or case.material)}</a>'
                cells.append(_cell(col, text or case.material, inner=link))
            elif col == "status":
                cells.append(_cell(col, case.status, sort_key=f"{rank:06d}"))
            else:
                cells.append(_cell(col, text))
        why = "; ".join(([case.error] if case.error else []) + case.reasons)
        # long reasons fold to three lines; the whole text is the cell's title and the case's
        cells.append(
            f'<td class="why"><div class="clamp" title="{_esc(why)}">{_esc(why)}</div></td>'
        )
        body.append(
            f'<tr class="st-{_esc(case.status)}" data-case="{_esc(case.case_id)}" '
            f'data-status="{_esc(case.status)}">{"".join(cells)}</tr>'
        )
    statuses = sorted({c.status for c in run.cases})
    options = "".join(f'<option value="{_esc(s)}">{_esc(s)}</option>' for s in statuses)
    return (
        '<section id="results-section"><h2>Results</h2>'
        '<p class="tools"><input id="filter" type="search" placeholder="filter rows" '
        'aria-label="filter rows"> <select id="status-filter" aria-label="status">'
        f'<option value="">every status</option>{options}</select> '
        "Click a column to sort. Numbers to 4 digits; each case's table below has every "
        "column of results.csv.</p>"
        f'<div class="scroll"><table id="results"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table></div></section>"
    )


def scene_figures(run: Run) -> dict[str, list[dict[str, Any]]]:
    """Each scene's curves (E(α), shear force, shear energy), scenes without any left out."""
    out = {}
    for scene in run.scenes():
        cases = [c for c in run.cases if c.scene == scene]
        specs = [
            figures.energy_vs_angle(scene, cases),
            figures.shear_curves(scene, cases, "force_N_per_mm"),
            figures.shear_curves(scene, cases, "energy_J_per_m2"),
        ]
        if any(specs):
            out[scene] = [s for s in specs if s is not None]
    return out


def _scene_anchor(scene: str) -> str:
    return "scene-" + re.sub(r"[^A-Za-z0-9_.-]", "-", scene)


def _scene_sections(by_scene: dict[str, list[dict[str, Any]]], figs: _Figures) -> str:
    return "".join(
        f'<section class="scene" id="{_esc(_scene_anchor(scene))}"><h2>Scene {_esc(scene)}</h2>'
        + "".join(figs.place(spec, "2d") for spec in specs)
        + "</section>"
        for scene, specs in by_scene.items()
    )


def _trade_table(case: CaseData) -> str:
    table = case.summary.get("energy_vs_angle_table")
    if not isinstance(table, list) or not table:
        return ""
    head = "".join(f"<th>{_esc(c)}</th>" for c in TRADE_COLUMNS)
    rows = []
    for row in table:
        if isinstance(row, dict):
            cells = "".join(
                _cell(c, "" if row.get(c) is None else str(row.get(c))) for c in TRADE_COLUMNS
            )
            rows.append(f"<tr>{cells}</tr>")
    return (
        "<details><summary>Energy/wrinkle trade table of the search "
        f'({len(rows)} angles)</summary><table class="trade"><tr>{head}</tr>'
        f"{''.join(rows)}</table></details>"
    )


def _case_section(case: CaseData, columns: list[str], figs: _Figures) -> str:
    status = _esc(case.status)
    headline = []
    for col, fmt in (("optimum_generator_angle_deg", "α* = {}°"), ("optimum_energy_J", "E = {} J")):
        text = case.row.get(col, "")
        if text:
            headline.append(fmt.format(display_number(text)))
    why = "".join(f'<li class="error">{_esc(case.error)}</li>' for _ in [0] if case.error)
    why += "".join(f"<li>{_esc(r)}</li>" for r in case.reasons)
    warn = "".join(f"<li>{_esc(w)}</li>" for w in case.warnings)
    problems = "".join(f'<p class="problem">{_esc(p)}</p>' for p in case.problems)
    if case.net is not None:
        net = case.net
        thinned = (
            f"one cell in {net.stride} along each fibre direction, of {net.cells_total} placed"
            if net.stride > 1
            else f"all {net.cells_total} placed cells"
        )
        marks = (
            f"; {net.marks_total} cells wrinkle, fold or lie past a limit (crosses"
            + (f", {len(net.marks)} of them shown" if len(net.marks) < net.marks_total else "")
            + ")"
            if net.marks_total
            else "; no cell wrinkles, folds or lies past a limit"
        )
        view = figs.place(figures.drape_3d(case, net), "3d") + (
            f'<p class="caption">The draped ply through its cell centres ({thinned}){marks}. '
            "Drag to rotate, scroll to zoom.</p>"
        )
    else:
        view = f'<p class="note">{_esc(case.net_note)}</p>' if case.net_note else ""
    pictures = "".join(
        f'<figure><img alt="{_esc(caption)}" src="data:{mime};base64,'
        f'{base64.b64encode(data).decode("ascii")}"><figcaption>{_esc(caption)} '
        f"({_esc(name)})</figcaption></figure>"
        for name, caption, mime, data in case.pictures
    )
    table_rows = "".join(
        f"<tr><th>{_esc(col)}</th>{_cell(col, case.row[col])}</tr>"
        for col in columns
        if case.row.get(col, "") != ""
    )
    links = "".join(
        f'<li><a href="{_esc(quote(f"{case.folder}/{name}"))}">{_esc(name)}</a></li>'
        for name in case.files
    )
    is_open = " open" if case.status != CaseStatus.OK.value else ""
    return (
        f'<details class="case st-{status}" id="{case_anchor(case.case_id)}" '
        f'data-case="{_esc(case.case_id)}"{is_open}><summary><span class="badge st-{status}">'
        f"{status}</span> {_esc(case.case_id)}"
        + (f' <span class="headline">{_esc(", ".join(headline))}</span>' if headline else "")
        + "</summary>"
        + (f'<ul class="why">{why}</ul>' if why else "")
        + (
            f'<details class="warnings"><summary>{len(case.warnings)} warning'
            f"{'s' if len(case.warnings) != 1 else ''}</summary><ul>{warn}</ul></details>"
            if warn
            else ""
        )
        + problems
        + view
        + (f'<div class="pictures">{pictures}</div>' if pictures else "")
        + _trade_table(case)
        + (
            f"<details><summary>Summary (every column of results.csv)</summary>"
            f'<table class="summary">{table_rows}</table></details>'
            if table_rows
            else ""
        )
        + (
            f'<p class="files">Files in {_esc(case.folder)}/:</p><ul class="files">{links}</ul>'
            if links
            else ""
        )
        + "</details>"
    )


def _tradeoff_section(run: Run, figs: _Figures) -> str:
    if run.tradeoff is None:
        return ""
    columns, rows = run.tradeoff
    head = "".join(f"<th>{_esc(c)}</th>" for c in columns)
    body = "".join(
        "<tr>" + "".join(_cell(c, row.get(c) or "") for c in columns) + "</tr>" for row in rows
    )
    return (
        '<section id="tradeoff"><h2>Trade study (tradeoff.csv)</h2>'
        + figs.place(figures.tradeoff_plot(columns, rows), "2d")
        + f'<div class="scroll"><table class="trade"><tr>{head}</tr>{body}</table></div></section>'
    )


def _asset(name: str) -> str:
    return resources.files("preform.report").joinpath(name).read_text(encoding="utf-8")


def render_page(run: Run, plotly_js: str | None) -> str:
    """The page's HTML for ``run``; ``plotly_js`` is the plotly.js bundle to embed (None:
    the page has no interactive figure and says how to get them)."""
    figs = _Figures(plotly_js is not None)
    by_scene = scene_figures(run)
    body = (
        _run_section(run)
        + _attention_section(run.cases)
        + _warnings_section(run.cases)
        + _results_section(run)
        + _scene_sections(by_scene, figs)
        + _tradeoff_section(run, figs)
        + '<section id="cases"><h2>Cases</h2>'
        + "".join(_case_section(c, run.columns, figs) for c in run.cases)
        + "</section>"
    )
    nav = "".join(f'<a href="#{a}">{_esc(t)}</a>' for a, t in _nav(run, by_scene))
    plotly = f"<script>{plotly_js}</script>" if plotly_js is not None else ""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{CSP}">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<meta name="generator" content="preform {_esc(__version__)}">'
        f"<title>preform run report: {_esc(run.name)}</title>"
        f"<style>{_asset('page.css')}</style></head><body>"
        f"<header><h1>preform run report: {_esc(run.name)}</h1><nav>{nav}</nav></header>"
        f"<main>{body}</main>"
        f"<footer>Written by preform {_esc(__version__)} from the files of this folder only; "
        "<code>preform report DIR</code> writes the same page again.</footer>"
        # plotly.js last: the tables show while it is read
        f"{plotly}<script>{_asset('page.js')}</script></body></html>\n"
    )


def _nav(run: Run, by_scene: dict[str, list[dict[str, Any]]]) -> Iterable[tuple[str, str]]:
    yield "run", "run"
    if any(c.status != CaseStatus.OK.value for c in run.cases):
        yield "attention", "needs reading"
    if any(c.warnings for c in run.cases):
        yield "warnings", "warnings"
    yield "results-section", "results"
    for scene in by_scene:
        yield _scene_anchor(scene), scene
    if run.tradeoff is not None:
        yield "tradeoff", "trade study"
    yield "cases", "cases"


__all__ = ["case_anchor", "cause_of", "display_number", "render_page"]
