"""The report of a real run, opened in headless Chromium: no console error, no request but the
file itself and its data: pictures, every case and number of results.csv in the page, the
cases that need reading first, and a 3-D view that draws.

Skipped without Chromium, except under CI (``CI`` set), where .ci/run installs it.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from preform.cli import cli
from preform.report import REPORT_NAME

SMALL_PLY = """\
name: small-ply
tool: {surface: hemisphere, radius_mm: 100}
ply: {node_spacing_mm: 5, size_mm: [240, 240]}
start: {point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90, generators: geodesic}
outputs: [drape, cells_csv, cut_pattern]
"""

#: Everything the page shows of its tables, read in the browser.
READ_TABLES = """JSON.stringify(Array.from(document.querySelectorAll('td[data-col]')).map(td => {
  const tr = td.closest('tr'), details = td.closest('details.case'), table = td.closest('table');
  return {case: (tr && tr.dataset.case) || (details && details.dataset.case) || '',
          table: table.id || table.className, col: td.dataset.col, value: td.dataset.value,
          text: td.textContent};
}))"""


def _run(*args: str) -> None:
    result = CliRunner().invoke(cli, ["pipeline", "run", "--engine", "serial", *args])
    assert result.exit_code in (0, 1), result.output


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two runs into one folder: shear curves and a drape with its cut pattern (ok), then a
    case stopped at a 1 ms time limit (timed_out), whose run writes the report."""
    root = tmp_path_factory.mktemp("report-run")
    scene = root / "small-ply.yaml"
    scene.write_text(SMALL_PLY)
    out = root / "out"
    _run("--scene", "shear", "--scene", str(scene), "--materials", "plain-weave-600",
         "--out", str(out), "--no-report")  # fmt: skip
    _run("--scene", "hemisphere", "--materials", "E-BX-318", "--case-timeout", "0.001",
         "--out", str(out))  # fmt: skip
    assert (out / REPORT_NAME).is_file()
    return out


def results_rows(root: Path) -> dict[str, dict[str, str]]:
    with open(root / "results.csv", newline="", encoding="utf-8") as f:
        return {f"{r['scene']}/{r['material']}": r for r in csv.DictReader(f)}


def open_report(browser: Any, root: Path) -> float:
    """Load the folder's report with the network switched off; the seconds it took."""
    browser.events.clear()
    browser.call(
        "Network.emulateNetworkConditions",
        offline=True,
        latency=0,
        downloadThroughput=-1,
        uploadThroughput=-1,
    )
    seconds = float(browser.open(root / REPORT_NAME))
    browser.wait_for("window.preformReport && window.preformReport.ready")
    return seconds


def check_page(browser: Any, root: Path) -> None:
    """No error, no request, every case and every number of results.csv, in the browser."""
    errors = browser.console_errors()
    assert errors == []
    allowed = (root / REPORT_NAME).resolve().as_uri()
    requests = browser.requests()
    assert requests and requests[0] == allowed
    assert all(url == allowed or url.startswith("data:") for url in requests), requests
    rows = results_rows(root)
    cells = json.loads(browser.evaluate(READ_TABLES))
    shown = {c["case"] for c in cells if c["table"] == "results"}
    assert shown == set(rows)  # every case, and nothing else
    checked = 0
    for cell in cells:
        if cell["table"] not in ("results", "summary"):
            continue
        expected = rows[cell["case"]][cell["col"]]
        assert cell["value"] == expected, cell
        try:
            number = float(expected)
        except ValueError:
            continue
        assert float(cell["text"]) == pytest.approx(number, rel=5e-4, abs=0), cell
        checked += 1
    assert checked >= 10 * len(rows)


