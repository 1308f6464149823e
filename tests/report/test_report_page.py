"""The report page's HTML, read back with the standard library's HTML parser: what it shows,
in which order, the numbers against results.csv, and that a folder always gives the same page."""

from __future__ import annotations

import csv
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import example, given, settings
from hypothesis import strategies as st

from preform.cli import cli
from preform.report import REPORT_NAME, build_report, write_report
from preform.report.gather import NET_MAX_CELLS, cause_of, csv_columns, read_net, read_run
from preform.report.render import display_number, render_page


class Page(HTMLParser):
    """The parts of the page the tests read: table cells with their row and section, case
    sections in order, figure specifications, scripts, images."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, dict[str, str]]] = []
        self.cells: list[dict[str, str]] = []  # data-col, data-value, text, table id, case
        self.cases: list[dict[str, str]] = []  # details.case in order
        self.rows: list[dict[str, str]] = []  # rows of #results
        self.attention: list[str] = []  # text of the items of ul.attention
        self.specs: dict[str, str] = {}
        self.scripts: list[dict[str, str]] = []
        self.images: list[str] = []
        self.links: list[str] = []
        self._text: list[str] | None = None
        self._li: list[str] | None = None
        self._script: list[str] | None = None
        self.feed(text)

    def _within(self, tag: str, **attrs: str) -> dict[str, str] | None:
        for t, a in reversed(self.stack):
            if t == tag and all(a.get(k) == v for k, v in attrs.items()):
                return a
        return None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag in ("img", "meta", "input", "br"):
            if tag == "img":
                self.images.append(a.get("src", ""))
            return
        self.stack.append((tag, a))
        if tag == "td" and "data-col" in a:
            self._text = []
        elif tag == "details" and "case" in a.get("class", "").split():
            self.cases.append(a)
        elif tag == "tr" and self._within("table", id="results"):
            self.rows.append(a)
        elif tag == "li" and self._within("ul", **{"class": "attention"}):
            self._li = []
        elif tag == "script":
            self.scripts.append(a)
            self._script = []
        elif tag == "a":
            self.links.append(a.get("href", ""))

    def handle_endtag(self, tag: str) -> None:
        while self.stack:
            t, a = self.stack.pop()
            if t == tag:
                break
        if tag == "td" and self._text is not None and "data-col" in a:
            table = self._within("table") or {}
            case = self._within("details", **{"class": f"case st-{self._case_status()}"})
            self.cells.append(
                {
                    "col": a["data-col"],
                    "value": a["data-value"],
                    "text": "".join(self._text),
                    "table": table.get("id", table.get("class", "")),
                    "case": (case or {}).get("data-case", ""),
                    "row_case": (self._within("tr") or {}).get("data-case", ""),
                }
            )
            self._text = None
        elif tag == "li" and self._li is not None:
            self.attention.append("".join(self._li))
            self._li = None
        elif tag == "script" and self._script is not None:
            if a.get("type") == "application/json":
                self.specs[a["id"]] = "".join(self._script)
            self._script = None

    def _case_status(self) -> str:
        for t, a in reversed(self.stack):
            if t == "details" and "case" in a.get("class", "").split():
                return a["class"].split("st-")[-1]
        return ""

    def handle_data(self, data: str) -> None:
        for buffer in (self._text, self._li, self._script):
            if buffer is not None:
                buffer.append(data)


def results_csv(root: Path) -> list[dict[str, str]]:
    with open(root / "results.csv", newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_failed_and_partial_cases_come_first_with_their_reasons(made_run):
    page = Page(build_report(made_run))
    order = [c["data-case"] for c in page.cases]
    assert order == [
        "dome/E-BX-318",  # failed
        "dome/satin-<b>8hs</b>",  # partial
        "dome/plain-weave-600",
        "shear/plain-weave-600",
    ]
    assert [r["data-case"] for r in page.rows if "data-case" in r] == order
    assert "CaseFailure: the drape placed no cell" in page.attention[0]
    assert page.attention[1].startswith("partial dome/satin-<b>8hs</b>: covers 54.2 %")
    assert "the net covers 54.2 % of the ply's fabric area" in page.attention[1]
    assert len(page.attention) == 2  # ok cases are not listed as needing reading
    # a case that is not ok is open; an ok one is closed until asked for
    assert [("open" in c) for c in page.cases] == [True, True, False, False]


def test_every_number_in_the_page_is_the_one_in_results_csv(made_run):
    page = Page(build_report(made_run))
    rows = {f"{r['scene']}/{r['material']}": r for r in results_csv(made_run)}
    checked = 0
    for cell in page.cells:
        case = cell["row_case"] or cell["case"]
        if cell["table"] not in ("results", "summary"):
            continue
        expected = rows[case][cell["col"]]
        assert cell["value"] == expected, (case, cell)
        checked += 1
        try:
            number = float(expected)
        except ValueError:
            if cell["col"] != "material":
                assert cell["text"] == expected
            continue
        shown = float(cell["text"])
        assert shown == pytest.approx(number, rel=5e-4, abs=0), (case, cell)
    # every non-empty field of every row appears in its case's own table
    summary_cells = {(c["case"], c["col"]) for c in page.cells if c["table"] == "summary"}
    for case, row in rows.items():
        for col, value in row.items():
            if value != "":
                assert (case, col) in summary_cells
    assert checked > 4 * 10


@given(st.floats(allow_nan=False, allow_infinity=False, width=64))
def test_a_displayed_number_is_the_value_to_4_digits(value):
    shown = float(display_number(repr(value)))
    assert shown == pytest.approx(value, rel=5e-4, abs=0)
    assert display_number(str(int(value) if abs(value) < 1e15 else 7)) in (str(int(value)), "7")


def test_the_same_folder_gives_the_same_page_byte_for_byte(made_run):
    first = write_report(made_run).read_bytes()
    # the page itself (and the run's lock file) are not inputs of the page
    assert write_report(made_run).read_bytes() == first
    assert build_report(made_run).encode() == first
    result = CliRunner().invoke(cli, ["report", str(made_run)])
    assert result.exit_code == 0, result.output
    assert (made_run / REPORT_NAME).read_bytes() == first
    # nothing in it names the time it was written or a random id
    assert not re.search(rb"2026-12-03T1[3-9]", first)


def test_the_figures_are_what_the_summaries_hold(made_run):
    page = Page(build_report(made_run))
    specs = [json.loads(s) for s in page.specs.values()]
    energy = next(s for s in specs if "generator angle" in s["layout"]["xaxis"]["title"]["text"])
    curves = {t["name"]: t for t in energy["data"] if t.get("mode") == "lines+markers"}
    assert set(curves) == {"plain-weave-600", "satin-<b>8hs</b>"}  # the failed case has none
    assert curves["plain-weave-600"]["x"] == list(range(30, 151, 5))
    assert curves["plain-weave-600"]["y"][12] == pytest.approx(1.2)  # 90° is the 13th angle
    stars = [t for t in energy["data"] if t["mode"] == "markers"]
    # to 6 digits: more than the hover's 4
    found = sorted((t["x"][0], t["y"][0]) for t in stars)
    assert [x for x, _ in found] == [80.25, 90.0]
    assert [y for _, y in found] == pytest.approx([2.0000001, 1.2], rel=1e-6)
    force = next(s for s in specs if "force" in s["layout"]["yaxis"]["title"]["text"])
    assert [t["name"] for t in force["data"]] == [
        "plain-weave-600 (positive)",
        "plain-weave-600 (negative)",
    ]
    assert force["data"][1]["x"] == list(range(0, 61, 5))  # |γ| of the negative sense
    assert force["data"][1]["y"][-1] == pytest.approx(0.6)
    mesh = next(s for s in specs if s["data"][0]["type"] == "mesh3d")["data"][0]
    # every vertex lies on the 100 mm hemisphere and carries its own shear (x/10 degrees)
    for x, y, z, g in zip(mesh["x"], mesh["y"], mesh["z"], mesh["intensity"], strict=True):
        assert math.hypot(x, y, z) == pytest.approx(100, abs=0.02)
        assert g == pytest.approx(x / 10, abs=0.01)


def test_the_net_is_thinned_to_fit_and_stays_a_surface(tmp_path, cells_maker):
    from preform.export.csv_columns import rows_to_columns, write_csv_columns

    path = tmp_path / "cells.csv"
    n = 160  # 160 x 160 grid, of which the cells within the 100 mm radius are placed
    write_csv_columns(rows_to_columns(cells_maker(n, spacing_mm=1.25)), path)
    net, note = read_net(path)
    assert net is not None and note == ""
    placed = len(_grid(n, 1.25))
    assert net.cells_total == placed
    assert net.stride == math.ceil(math.sqrt(placed / NET_MAX_CELLS))
    assert len(net.x_mm) <= NET_MAX_CELLS
    assert all(0 <= v < len(net.x_mm) for t in net.triangles for v in t)
    # neighbouring kept cells are one stride apart: no triangle edge is longer than the
    # diagonal of a thinned cell, and the surface is whole (two triangles per inner quad)
    step = 1.25 * net.stride
    for a, b, c in net.triangles:
        for p, q in ((a, b), (b, c), (c, a)):
            # the synthetic grid is even in plan (x, y)
            d = math.dist((net.x_mm[p], net.y_mm[p]), (net.x_mm[q], net.y_mm[q]))
            assert d <= step * math.sqrt(2) + 0.02
    assert len(net.triangles) >= 1.8 * len(net.x_mm)
    assert net.marks_total == sum(1 for i, j in _grid(n, 1.25) if (i - n / 2) * 1.25 > 60)


def test_pandas_reads_a_cells_table_as_the_csv_module_does(tmp_path, cells_maker):
    """A run of many cases parses its tables with pandas (PANDAS_FROM_CASES): the same net."""
    from preform.export.csv_columns import rows_to_columns, write_csv_columns

    path = tmp_path / "cells.csv"
    write_csv_columns(rows_to_columns(cells_maker(60, spacing_mm=3.5)), path)
    assert read_net(path, by_pandas=True) == read_net(path)


_FIELD = st.one_of(
    st.just(""),
    st.floats(allow_nan=False).map(repr),
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from(["NA", "None", "nan", "N/A", "null", "True", "OK", "A, B", 'say "x"']),
)


@settings(deadline=None)  # the first example imports pandas
@given(rows=st.lists(st.tuples(_FIELD, _FIELD, _FIELD), max_size=12))
@example(rows=[("True", "1", "x")])  # pandas alone would read True as 1.0
@example(rows=[("", "NA", "NA"), ("1.5", "", "")])
def test_both_parsers_give_the_same_columns_or_both_refuse(tmp_path_factory, rows):
    """Numbers (an empty field NaN, a word refused) and texts (kept as written: "NA" is a
    word, not a gap), quoted fields with commas and quotes: the csv module and pandas agree."""
    path = tmp_path_factory.mktemp("table") / "t.csv"
    with open(path, "w", newline="", encoding="utf-8") as f:
        csv.writer(f, lineterminator="\n").writerows([("a", "b", "t"), *rows])
    results = []
    for by_pandas in (False, True):
        try:
            numbers, texts = csv_columns(path, {"a", "b"}, {"t"}, by_pandas)
        except ValueError:
            results.append(None)
        else:
            results.append(
                (
                    {k: v.tobytes() for k, v in numbers.items()},
                    {k: v.tolist() for k, v in texts.items()},
                )
            )
    assert results[0] == results[1]


def _grid(n: int, spacing: float) -> list[tuple[int, int]]:
    return [
        (i, j)
        for i in range(n)
        for j in range(n)
        if 100.0**2 - ((i - n / 2) * spacing) ** 2 - ((j - n / 2) * spacing) ** 2 > 0
    ]


def test_warnings_of_many_cases_group_by_their_cause():
    a = "1208 cells (7.5 % of the part's draped area) are sheared past the locking angle 39.2°"
    b = "412 cells (3.1 % of the part's draped area) are sheared past the locking angle 22.2°"
    c = (
        "at generator angle(s) 30°, 35°, 40° and 14 more the drape shears cells past 57.0°, "
        "where the law's fabric is jammed: E(α) there"
    )
    d = "at generator angle(s) 45°, 50° and 3 more the drape shears cells past 38.4°, where"
    assert cause_of(a) == cause_of(b) == "# cells"
    assert cause_of(c) == cause_of(d)
    assert cause_of(c) != cause_of(a)


def test_names_and_texts_are_escaped_never_markup(made_run):
    text = build_report(made_run)
    assert "<b>8hs</b>" not in text.replace("\\u003cb\\u003e8hs\\u003c/b\\u003e", "")
    assert "&lt;b&gt;8hs&lt;/b&gt;" in text
    page = Page(text)
    # only the page's own scripts: plotly.js, the figures' data and page.js
    kinds = [s.get("type", "") for s in page.scripts]
    assert kinds.count("") == 2 and set(kinds) <= {"", "application/json"}


def test_the_page_asks_nothing_of_any_server(made_run):
    text = build_report(made_run)
    policy = re.search(r'http-equiv="Content-Security-Policy" content="([^"]+)"', text)
    assert policy is not None and "default-src 'none'" in policy.group(1)
    page = Page(text)
    assert all(src.startswith("data:") for src in page.images)
    assert not [s for s in page.scripts if "src" in s]
    assert all(not re.match(r"[a-z]+://", link) for link in page.links), page.links


def test_without_plotly_the_page_says_how_to_get_the_figures(made_run):
    page_text = render_page(read_run(made_run), None)
    page = Page(page_text)
    assert page.specs == {}
    assert "pip install 'preform[report]'" in page_text
    assert len(page.cases) == 4 and len(page.rows) == 5  # the header row and four cases


def test_a_folder_with_missing_files_still_gives_a_page_that_says_so(made_run):
    (made_run / "dome" / "plain-weave-600" / "cells.csv").write_text("i,j\n1,2\n")
    (made_run / "manifest.json").unlink()
    text = build_report(made_run)
    assert "cells.csv lacks the columns" in text
    assert "manifest.json is missing or unreadable" in text


def test_report_command_refuses_what_is_not_a_run_folder(tmp_path):
    result = CliRunner().invoke(cli, ["report", str(tmp_path)])
    assert result.exit_code == 2
    assert "not a run folder" in result.stderr
    assert not (tmp_path / REPORT_NAME).exists()


def test_a_run_writes_its_report_and_the_command_writes_the_same_page(tmp_path):
    out = tmp_path / "run"
    args = ["pipeline", "run", "--scene", "shear", "--materials", "plain-weave-150"]
    args += ["--engine", "serial", "--out", str(out)]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 0, result.output
    written = (out / REPORT_NAME).read_bytes()
    assert b"plain-weave-150" in written
    (out / REPORT_NAME).unlink()
    result = CliRunner().invoke(cli, ["report", str(out), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["cases"] == 1
    assert (out / REPORT_NAME).read_bytes() == written
    quiet = tmp_path / "quiet"
    result = CliRunner().invoke(cli, [*args[:-1], str(quiet), "--no-report"])
    assert result.exit_code == 0 and not (quiet / REPORT_NAME).exists()


def test_a_fine_net_adds_little_to_the_page(tmp_path, run_maker):
    """A 160 x 160 cell net (some 20 000 placed cells, as the default study's) is thinned:
    the page without plotly.js stays under 400 kB, so ten such cases and plotly.js's 5 MB
    stay far below the 15 MB the issue allows."""
    root = run_maker(tmp_path / "run", n_grid=160)
    assert len(render_page(read_run(root), "").encode()) < 400_000


def test_a_report_that_cannot_be_written_never_fails_the_run(tmp_path, monkeypatch):
    import preform.report

    def broken(run_dir, run=None):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(preform.report, "write_report", broken)
    out = tmp_path / "run"
    args = ["pipeline", "run", "--scene", "shear", "--materials", "plain-weave-150"]
    result = CliRunner().invoke(cli, [*args, "--engine", "serial", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "warning: report.html was not written: OSError" in result.stderr
    assert (out / "results.csv").is_file() and not (out / REPORT_NAME).exists()


def test_a_file_list_cannot_reach_outside_the_folder(made_run):
    """summary.json is data: a listed picture that leads outside the run folder (by its name
    or by a symbolic link) is not read into the page."""
    import base64

    secret = made_run.parent / "secret.png"
    secret.write_bytes(b"\x89PNG secret")
    case_dir = made_run / "dome" / "plain-weave-600"
    (case_dir / "fibre_pattern.png").symlink_to(secret)
    summary = json.loads((case_dir / "summary.json").read_text())
    summary["files"] = ["../../../secret.png", "fibre_pattern.png", "cells.csv"]
    (case_dir / "summary.json").write_text(json.dumps(summary))
    text = build_report(made_run)
    assert base64.b64encode(secret.read_bytes()).decode() not in text
    case = next(c for c in read_run(made_run).cases if c.case_id == "dome/plain-weave-600")
    assert case.pictures == [] and case.net is not None
    # the same picture inside the folder is shown
    (case_dir / "fibre_pattern.png").unlink()
    (case_dir / "fibre_pattern.png").write_bytes(secret.read_bytes())
    assert base64.b64encode(secret.read_bytes()).decode() in build_report(made_run)
