"""``preform validate``: the model against every dataset of the suite; a figure and a table row
per dataset.

For each dataset (``datasets/*/dataset.yaml``) the measured curve is normalised (γ [deg],
F_s/L [N/mm], ``preform.shear.testdata``) and compared with three laws over the same points,
those up to the benchmark fabric's locking angle (the law's own; past it the friction law and
the bias-extension kinematics both stop being what is compared):

1. ``bundled``: the bundled fabric closest to the tested one, as it ships (uncalibrated);
2. ``benchmark``: the tested fabric from its paper's table (``fabrics.yaml``), its unknown law
   constants at the bundled fabric's illustrative values (uncalibrated);
3. ``calibrated``: the benchmark fabric with its pre-tension and its friction mobilisation
   angle fitted to the points up to its locking angle (``preform.shear.calibrate``). Before
   locking the law's force is μ·(pre-tension force)·(geometry)·(1 − exp(−γ/γ_m)), so only the
   product of friction and pre-tension is identifiable there: friction stays at its value and
   pre-tension carries the product; γ_m sets how the force rises from zero (measured curves
   do, a Coulomb crossover would not). The residuals are absolute (N/mm): the fit minimises
   the rms the table reports.

Errors are rms [N/mm] and rms relative to the data's rms, R².
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import click

from preform.command_line import InputError, echo_json, json_option

#: The constants the suite fits (PATH=LO:HI), per law; see the module docstring for why these.
#: The bounds are the fields' plausible ranges (docs/ranges.md), pre-tension from 1 N.
SUITE_CONSTANTS = {
    "friction_compaction": (
        "shear_law.pretension_N=1:10000",
        "shear_law.friction_mobilisation_deg=0:90",
    )
}


def suite_dir() -> Path:
    """The installed ``validation/`` folder (datasets and the benchmark fabrics)."""
    return Path(str(resources.files("preform.validation_suite")))


def dataset_dirs() -> list[Path]:
    return sorted(p.parent for p in (suite_dir() / "datasets").glob("*/dataset.yaml"))


@dataclass
class Comparison:
    """One dataset against one law: the law's label and its errors up to locking."""

    dataset: str
    model: str
    fabric: str
    rms_N_per_mm: float
    relative_rms: float
    r_squared: float | None
    points: int
    up_to_deg: float
    constants: str
    #: The fitted constants (``FittedConstant.as_json``), for the calibrated row; else empty.
    fitted: list[dict[str, Any]] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        return dict(self.__dict__)


def load_dataset(folder: Path) -> dict[str, Any]:
    import yaml

    meta: dict[str, Any] = yaml.safe_load((folder / "dataset.yaml").read_text(encoding="utf-8"))
    meta["id"] = folder.name
    meta["points_path"] = folder / str(meta["points"])
    return meta


NORMALISED_COLUMNS = ("shear_angle_deg", "force_per_length_N_per_mm")