def draw_first_3d_view(browser: Any) -> np.ndarray:
    """Open the first case with a 3-D view, wait until plotly drew it, and take a screenshot
    of it (RGB, 0..1)."""
    import matplotlib.image

    browser.evaluate(
        "(() => { const d = document.querySelector('.plot-3d').closest('details');"
        " d.open = true; d.querySelector('.plot-3d').scrollIntoView({block: 'center'});"
        " return true; })()"
    )
    browser.wait_for("document.querySelector('.plot-3d').dataset.drawn === 'done'")
    assert browser.evaluate("document.querySelectorAll('.plot-3d canvas').length") >= 1
    rect = browser.evaluate(
        "(() => { const r = document.querySelector('.plot-3d').getBoundingClientRect();"
        " return [r.left + scrollX, r.top + scrollY, r.width, r.height]; })()"
    )
    png = browser.screenshot({"x": rect[0], "y": rect[1], "width": rect[2], "height": rect[3]})
    return np.asarray(matplotlib.image.imread(io.BytesIO(png), format="png"))[..., :3]


def assert_drawn(image: np.ndarray) -> None:
    """A surface is drawn: a good share of the view is neither white nor grey, and it holds
    many colours (the shear colour scale), not one flat fill."""
    saturation = image.max(axis=2) - image.min(axis=2)
    coloured = saturation > 0.15
    assert coloured.mean() > 0.05, f"only {coloured.mean():.1%} of the view is coloured"
    colours = np.unique((image[coloured] * 31).round().astype(int), axis=0)
    assert len(colours) > 30


def test_the_report_opens_offline_without_error_or_request(browser, run_folder):
    open_report(browser, run_folder)
    check_page(browser, run_folder)


def test_the_case_that_timed_out_comes_first_with_why(browser, run_folder):
    open_report(browser, run_folder)
    order = browser.evaluate(
        "Array.from(document.querySelectorAll('details.case')).map(d => d.dataset.case)"
    )
    assert order[0] == "hemisphere/E-BX-318"
    assert sorted(order[1:]) == ["shear/plain-weave-600", "small-ply/plain-weave-600"]
    first = browser.evaluate("document.querySelector('ul.attention li').textContent")
    assert first.startswith("timed_out hemisphere/E-BX-318: stopped at the case time limit")


def test_the_3d_view_draws(browser, run_folder):
    open_report(browser, run_folder)
    assert_drawn(draw_first_3d_view(browser))
    assert browser.console_errors() == []


def test_a_page_that_asks_the_network_fails_the_check(browser, run_folder, tmp_path):
    """The check of requests and console errors is not blind: a copy of the page with one
    picture from a server (refused by the page's policy, and offline anyway) fails it."""
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(run_folder, copy)
    page = (copy / REPORT_NAME).read_text(encoding="utf-8")
    page = page.replace("<main>", '<main><img src="https://example.invalid/x.png">', 1)
    (copy / REPORT_NAME).write_text(page, encoding="utf-8")
    open_report(browser, copy)
    assert any("example.invalid" in e for e in browser.console_errors())
    with pytest.raises(AssertionError):
        check_page(browser, copy)


def test_a_blank_view_is_told_from_a_drawn_one():
    """The check of the screenshot fails a white view, and a view of one flat colour."""
    with pytest.raises(AssertionError):
        assert_drawn(np.ones((100, 100, 3)))
    flat = np.ones((100, 100, 3))
    flat[20:80, 20:80] = (0.2, 0.4, 0.8)
    with pytest.raises(AssertionError):
        assert_drawn(flat)


@pytest.mark.slow
def test_the_default_studys_report(browser, tmp_path, monkeypatch):
    """The issue's numbers: the bundled default study (ten fabrics) gives a page under 15 MB
    that opens offline in under 5 s, with every case and number, and draws its 3-D view."""
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["pipeline", "run"])
    assert result.exit_code in (0, 1), result.output
    root = tmp_path / "preform-results"
    size = (root / REPORT_NAME).stat().st_size
    assert size < 15e6
    assert len(results_rows(root)) >= 10
    seconds = open_report(browser, root)
    assert seconds < 5.0
    check_page(browser, root)
    assert_drawn(draw_first_3d_view(browser))
