"""``preform compare``: a drape against measured fibre angles, and the set-up that explains them.

The work is ``preform.compare_drape`` (``preform.compare``); this module reads the command line
and writes what was asked: the per-point table (CSV), the points for ParaView (VTU), the error
map (PNG) and the summary (JSON), for the drape as the scene sets it up and, with
``--explain``, at the best set-up.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from preform.command_line import (
    EXIT_FAILED,
    InputError,
    echo_json,
    fabric_or_exit,
    json_option,
    library_options,
    load_library_or_exit,
)

VARY = ("start", "orientation", "generator_angle")


def _write(compared: Any, out: Path) -> dict[str, str]:
    """The comparison's files in ``out``; their names by kind."""
    from preform.base.atomic import atomic_open
    from preform.base.strict_json import clean_json
    from preform.compare.figure import error_map_figure
    from preform.compare.vtu import write_comparison_vtu

    out.mkdir(parents=True, exist_ok=True)
    files: dict[str, str] = {}
    result = compared.drape._product("drape").result
    stages = [("", compared.comparison, result, "as the scene sets it up")]
    if compared.explanation is not None:
        e = compared.explanation
        stages.append(("explained_", e.after, e.result, "at the best set-up"))
    for prefix, comparison, net, words in stages:
        table = out / f"{prefix}comparison.csv"
        with atomic_open(table, "w", encoding="utf-8") as handle:
            handle.write(f"# preform compare: measured against predicted fibre angles, {words}; "
                         "lengths in mm, angles in degrees (error = measured - predicted)\n")  # fmt: skip
            comparison.to_pandas().to_csv(handle, index=False)
        vtu = out / f"{prefix}comparison.vtu"
        write_comparison_vtu(comparison, vtu)
        png = out / f"{prefix}error_map.png"
        error_map_figure(comparison, net, png, title=f"{compared.drape.case.case_id}, {words}")
        files.update({f"{prefix}table": str(table), f"{prefix}vtu": str(vtu),
                      f"{prefix}figure": str(png)})  # fmt: skip
    summary = out / "summary.json"
    with atomic_open(summary, "w", encoding="utf-8") as handle:
        json.dump(clean_json({**compared.summary, "files": files}), handle, indent=2, default=str)
    files["summary"] = str(summary)
    return files


@click.command("compare")
@click.argument("name", metavar="FABRIC")
@click.argument("data", metavar="MEASUREMENT", type=click.Path(exists=True, dir_okay=False))
@click.option(
    "--scene",
    default="hemisphere",
    show_default=True,
    help="The scene whose drape is compared (a bundled scene's name or a file).",
)
@click.option(
    "--unit",
    type=click.Choice(["mm", "m"]),
    default="mm",
    show_default=True,
    help="Length unit of a point cloud's coordinates (a CSV says its own: x_mm or x_m).",
)
@click.option(
    "--max-gap-mm",
    type=float,
    default=None,
    help="Farthest a point may lie from the tool and the net [mm] (default: the node spacing).",
)
@click.option(
    "--explain",
    is_flag=True,
    help="Also search the set-up (start, orientation, generator angle) that best explains the "
    "measurement, with its uncertainty and the residual errors.",
)
@click.option(
    "--vary",
    default=",".join(VARY),
    show_default=True,
    help="What --explain varies: comma-separated, of start, orientation, generator_angle.",
)
@click.option(
    "--out",
    type=click.Path(file_okay=False),
    metavar="DIR",
    help="Write comparison.csv, comparison.vtu, error_map.png and summary.json (and "
    "explained_* with --explain) into DIR.",
)
@library_options
@json_option
def compare_command(
    name: str,
    data: str,
    scene: str,
    unit: str,
    max_gap_mm: float | None,
    explain: bool,
    vary: str,
    out: str | None,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """Compare fabric FABRIC's drape with measured fibre angles (MEASUREMENT).

    MEASUREMENT is a CSV, PLY or VTK file of measured fibre angles in mm and degrees
    (docs/compare.md). Per point the angle error of each fibre family and the
    shear difference, with flags; rms, max and percentiles, by region. Exit 1 when the drape
    failed; 2 for a bad measurement (a unit slip too)."""
    from preform.api import compare_drape
    from preform.base.status import CaseFailure
    from preform.compare.measurement import MeasurementError
    from preform.pipeline.scene import SceneError

    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric_or_exit(lib, name)
    varied = tuple(v.strip() for v in vary.split(",") if v.strip())
    if not varied or any(v not in VARY for v in varied):
        raise InputError(f"--vary takes some of {', '.join(VARY)}; got {vary!r}")
    try:
        compared = compare_drape(
            name, data, scene, library=lib, explain=explain, vary=varied,
            max_gap_mm=max_gap_mm, unit=unit,
        )  # fmt: skip
    except MeasurementError as error:
        raise InputError("\n".join(error.errors)) from error
    except (SceneError, FileNotFoundError, ValueError) as error:
        # a scene the search cannot vary (polyline generators), a --max-gap-mm of 0, ...
        raise InputError(str(error)) from error
    except CaseFailure as error:
        click.echo(f"error: the drape has no result: {error}", err=True)
        raise SystemExit(EXIT_FAILED) from error
    files = _write(compared, Path(out)) if out else {}
    if as_json:
        echo_json({**compared.summary, "files": files})
        return
    click.echo(f"{compared.drape.case.case_id} ({compared.status}): {compared.comparison.words()}")
    for region, stats in compared.comparison.summary()["by_region"].items():
        if "angle_rms_deg" in stats:
            click.echo(f"  {region}: {stats['points']} points, angle error rms "
                       f"{stats['angle_rms_deg']:.3g}°, max {stats['angle_max_deg']:.3g}°")  # fmt: skip
    if compared.explanation is not None:
        click.echo(compared.explanation.words())
    for path in files.values():
        click.echo(f"wrote {path}")
