"""Each output of a case against the drape and search it reports (issue 30), in one process.

The case: the default study's scene (``hemisphere-min-energy``: R = 100 mm, 360 mm ply, the
least-energy search over generator angles, ``--fidelity``) and ``--fabric``. Its physics (the
surface, shear law, the search's drapes, the drape at the optimum and its thickness: what
``preform.least_energy`` runs without files) is timed as one call; then each output's own
pipeline step (``cells_csv``, ``vtu``, ``fibre_pattern_png``) is run on that case's products,
as the runner runs it, into a scratch folder. Everything runs once untimed first (imports,
compilation, font caches, the first figure); then the physics and each output take turns
``--repeat`` times: CPU time of this process (pinned to one core), best and median, and each
output's best over the physics' best. One row times the code before issue 30 on the same
case, for the ratio of the change: ``cells_csv`` with every field formatted on its own (the
per-value ``format_column`` it replaced, frozen here).

Then the stack's own outputs, on the bundled ``hemisphere-layup`` at the same fidelity, against
the layup without files of its own (``preform.layup(..., outputs=["layup"])``: its plies with
their outputs, the offsets, the maps): ``stack_csv`` (today's and per value, as above) and
``stack_thickness_png`` (its stations as the reference ply's cells, as the pipeline draws it,
and as one marker a station, as ``Layup.plot`` does).

    python benchmarks/bench_outputs.py [--fabric E-BXhd-936] [--fidelity standard] [--repeat 7]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from preform import api
from preform.export import csv_columns
from preform.pipeline.planner import plan
from preform.step import CaseContext

if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

PHYSICS = ["energy_vs_angle", "optimum", "drape"]
OUTPUTS = ["cells_csv", "vtu", "fibre_pattern_png"]


def format_column_per_value(values: Any) -> list[str]:
    """The fields of a column as ``csv_columns.format_column`` wrote them before issue 30, each
    value formatted on its own (frozen copy, for the "before" row)."""
    if isinstance(values, np.ma.MaskedArray):
        missing = np.ma.getmaskarray(values).ravel()
        fields = format_column_per_value(np.ma.getdata(values).ravel())
        for k in np.flatnonzero(missing).tolist():
            fields[k] = ""
        return fields
    if isinstance(values, np.ndarray):
        flat = values.ravel()
        if flat.dtype.kind == "f":
            present = ~np.isnan(flat)
            text = np.full(flat.size, "", dtype=object)
            text[present] = list(map(repr, flat[present].astype(np.float64).tolist()))
            return list(text.tolist())
        if flat.dtype.kind in "iub":
            return list(map(str, flat.tolist()))
        values = flat.tolist()
    return [
        ""
        if v is None or (isinstance(v, float) and math.isnan(v))
        else repr(v)
        if isinstance(v, float)
        else str(v)
        for v in values
    ]


def cpu(call: Callable[[], Any]) -> float:
    """CPU time of ``call`` [s] (this process's own: other work on the machine does not
    count, nor a write's wait for the disk)."""
    start = time.process_time()
    call()
    return time.process_time() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fabric", default="E-BXhd-936")
    parser.add_argument("--fidelity", default="standard")
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    library = api.load_library()

    def physics() -> Any:
        return api.least_energy(
            args.fabric, library=library, fidelity=args.fidelity, outputs=PHYSICS
        )

    full = api.least_energy(
        args.fabric, library=library, fidelity=args.fidelity, outputs=PHYSICS + OUTPUTS
    )
    full.raise_for_status()
    steps = {s.name: s for s in plan(full.scene, api._host().registry) if s.name in OUTPUTS}
    result = full.products["drape"].result
    with tempfile.TemporaryDirectory(prefix="preform-outputs-") as scratch:

        def output(name: str) -> Callable[[], Any]:
            def write() -> Any:
                ctx = CaseContext(
                    fabric=full.fabric,
                    scene=full.scene,
                    registry=api._host().registry,
                    case_dir=Path(scratch),
                    products=dict(full.products),
                    summary=dict(full.summary),
                )
                return steps[name].run(ctx)

            return write

        def before_csv() -> Any:
            kept = csv_columns.format_column
            csv_columns.format_column = format_column_per_value
            try:
                return output("cells_csv")()
            finally:
                csv_columns.format_column = kept

        calls = {
            "drape + search": physics,
            **{name: output(name) for name in OUTPUTS},
            "cells_csv before": before_csv,
        }
        for call in calls.values():  # untimed: imports, compilation, caches, first figure
            call()
        times: dict[str, list[float]] = {name: [] for name in calls}
        for _ in range(args.repeat):
            for name, call in calls.items():
                times[name].append(cpu(call))
        sizes = {n: (Path(scratch) / f).stat().st_size for n, f in _files().items()}
        before_csv()
        text_before = (Path(scratch) / "cells.csv").read_bytes()
        output("cells_csv")()
        same = (Path(scratch) / "cells.csv").read_bytes() == text_before
    base = min(times["drape + search"])
    drapes = full.summary.get("search_drapes", "?")
    print(
        f"default study case: {args.fabric}, fidelity {args.fidelity}, net "
        f"{result.shape[0]} x {result.shape[1]}, {drapes} drapes in the search; CPU, one "
        f"core, best of {args.repeat}"
    )
    print(f"{'':<18}{'best ms':>9}{'median ms':>11}{'x physics':>11}{'file kB':>9}")
    for name, values in times.items():
        size = f"{sizes[name] / 1e3:>9.0f}" if name in sizes else f"{'':>9}"
        print(
            f"{name:<18}{1e3 * min(values):>9.1f}{1e3 * statistics.median(values):>11.1f}"
            f"{min(values) / base:>11.2f}{size}"
        )
    print(f"cells.csv byte-identical, today's code and the per-value code: {same}")
    every = sum(min(times[name]) for name in OUTPUTS)
    print(f"{'all three outputs':<18}{1e3 * every:>9.1f}{'':>11}{every / base:>11.2f}")
    stack_outputs(args.fidelity, args.repeat, library)


def stack_outputs(fidelity: str, repeat: int, library: Any) -> None:
    """The stack's own files against the layup they report (module docstring)."""
    from preform.export.fig_stack import stack_figure
    from preform.pipeline.scene import bundled_scene_dir
    from preform.stack.steps import write_stack_csv, write_stack_thickness_png

    scene = api.scene(bundled_scene_dir() / "hemisphere-layup.yaml", fidelity=fidelity)
    with tempfile.TemporaryDirectory(prefix="preform-outputs-") as scratch:
        folder = Path(scratch)

        def layup() -> Any:
            with tempfile.TemporaryDirectory(dir=scratch) as out:
                return api.layup(scene, library=library, out_dir=out, outputs=["layup"])

        made = layup()
        stack = made.products["layup"]

        def context() -> CaseContext:
            return CaseContext(
                fabric=made.fabric,
                scene=made.scene,
                registry=api._host().registry,
                case_dir=folder,
                products=dict(made.products),
            )

        def csv_before() -> Any:
            kept = csv_columns.format_column
            csv_columns.format_column = format_column_per_value
            try:
                return write_stack_csv(context())
            finally:
                csv_columns.format_column = kept

        calls = {
            "layup, no files": layup,
            "stack_csv": lambda: write_stack_csv(context()),
            "stack_thickness_png": lambda: write_stack_thickness_png(context()),
            "stack_csv before": csv_before,
            "png, markers": lambda: stack_figure(stack.maps, folder / "markers.png", "t"),
        }
        for call in calls.values():
            call()
        times: dict[str, list[float]] = {name: [] for name in calls}
        for _ in range(repeat):
            for name, call in calls.items():
                times[name].append(cpu(call))
    base = min(times["layup, no files"])
    print(
        f"bundled hemisphere-layup, fidelity {fidelity}, {len(stack.maps.points_mm)} stations, "
        f"{len(stack.layers)} plies with their outputs; CPU, one core, best of {repeat}"
    )
    print(f"{'':<20}{'best ms':>9}{'median ms':>11}{'x layup':>9}")
    for name, values in times.items():
        print(
            f"{name:<20}{1e3 * min(values):>9.1f}{1e3 * statistics.median(values):>11.1f}"
            f"{min(values) / base:>9.3f}"
        )


def _files() -> dict[str, str]:
    return {
        "cells_csv": "cells.csv",
        "vtu": "drape.vtu",
        "fibre_pattern_png": "fibre_pattern.png",
    }


if __name__ == "__main__":
    main()
