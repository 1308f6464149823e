"""``preform shear`` (curves of a library fabric's law) and ``preform fit`` (test data → law).

The lead adds ``shear_command`` and ``fit_command`` to the ``preform`` click group. The work is
done by plain functions (``shear_curves``, ``plot_shear_curves``, ``fit_test_data``) that take a
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
import json
import math
from pathlib import Path
from typing import Any

import click
import numpy as np
from numpy.typing import ArrayLike

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
    from preform.export.fig_curves import shear_curve_figure

    title = f"{curves.get('material', '')} ({curves.get('law', '')})"
    shear_curve_figure(curves, path, title=title)


def _law_name(entry: Any) -> str:
    block = getattr(entry, "shear_law", None) or entry.default_shear_law()
    name = block.get("law") if isinstance(block, dict) else getattr(block, "law", None)
    return str(name or "")


@click.command("shear")
@click.argument("name")
@click.option("--angles", default="0:60:5", show_default=True, help="START:STOP:STEP [deg].")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option("--png", type=click.Path(dir_okay=False), help="Write force and energy plots.")
@click.option(
    "--library", "libraries", multiple=True, type=click.Path(exists=True), help="Extra library."
)
def shear_command(
    name: str, angles: str, as_json: bool, png: str | None, libraries: tuple[str, ...]
) -> None:
    """Print the shear force and energy curves of fabric NAME, both senses."""
    from preform.library import load_library  # the library loads plugins: import on use

    try:
        grid = parse_angles(angles)
    except ValueError as error:
        raise click.BadParameter(str(error), param_hint="--angles") from error
    lib = load_library(list(libraries))
    curves = shear_curves(lib.shear_law(name), grid, name, _law_name(lib.fabric(name)))
    if png:
        plot_shear_curves(curves, png)
    if as_json:
        click.echo(json.dumps(curves, indent=2))
        return
    click.echo(f"{name}: law {curves['law']}")
    click.echo(f"{'|γ| deg':>8} {'F+ N/mm':>10} {'W+ J/m²':>10} {'F- N/mm':>10} {'W- J/m²':>10}")
    for pos, neg in zip(curves["positive"], curves["negative"], strict=True):
        click.echo(
            f"{pos['angle_deg']:8.2f} {pos['force_N_per_mm']:10.4f} {pos['energy_J_per_m2']:10.4f}"
            f" {abs(neg['force_N_per_mm']):10.4f} {neg['energy_J_per_m2']:10.4f}"
        )


def read_test_csv(path: str | Path) -> list[dict[str, str]]:
    """Rows of a test file with columns displacement_mm, force_N and optionally sense."""
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    if not rows or not {"displacement_mm", "force_N"} <= set(rows[0]):
        raise ValueError(f"{path}: need a header with displacement_mm and force_N")
    return rows


def fit_test_data(
    rows: list[dict[str, str]],
    test: str,
    side_mm: float | None = None,
    height_mm: float | None = None,
    width_mm: float | None = None,
    fabric_side_mm: float | None = None,
    sense: str = "parallel",
    degree: int | None = 3,
    step_deg: float = 2.0,
) -> tuple[dict[str, Any], list[str]]:
    """Normalise test rows and fit them; returns (shear_law block, comment lines on quality).

    ``degree=None`` gives a tabulated law. ``sense="both"`` needs a ``sense`` column
    (parallel/perpendicular) and gives an asymmetric law; one sense gives a symmetric law from
    the rows of that sense (all rows when there is no ``sense`` column).
    """

    def normalise(selected: list[dict[str, str]]) -> tuple[np.ndarray, np.ndarray]:
        delta = np.array([float(r["displacement_mm"]) for r in selected])
        force = np.array([float(r["force_N"]) for r in selected])
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

    def select(which: str) -> list[dict[str, str]]:
        if "sense" not in rows[0]:
            if sense == "both":
                raise ValueError("--sense both needs a 'sense' column")
            return rows
        chosen = [r for r in rows if r["sense"].strip().lower() == which]
        if not chosen:
            raise ValueError(f"no rows with sense {which!r}")
        return chosen

    def fit(which: str) -> PolynomialFit | TableFit:
        angle, force = normalise(select(which))
        return fit_polynomial(angle, force, degree) if degree else fit_table(angle, force, step_deg)

    senses = ["parallel", "perpendicular"] if sense == "both" else [sense]
    fits = [fit(s) for s in senses]
    block = shear_law_block(fits[0], fits[1] if len(fits) > 1 else None)
    comments = [f"fitted by preform fit from {test} data ({', '.join(senses)})"]
    for s, f in zip(senses, fits, strict=True):
        q = f.quality
        comments.append(
            f"{s}: R² = {q.r_squared:.4f}, RMSE = {q.rmse_N_per_mm:.4g} N/mm, {q.points} points"
        )
    if sense == "perpendicular":
        comments.append("perpendicular data only: the block is symmetric; merge as negative sense")
    return block, comments


@click.command("fit")
@click.argument("data", type=click.Path(exists=True, dir_okay=False))
@click.option("--test", type=click.Choice(["picture-frame", "bias-extension"]), required=True)
@click.option("--side-mm", type=float, help="Picture-frame side, pin to pin [mm].")
@click.option("--fabric-side-mm", type=float, help="Cruciform specimen: sheared fabric side [mm].")
@click.option("--height-mm", type=float, help="Bias-extension specimen height H [mm].")
@click.option("--width-mm", type=float, help="Bias-extension specimen width W [mm].")
@click.option(
    "--sense", type=click.Choice(["parallel", "perpendicular", "both"]), default="parallel"
)
@click.option("--degree", type=int, default=3, show_default=True, help="0: tabulated law.")
@click.option("--step-deg", type=float, default=2.0, show_default=True, help="Table bin [deg].")
@click.option("--out", type=click.Path(dir_okay=False), help="Write the YAML block here.")
def fit_command(
    data: str,
    test: str,
    side_mm: float | None,
    fabric_side_mm: float | None,
    height_mm: float | None,
    width_mm: float | None,
    sense: str,
    degree: int,
    step_deg: float,
    out: str | None,
) -> None:
    """Normalise a shear test (DATA.csv: displacement_mm, force_N[, sense]) and fit a law."""
    try:
        block, comments = fit_test_data(
            read_test_csv(data),
            test,
            side_mm=side_mm,
            height_mm=height_mm,
            width_mm=width_mm,
            fabric_side_mm=fabric_side_mm,
            sense=sense,
            degree=degree or None,
            step_deg=step_deg,
        )
    except ValueError as error:
        raise click.ClickException(str(error)) from error
    text = block_to_yaml(block, comments)
    if out:
        Path(out).write_text(text, encoding="utf-8")
    click.echo(text, nl=False)
