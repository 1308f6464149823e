"""The run report: one self-contained web page of a run folder (``report.html``).

``write_report(run_dir)`` reads only the folder (``preform.report.gather``) and writes the page
(``preform.report.render``); ``preform pipeline run`` calls it at the end of a run (unless
``--no-report``) and ``preform report DIR`` rebuilds it. The interactive figures need plotly's
offline bundle (``pip install 'preform[report]'``); without it the page has the tables and
pictures and says how to get the figures.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from preform.report.gather import Run

#: The report's file name in a run folder.
REPORT_NAME = "report.html"


def plotly_bundle() -> str | None:
    """plotly.js (minified) from the installed plotly package, or None without it. Read as a
    file: importing plotly's Python package is not needed for the page."""
    import importlib.util

    spec = importlib.util.find_spec("plotly")
    if spec is None or not spec.submodule_search_locations:
        return None
    for folder in spec.submodule_search_locations:
        path = Path(folder) / "package_data" / "plotly.min.js"
        if path.is_file():
            return path.read_text(encoding="utf-8")
    return None


def build_report(run_dir: Path, run: Run | None = None) -> str:
    """The report page of the run folder ``run_dir`` (``run``: its contents, when already
    read), as HTML text."""
    from preform.report.gather import read_run
    from preform.report.render import render_page

    return render_page(run if run is not None else read_run(Path(run_dir)), plotly_bundle())


def write_report(run_dir: Path, run: Run | None = None) -> Path:
    """Write ``report.html`` into the run folder ``run_dir`` (atomically) and return its path.
    The caller holds the folder (a run's lock, or ``preform report``'s)."""
    from preform.base.atomic import atomic_open

    path = Path(run_dir) / REPORT_NAME
    text = build_report(Path(run_dir), run)
    with atomic_open(path) as f:
        f.write(text)
    return path


__all__ = ["REPORT_NAME", "build_report", "plotly_bundle", "write_report"]
