"""``preform shear`` (curves of a library fabric's law) and ``preform fit`` (test data → law).

The lead adds ``shear_command`` and ``fit_command`` to the ``preform`` click group. The work is
done by plain functions (``shear_curves``, ``plot_shear_curves``, ``fit_report``) that take a
``ShearLaw`` or arrays, so they can be used and tested without a library.

JSON of ``shear --json``::

    {"material": NAME, "law": LAW NAME, "locking_angle_deg": float | null,
     "failure_angle_deg": float | null,
     "positive": [{"angle_deg", "torque_N_per_m", "force_N_per_mm", "energy_J_per_m2"}, ...],
     "negative": [... same keys ...]}

"positive" is shear parallel to the reference direction (stitch), γ > 0; "negative" holds the
same angle magnitudes with γ < 0, its angle, torque and force signed (negative), its energy ≥ 0.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import click
import numpy as np
from numpy.typing import ArrayLike

from preform.command_line import (
    InputError,
    echo_json,
    fabric_or_exit,
    file_option,
    json_option,
    library_options,
    load_library_or_exit,
)
from preform.shear.fit import (
    PolynomialFit,
    TableFit,
    block_to_yaml,
    fit_polynomial,
    fit_table,
    shear_law_block,
)
from preform.shear.law import ShearLaw, force_per_length_N_per_mm
from preform.shear.testdata import normalise_bias_extension, normalise_picture_frame


def parse_angles(spec: str) -> np.ndarray:
    """Angles [deg] from "START:STOP:STEP" (STOP included when on the grid), all ≥ 0."""
    try:
        start, stop, step = (float(part) for part in spec.split(":"))
    except ValueError as error:
        raise ValueError(f"angles must be START:STOP:STEP, got {spec!r}") from error
    if step <= 0.0 or stop < start or start < 0.0 or stop >= 90.0:
        raise ValueError("need 0 ≤ START ≤ STOP < 90 and STEP > 0")
    count = math.floor((stop - start) / step + 1e-9) + 1
    return start + step * np.arange(count)


def shear_curves(
    law: ShearLaw, angles_deg: ArrayLike, material: str = "", law_name: str = ""
) -> dict[str, Any]:
    """Torque [N·m/m²], F_s/L [N/mm] and energy [J/m²] of both senses at angle magnitudes [deg]."""
    magnitudes = np.abs(np.asarray(angles_deg, dtype=float))

    def sense(sign: float) -> list[dict[str, float]]:
        gamma = sign * np.radians(magnitudes)
        torque = law.torque(gamma)
        force = force_per_length_N_per_mm(law, gamma)
        energy = law.energy(gamma)
        return [
            {
                "angle_deg": float(sign * a),
                "torque_N_per_m": float(t),
                "force_N_per_mm": float(f),
                "energy_J_per_m2": float(e),
            }
            for a, t, f, e in zip(magnitudes, torque, force, energy, strict=True)
        ]

    def degrees(angle: float | None) -> float | None:
        return None if angle is None else math.degrees(angle)

    return {
        "material": material,
        "law": law_name,
        "locking_angle_deg": degrees(law.locking_angle),
        "failure_angle_deg": degrees(law.failure_angle),
        "positive": sense(1.0),
        "negative": sense(-1.0),
    }


def plot_shear_curves(curves: dict[str, Any], path: str | Path) -> None:
    """Write a PNG with F_s/L and energy against |γ| for both senses (cf. paper Figs 8–9)."""
    from preform.shear.figures import shear_curve_figure

    title = f"{curves.get('material', '')} ({curves.get('law', '')})"
    shear_curve_figure(curves, path, title=title)


def _law_name(entry: Any) -> str:
    block = getattr(entry, "shear_law", None) or entry.default_shear_law()
    name = block.get("law") if isinstance(block, dict) else getattr(block, "law", None)
    return str(name or "")


@click.command("shear")
@click.argument("name")
@click.option("--angles", default="0:60:5", show_default=True, help="START:STOP:STEP [deg].")
@file_option(
    "--out", "figure", help="Write the force and energy curves as a figure (.png, .svg, .pdf)."
)
@click.option("--png", "png", type=click.Path(dir_okay=False), hidden=True)  # old name of --out
@library_options
@json_option
def shear_command(
    name: str,
    angles: str,
    figure: str | None,
    png: str | None,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """Print the shear force and energy curves of fabric NAME, both senses."""
    try:
        grid = parse_angles(angles)
    except ValueError as error:
        raise click.BadParameter(str(error), param_hint="--angles") from error
    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric = fabric_or_exit(lib, name)
    curves = shear_curves(lib.shear_law(name), grid, name, _law_name(fabric))
    path = figure or png
    if path:
        plot_shear_curves(curves, path)
    if as_json:
        echo_json(curves)
        return
    click.echo(f"{name}: law {curves['law']}")
    click.echo(f"{'|γ| deg':>8} {'F+ N/mm':>10} {'W+ J/m²':>10} {'F- N/mm':>10} {'W- J/m²':>10}")
    for pos, neg in zip(curves["positive"], curves["negative"], strict=True):
        click.echo(
            f"{pos['angle_deg']:8.2f} {pos['force_N_per_mm']:10.4f} {pos['energy_J_per_m2']:10.4f}"
            f" {abs(neg['force_N_per_mm']):10.4f} {neg['energy_J_per_m2']:10.4f}"
        )
    if path:
        click.echo(f"wrote {path}")


#: Units a test file's column may be written in, with their factor to mm and N.
_DISPLACEMENT_UNITS = {"": 1.0, "mm": 1.0, "cm": 10.0, "m": 1000.0}
_FORCE_UNITS = {"": 1.0, "n": 1.0, "kn": 1000.0}
#: Column words (lower case, unit removed) read as displacement, force and sense.
_COLUMN_WORDS = {
    "displacement": "displacement_mm",
    "disp": "displacement_mm",
    "extension": "displacement_mm",
    "elongation": "displacement_mm",
    "crosshead displacement": "displacement_mm",
    "force": "force_N",
    "load": "force_N",
    "sense": "sense",
}


def _column(header: str) -> tuple[str | None, str]:
    """(canonical column, unit) of a header cell: ``displacement``, ``displacement_mm``,
    ``Displacement (mm)``, ``displacement [mm]``, ``Force (kN)``... (None when unknown)."""
    text = header.strip().lower()
    unit = ""
    bracketed = re.fullmatch(r"(.*?)\s*[(\[]\s*([a-z]*)\s*[)\]]", text)
    if bracketed:
        text, unit = bracketed.group(1), bracketed.group(2)
    else:
        suffixed = re.fullmatch(r"(.*?)_(mm|cm|m|n|kn)", text)
        if suffixed:
            text, unit = suffixed.group(1), suffixed.group(2)
    word = re.sub(r"[\s_]+", " ", text).strip()
    return _COLUMN_WORDS.get(word), unit


def read_test_csv(path: str | Path) -> list[dict[str, str]]:
    """Rows of a shear-test file as ``{"displacement_mm", "force_N"[, "sense"]}`` (text).

    The header names a displacement and a force column in any of the usual spellings
    (``displacement, force``, ``displacement_mm,force_N``, ``Displacement (mm),Force (N)``,
    spaces after the commas, any case); displacement in mm (or cm, m) and force in N (or kN),
    converted to mm and N; without a unit, mm and N. Lines starting with ``#`` before the header
    and blank lines are skipped. A ValueError says the file and line of what is wrong.
    """
    with open(path, newline="", encoding="utf-8-sig") as handle:
        lines = [
            (number, line)
            for number, line in enumerate(handle, start=1)
            if line.strip() and not line.lstrip().startswith("#")
        ]
    if not lines:
        raise ValueError(f"{path}: no header and no data")
    header_line, header = lines[0]
    cells = next(csv.reader([header]))
    columns: dict[str, tuple[int, float]] = {}
    for index, cell in enumerate(cells):
        name, unit = _column(cell)
        if name is None:
            continue
        units = _DISPLACEMENT_UNITS if name == "displacement_mm" else _FORCE_UNITS
        if name != "sense" and unit not in units:
            known = ", ".join(u for u in units if u)
            raise ValueError(
                f"{path}:{header_line}: column {cell.strip()!r}: unit {unit!r} is not one of {known}"
            )
        columns.setdefault(name, (index, 1.0 if name == "sense" else units[unit]))
    missing = [n for n in ("displacement_mm", "force_N") if n not in columns]
    if missing:
        raise ValueError(
            f"{path}:{header_line}: need a displacement and a force column (e.g. "
            f"'displacement, force' or 'displacement_mm,force_N'), got {header.strip()!r}"
        )
    rows: list[dict[str, str]] = []
    for number, line in lines[1:]:
        values = [v.strip() for v in next(csv.reader([line]))]
        row: dict[str, str] = {}
        for name, (index, factor) in columns.items():
            if index >= len(values):
                raise ValueError(f"{path}:{number}: missing the {name} column")
            if name == "sense":
                row[name] = values[index]
                continue
            try:
                value = float(values[index])
            except ValueError:
                raise ValueError(
                    f"{path}:{number}: {name}: {values[index]!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise ValueError(f"{path}:{number}: {name}: {values[index]!r} is not finite")
            row[name] = repr(value * factor)
        rows.append(row)
    if not rows:
        raise ValueError(f"{path}:{header_line}: a header but no data rows")
    return rows


@dataclass
class FitReport:
    """What ``preform fit`` found: the ``shear_law`` block, comment lines on its quality, and
    per sense the normalised data (angle [deg], F_s/L [N/mm]) and the fit drawn against it."""

    block: dict[str, Any]
    comments: list[str]
    through_zero: bool
    data: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    fits: dict[str, PolynomialFit | TableFit] = field(default_factory=dict)
    #: Per sense, the constant a free fit of the same degree gives [N/mm] (polynomials forced
    #: through zero only): how far the data are from passing through zero.
    free_intercept_N_per_mm: dict[str, float] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        senses = {}
        for sense, fit in self.fits.items():
            q = fit.quality
            senses[sense] = {
                "r_squared": q.r_squared,
                "rmse_N_per_mm": q.rmse_N_per_mm,
                "points": q.points,
                "free_intercept_N_per_mm": self.free_intercept_N_per_mm.get(sense),
            }
        return {
            "shear_law": self.block,
            "through_zero": self.through_zero,
            "senses": senses,
            "comments": self.comments,
        }


def normalise_rows(
    rows: list[dict[str, str]],
    test: str,
    side_mm: float | None = None,
    height_mm: float | None = None,
    width_mm: float | None = None,
    fabric_side_mm: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rows of :func:`read_test_csv` → (γ [deg], F_s/L [N/mm]) in order of displacement."""
    delta = np.array([float(r["displacement_mm"]) for r in rows])
    force = np.array([float(r["force_N"]) for r in rows])
    order = np.argsort(delta, kind="stable")
    if test == "picture-frame":
        if side_mm is None:
            raise ValueError("picture-frame needs --side-mm")
        result = normalise_picture_frame(delta[order], force[order], side_mm, fabric_side_mm)
    elif test == "bias-extension":
        if height_mm is None or width_mm is None:
            raise ValueError("bias-extension needs --height-mm and --width-mm")
        result = normalise_bias_extension(delta[order], force[order], height_mm, width_mm)
    else:
        raise ValueError(f"unknown test {test!r}")
    return np.degrees(result.shear_angle), result.force_per_length_N_per_mm