def read_normalised_csv(path: Path) -> tuple[Any, Any]:
    """A normalised curve: columns ``shear_angle_deg, force_per_length_N_per_mm`` (γ [deg],
    F_s/L [N/mm]); ValueError naming the file and line of a bad row."""
    import csv

    import numpy as np

    angles, forces = [], []
    with path.open(newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = [h.strip() for h in next(reader, [])]
        if tuple(header) != NORMALISED_COLUMNS:
            raise ValueError(f"{path}:1: header must be {', '.join(NORMALISED_COLUMNS)}")
        for line, row in enumerate(reader, start=2):
            try:
                a, f = (float(v) for v in row)
            except ValueError:
                raise ValueError(f"{path}:{line}: two numbers expected, got {row!r}") from None
            angles.append(a)
            forces.append(f)
    return np.asarray(angles), np.asarray(forces)


def run_dataset(folder: Path, library: Any, out_dir: Path) -> tuple[list[Comparison], Path]:
    """Compare the three laws with one dataset; write its figure; its table rows."""
    import numpy as np

    from preform.library import build_shear_law
    from preform.shear.calibrate import calibrate_law, file_sha256, quality, resolve_constants
    from preform.shear.commands import normalise_rows, read_test_csv
    from preform.shear.figures import calibration_figure
    from preform.shear.law import force_per_length_N_per_mm

    meta = load_dataset(folder)
    specimen = meta.get("specimen") or {}
    if meta.get("normalised"):
        # points already normalised by their authors (γ [deg], F_s/L [N/mm])
        angle, force = read_normalised_csv(meta["points_path"])
        count = len(angle)
    else:
        rows = read_test_csv(meta["points_path"])
        count = len(rows)
        angle, force = normalise_rows(
            rows,
            meta["test"],
            side_mm=specimen.get("side_mm"),
            fabric_side_mm=specimen.get("fabric_side_mm"),
            height_mm=specimen.get("height_mm"),
            width_mm=specimen.get("width_mm"),
        )
    if count != int(meta["point_count"]):
        raise ValueError(
            f"{meta['points_path']}: {count} points, dataset.yaml says {meta['point_count']}"
        )
    benchmark = library.fabric(meta["fabric"])
    bundled = library.fabric(meta["closest_bundled"])
    locking = build_shear_law(benchmark, library.registry).locking_angle
    up_to = math.degrees(locking) if locking is not None else float(np.max(angle))
    law_name = str(getattr(benchmark.shear_law, "law", ""))
    constants = resolve_constants(benchmark, list(SUITE_CONSTANTS.get(law_name, ())) or None)
    calibration = calibrate_law(
        benchmark,
        library.registry,
        angle,
        force,
        constants,
        max_angle_deg=up_to,
        test=meta["test"],
        specimen={k.removesuffix("_mm"): float(v) for k, v in specimen.items()},
        data_file=str(meta["points_path"].name),
        data_sha256=file_sha256(meta["points_path"]),
        weights="absolute",
    )
    chosen = angle <= up_to
    grid = np.linspace(0.0, float(np.max(angle)), 300)
    laws = {
        "bundled": (bundled.name, build_shear_law(bundled, library.registry), ""),
        "benchmark": (benchmark.name, build_shear_law(benchmark, library.registry), ""),
        "calibrated": (
            benchmark.name,
            None,
            ", ".join(
                f"{c.name.split('.')[-1]} = {c.value:.3g}"
                + (f" ± {c.sigma:.2g}" if c.sigma is not None else "")
                + (" (at its bound)" if c.at_bound else "")
                for c in calibration.constants
            ),
        ),
    }
    rows_out: list[Comparison] = []
    curves = []
    for label, (fabric_name, law, fitted) in laws.items():
        if law is None:
            model = calibration.model_curve(angle[chosen])
            curve = calibration.model_curve(grid)
        else:
            model = force_per_length_N_per_mm(law, np.radians(angle[chosen]))
            curve = force_per_length_N_per_mm(law, np.radians(grid))
        q = quality(np.asarray(model), force[chosen], angle[chosen])
        rows_out.append(
            Comparison(
                meta["id"],
                label,
                fabric_name,
                q.rms_N_per_mm,
                q.relative_rms,
                q.r_squared,
                q.points,
                up_to,
                fitted,
                [c.as_json() for c in calibration.constants] if law is None else [],
            )
        )
        curves.append((grid, curve, f"{label} ({fabric_name}): {100 * q.relative_rms:.0f} % rms"))
    curves = [curves[2], curves[1], curves[0]]  # calibrated first: drawn bold
    figure = out_dir / f"{meta['id']}.png"
    calibration_figure(
        data=(angle, force),
        curves=curves,
        path=figure,
        locking_deg=up_to,
        title=meta["title"],
        size_px=(720, 480),
    )
    return rows_out, figure


def measured_angles() -> list[dict[str, Any]]:
    """The suite's measured angles (``angles.yaml``), each with its citation."""
    import yaml

    path = suite_dir() / "angles.yaml"
    return list(yaml.safe_load(path.read_text(encoding="utf-8")) or [])


def angle_rows(library: Any) -> list[dict[str, Any]]:
    """Each measured angle beside the model's locking (tows meet) and jamming (tows at the
    weave's jamming fraction, the law's ``packing_angle``) angles of the same fabric [deg], and
    whether the measurement's interval holds either."""
    import math

    rows = []
    for entry in measured_angles():
        law = library.shear_law(entry["fabric"])
        lock = math.degrees(law.locking_angle or 0.0)
        jam = math.degrees(law.packing_angle) if law.packing_angle is not None else 90.0
        lo = float(entry["value_deg"]) - float(entry["uncertainty_deg"])
        hi = float(entry["value_deg"]) + float(entry["uncertainty_deg"])
        rows.append(
            {
                "name": entry["name"],
                "fabric": entry["fabric"],
                "quantity": entry["quantity"],
                "measured_deg": float(entry["value_deg"]),
                "uncertainty_deg": float(entry["uncertainty_deg"]),
                "model_locking_deg": lock,
                "model_jamming_deg": jam,
                "within": [
                    label for label, a in (("locking", lock), ("jamming", jam)) if lo <= a <= hi
                ],
            }
        )
    return rows


def angles_markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| measurement | fabric | measured [deg] | model locking [deg] | model jamming [deg] | "
        "within the measurement's interval |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['name']} | {r['fabric']} | {r['measured_deg']:.0f} ± "
            f"{r['uncertainty_deg']:.0f} | {r['model_locking_deg']:.1f} | "
            f"{r['model_jamming_deg']:.1f} | {', '.join(r['within']) or 'neither'} |"
        )
    return "\n".join(lines) + "\n"


