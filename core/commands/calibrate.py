"""``preform calibrate``: fit a fabric's mechanistic-law constants to a measured shear test.

The work is ``preform.calibrate`` (``preform.shear.calibrate``); this module reads the command
line and the library, and writes what was asked (YAML library file, figure, JSON).
"""

from __future__ import annotations

from pathlib import Path

import click

from preform.command_line import (
    InputError,
    echo_json,
    fabric_or_exit,
    file_option,
    json_option,
    library_options,
    load_library_or_exit,
)
from preform.shear.commands import specimen_options


@click.command("calibrate")
@click.argument("name", metavar="FABRIC")
@click.argument("data", type=click.Path(exists=True, dir_okay=False))
@specimen_options
@click.option(
    "--param",
    "params",
    multiple=True,
    metavar="PATH[=LO:HI]",
    help="A constant to fit, by its path in the fabric's entry (shear_law.pretension_N, "
    "threads[0].failure_strain), with bounds in the entry's units (repeatable). Default: "
    "the law's default constants, bounds value/20 to 20×value within the plausible range.",
)
@click.option(
    "--max-angle-deg",
    type=float,
    default=None,
    help="Fit the points up to this shear angle [deg] (default: all).",
)
@click.option(
    "--weights",
    type=click.Choice(["relative", "absolute"]),
    default="relative",
    show_default=True,
    help="Residuals relative to the measured force (floored at 5 % of its peak: scatter that "
    "grows with force) or in N/mm (minimises the reported rms).",
)
@file_option("--out", help="Write the calibrated entry (and --apply-to's) as a library YAML file.")
@file_option(
    "--plot", help="Write the data against the calibrated law as a figure (.png, .svg, .pdf)."
)
@click.option(
    "--apply-to",
    "apply_to",
    default=None,
    metavar="GLOB",
    help="Also write calibrated entries for the library's fabrics matching GLOB that are "
    "built from the same tows (fibre, tex, width, height) with the same law.",
)
@library_options
@json_option
def calibrate_command(
    name: str,
    data: str,
    test: str,
    side_mm: float | None,
    fabric_side_mm: float | None,
    height_mm: float | None,
    width_mm: float | None,
    params: tuple[str, ...],
    max_angle_deg: float | None,
    weights: str,
    out: str | None,
    plot: str | None,
    apply_to: str | None,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """Fit constants of fabric FABRIC's law to a shear test (DATA.csv: displacement, force).

    Prints the fit quality, each constant with its standard uncertainty (linearised) and their
    correlation; --out writes the calibrated entry as a library file with its provenance,
    --plot the data against the law; --json prints the report.
    """
    from preform.api import calibrate
    from preform.shear.calibrate import CalibrationError, transfers

    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric_or_exit(lib, name)
    try:
        calibration = calibrate(
            name,
            data,
            test=test,
            side_mm=side_mm,
            fabric_side_mm=fabric_side_mm,
            height_mm=height_mm,
            width_mm=width_mm,
            constants=list(params) or None,
            max_angle_deg=max_angle_deg,
            weights=weights,
            library=lib,
        )
        carried = transfers(calibration, lib, apply_to) if apply_to else []
    except (CalibrationError, ValueError) as error:
        raise InputError(str(error)) from error
    written = [t.entry for t in carried if t.entry is not None]
    if out:
        from preform.base.atomic import atomic_open

        with atomic_open(out, "w", encoding="utf-8") as handle:
            handle.write(calibration.to_yaml(written))
    if plot:
        calibration.plot(plot, title=f"{name}: calibrated on {Path(data).name}")
    if as_json:
        echo_json(
            {
                **calibration.as_json(),
                "apply_to": [t.as_json() for t in carried],
                "files": {"yaml": out, "plot": plot},
            }
        )
        return
    for line in calibration.comment_lines():
        click.echo(line)
    for t in carried:
        verdict = f"wrote {t.entry['name']}" if t.entry is not None else "skipped"
        click.echo(f"apply to {t.fabric}: {verdict}: {t.reason}")
    if not out:
        click.echo("(no --out: nothing written; --out FILE writes the calibrated entry)")
    for path in (out, plot):
        if path:
            click.echo(f"wrote {path}")