def fit_report(
    rows: list[dict[str, str]],
    test: str,
    side_mm: float | None = None,
    height_mm: float | None = None,
    width_mm: float | None = None,
    fabric_side_mm: float | None = None,
    sense: str = "parallel",
    degree: int | None = 3,
    step_deg: float = 2.0,
    through_zero: bool = True,
) -> FitReport:
    """Normalise test rows and fit them (:class:`FitReport`: the block, its quality, the data).

    ``degree=None`` gives a tabulated law. ``sense="both"`` needs a ``sense`` column
    (parallel/perpendicular) and gives an asymmetric law; one sense gives a symmetric law from
    the rows of that sense (all rows when there is no ``sense`` column). ``through_zero``:
    polynomials without a constant term (see ``preform.shear.fit.fit_polynomial``).
    """

    def normalise(selected: list[dict[str, str]]) -> tuple[np.ndarray, np.ndarray]:
        return normalise_rows(
            selected,
            test,
            side_mm=side_mm,
            height_mm=height_mm,
            width_mm=width_mm,
            fabric_side_mm=fabric_side_mm,
        )

    def select(which: str) -> list[dict[str, str]]:
        if "sense" not in rows[0]:
            if sense == "both":
                raise ValueError("--sense both needs a 'sense' column")
            return rows
        chosen = [r for r in rows if r["sense"].strip().lower() == which]
        if not chosen:
            raise ValueError(f"no rows with sense {which!r}")
        return chosen

    senses = ["parallel", "perpendicular"] if sense == "both" else [sense]
    report = FitReport({}, [], through_zero)
    for which in senses:
        angle, force = normalise(select(which))
        report.data[which] = (angle, force)
        if degree:
            report.fits[which] = fit_polynomial(angle, force, degree, through_zero=through_zero)
            if through_zero:
                free = fit_polynomial(angle, force, degree, through_zero=False)
                report.free_intercept_N_per_mm[which] = free.coefficients_N_per_mm[0]
        else:
            report.fits[which] = fit_table(angle, force, step_deg)
    fits = [report.fits[s] for s in senses]
    report.block = shear_law_block(fits[0], fits[1] if len(fits) > 1 else None)
    comments = [f"fitted by preform fit from {test} data ({', '.join(senses)})"]
    if degree:
        comments.append(
            f"polynomial of degree {degree} "
            + (
                "forced through zero (no constant term; --free-intercept fits one)"
                if through_zero
                else "with a fitted constant term (--free-intercept)"
            )
        )
    for s, f in zip(senses, fits, strict=True):
        q = f.quality
        line = f"{s}: R² = {q.r_squared:.4f}, RMSE = {q.rmse_N_per_mm:.4g} N/mm, {q.points} points"
        if s in report.free_intercept_N_per_mm:
            line += f"; a free fit's constant would be {report.free_intercept_N_per_mm[s]:.3g} N/mm"
        comments.append(line)
    if sense == "perpendicular":
        comments.append("perpendicular data only: the block is symmetric; merge as negative sense")
    report.comments = comments
    return report