def run_validation(out_dir: str | Path, library: Any = None) -> dict[str, Any]:
    """Run every dataset; write ``OUT/<dataset>.png``, ``OUT/validation.csv`` and
    ``OUT/validation.md`` (the curves' table, then the measured angles'); return the tables
    and the files."""
    import csv

    from preform.library import load_library

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    lib = library or load_library([suite_dir() / "fabrics.yaml"])
    rows: list[Comparison] = []
    figures = []
    for folder in dataset_dirs():
        found, figure = run_dataset(folder, lib, out)
        rows += found
        figures.append(str(figure))
    table = out / "validation.csv"
    with table.open("w", newline="", encoding="utf-8") as handle:
        # the table keeps the constants in words; the structured ones are in the JSON report
        columns = [k for k in rows[0].as_json() if k != "fitted"]
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow(row.as_json())
    angles = angle_rows(lib)
    markdown = out / "validation.md"
    markdown.write_text(markdown_table(rows) + "\n" + angles_markdown(angles), encoding="utf-8")
    return {
        "rows": [r.as_json() for r in rows],
        "angles": angles,
        "files": {"table": str(table), "markdown": str(markdown), "figures": figures},
    }


def markdown_table(rows: list[Comparison]) -> str:
    lines = [
        "| dataset | model | fabric | up to [deg] | points | rms [N/mm] | rms / data rms | R² | "
        "fitted |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        r2 = "n/a" if r.r_squared is None else f"{r.r_squared:.2f}"
        lines.append(
            f"| {r.dataset} | {r.model} | {r.fabric} | {r.up_to_deg:.1f} | {r.points} | "
            f"{r.rms_N_per_mm:.4f} | {100 * r.relative_rms:.0f} % | {r2} | {r.constants or '-'} |"
        )
    return "\n".join(lines) + "\n"


@click.command("validate")
@click.option(
    "--out",
    "out_dir",
    default="preform-validation",
    show_default=True,
    type=click.Path(file_okay=False),
    metavar="DIR",
    help="Folder for the figures and the table (created).",
)
@json_option
def validate_command(out_dir: str, as_json: bool) -> None:
    """Compare the model with published measured shear curves: figures and a table.

    Each dataset of the suite (preform/validation_suite/datasets) against the closest bundled
    fabric, the tested fabric from its paper's table, and that fabric calibrated; errors up to
    the locking angle. docs/validation.md explains the datasets.
    """
    try:
        report = run_validation(out_dir)
    except (OSError, ValueError) as error:
        raise InputError(str(error)) from error
    if as_json:
        echo_json(report)
        return
    rows = report["rows"]
    click.echo(markdown_table([Comparison(**r) for r in rows]), nl=False)
    click.echo(angles_markdown(report["angles"]), nl=False)
    click.echo(f"wrote {report['files']['table']}, {report['files']['markdown']}")
    for figure in report["files"]["figures"]:
        click.echo(f"wrote {figure}")
