"""``preform report DIR``: write (again) the report page of a run folder."""

from __future__ import annotations

from pathlib import Path

import click

from preform.command_line import EXIT_USAGE, echo_json, fail, json_option


@click.command("report")
@click.argument("run_dir", type=click.Path(), metavar="DIR")
@json_option
def report_command(run_dir: str, as_json: bool = False) -> None:
    """Write report.html of the run folder DIR: one page, offline, from its files only.

    The page a `pipeline run` writes at its end (unless --no-report): the run, cases that
    failed or are partial first with their reasons, warnings by cause, the results table,
    E(α) and shear curves, each case's 3-D drape and pictures. The same folder gives the same
    page. Exit code 2 when DIR is not a run folder or a run is writing into it.
    """
    from preform.pipeline.rundir import RunDirectory, RunDirectoryError
    from preform.report import plotly_bundle, write_report
    from preform.report.gather import read_run

    folder = Path(run_dir)
    if not folder.is_dir():
        fail([f"error: {run_dir} is not a directory; give a run folder (pipeline run --out)"])
    if not (folder / "results.csv").is_file() and not (folder / "manifest.json").is_file():
        fail(
            [
                f"error: {run_dir} holds neither results.csv nor manifest.json: it is not a "
                "run folder (pipeline run --out DIR writes one)"
            ]
        )
    try:
        with RunDirectory(folder):  # no run may write into it meanwhile
            run = read_run(folder)
            path = write_report(folder, run)
    except RunDirectoryError as exc:
        fail([f"error: {exc}; no report was written"], code=EXIT_USAGE)
    interactive = plotly_bundle() is not None
    if as_json:
        echo_json(
            {
                "report": str(path),
                "bytes": path.stat().st_size,
                "cases": len(run.cases),
                "counts": run.counts(),
                "interactive": interactive,
            }
        )
        return
    size_mb = path.stat().st_size / 1e6
    click.echo(f"{path} ({size_mb:.1f} MB, {len(run.cases)} case(s))")
    if not interactive:
        click.echo(
            "note: plotly is not installed, so the page has no interactive figure: "
            "pip install 'preform[report]'",
            err=True,
        )