def plot_fit(report: FitReport, path: str | Path, title: str | None = None) -> None:
    """The fitted F_s/L against the normalised test data [N/mm over deg], one colour per sense."""
    from preform.shear.figures import fit_figure

    curves = {}
    for sense, fit in report.fits.items():
        angle, force = report.data[sense]
        grid = np.linspace(0.0, float(np.max(np.abs(angle))), 200)
        if isinstance(fit, PolynomialFit):
            model = fit(grid)
        else:
            model = np.interp(grid, fit.angle_deg, fit.force_N_per_mm)
        q = fit.quality
        curves[sense] = {
            "data": (np.abs(angle), np.abs(force)),
            "fit": (grid, model),
            "label": f"{sense}: R² = {q.r_squared:.3f}, RMSE {q.rmse_N_per_mm:.3g} N/mm",
        }
    fit_figure(curves, path, title=title)


def specimen_options(func: Any) -> Any:
    """``--test`` and the specimen's sizes, as ``fit`` and ``calibrate`` take them."""
    for option in reversed(
        (
            click.option(
                "--test", type=click.Choice(["picture-frame", "bias-extension"]), required=True
            ),
            click.option("--side-mm", type=float, help="Picture-frame side, pin to pin [mm]."),
            click.option(
                "--fabric-side-mm", type=float, help="Cruciform specimen: sheared fabric side [mm]."
            ),
            click.option("--height-mm", type=float, help="Bias-extension specimen height H [mm]."),
            click.option("--width-mm", type=float, help="Bias-extension specimen width W [mm]."),
        )
    ):
        func = option(func)
    return func


@click.command("fit")
@click.argument("data", type=click.Path(exists=True, dir_okay=False))
@specimen_options
@click.option(
    "--sense", type=click.Choice(["parallel", "perpendicular", "both"]), default="parallel"
)
@click.option("--degree", type=int, default=3, show_default=True, help="0: tabulated law.")
@click.option(
    "--through-zero/--free-intercept",
    default=True,
    show_default=True,
    help="Polynomial without a constant term, so F(0) = 0 (an unsheared fabric carries no "
    "force), or with a fitted one. The comments give a free fit's constant either way.",
)
@click.option("--step-deg", type=float, default=2.0, show_default=True, help="Table bin [deg].")
@file_option("--out", help="Write the YAML block to FILE instead of printing it.")
@file_option("--plot", help="Write the fit against the data as a figure (.png, .svg, .pdf).")
@json_option
def fit_command(
    data: str,
    test: str,
    side_mm: float | None,
    fabric_side_mm: float | None,
    height_mm: float | None,
    width_mm: float | None,
    sense: str,
    degree: int,
    through_zero: bool,
    step_deg: float,
    out: str | None,
    plot: str | None,
    as_json: bool,
) -> None:
    """Normalise a shear test (DATA.csv: displacement, force[, sense]) and fit a law.

    The header may read "displacement, force", "displacement_mm,force_N" or
    "Displacement (mm),Force (N)" (any case; cm, m and kN are converted).

    Prints the shear_law YAML block (with its fit quality as comments), or writes it to --out;
    --json prints the block, the quality per sense and the files written.
    """
    try:
        report = fit_report(
            read_test_csv(data),
            test,
            side_mm=side_mm,
            height_mm=height_mm,
            width_mm=width_mm,
            fabric_side_mm=fabric_side_mm,
            sense=sense,
            degree=degree or None,
            step_deg=step_deg,
            through_zero=through_zero,
        )
    except ValueError as error:
        raise InputError(str(error)) from error
    text = block_to_yaml(report.block, report.comments)
    if out:
        from preform.base.atomic import atomic_open

        with atomic_open(out, "w", encoding="utf-8") as handle:
            handle.write(text)
    if plot:
        plot_fit(report, plot, title=f"{Path(data).name}: {test} fit")
    if as_json:
        echo_json({**report.as_json(), "files": {"yaml": out, "plot": plot}})
        return
    if not out:
        click.echo(text, nl=False)
        return
    for line in report.comments[1:]:
        click.echo(line)
    for path in (out, plot):
        if path:
            click.echo(f"wrote {path}")
