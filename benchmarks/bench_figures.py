"""The default study's figures against their code before issue 15g, in one process.

Fig. 11 (``fibre_pattern_figure``, one a case): the default scene's drape at the least-energy
angle of ``--fabric`` (hemisphere R = 100 mm, 2.5 mm net, the part's edge), drawn and saved as a
PNG by today's module and by the frozen copy in ``fig_drape_baseline.py`` (mplot3d's 3D view,
matplotlib's PNG writer), taking turns ``--repeat`` times; processor time (``process_time``)
of each call, best and median, and the ratio. Then the first figure in a fresh process: a child
interpreter that has imported what a pipeline worker preloads (numpy, preform, matplotlib's
figure, Agg and mplot3d modules) draws one figure, for each code in turn, best of ``--fresh``
children.

Fig. 10 (``energy_vs_angle_figure`` of ten fabrics, drawn once a run): the same function saved by
today's ``save_figure`` and by the one before (the figure's code itself is unchanged); its
curves are illustrative parabolas on 25 angles, the figure's cost does not depend on them.

    python benchmarks/bench_figures.py [--repeat 15] [--fresh 3] [--fabric E-BXhd-936]
        [--keep DIR]

``--keep DIR`` leaves the PNGs of both codes there, to look at.
"""

from __future__ import annotations

import argparse
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import fig_drape_baseline as baseline
import numpy as np

from preform import api
from preform.drape.steps import scene_part
from preform.export import fig_curves, fig_drape

HERE = Path(__file__).resolve().parent

FRESH = """
import pickle, sys, time
sys.path.insert(0, {here!r})
# what a pipeline worker has imported (the runner's WORKER_PRELOAD) before its first case
import numpy, matplotlib.figure, matplotlib.backends.backend_agg, mpl_toolkits.mplot3d, preform
from preform.export import fig_drape
import fig_drape_baseline
result, energy, part, every = pickle.load(open({case!r}, "rb"))
draw = {{"today": fig_drape, "before": fig_drape_baseline}}[sys.argv[1]].fibre_pattern_figure
start = time.process_time()
draw(result, energy, {out!r}, title="fresh", tow_every=every, part=part)
print(time.process_time() - start)
"""


def default_case(fabric: str) -> tuple[Any, Any, Any, int]:
    """The default scene's drape of ``fabric`` at its least-energy angle, as the pipeline's
    fibre-pattern step receives it: (result, energy, part, tow_every)."""
    run = api.least_energy(fabric)
    run.raise_for_status()
    draped = run.products["drape"]
    surface = run.products.get("surface")
    part = scene_part(run.scene, surface) if surface is not None else None
    every = max(
        1, round(5e-3 / draped.result.node_spacing)
    )  # as drape_outputs.write_fibre_pattern_png
    return draped.result, draped.energy, part, every


def cpu(call: Callable[[], Any]) -> float:
    start = time.process_time()
    call()
    return time.process_time() - start


def alternate(calls: dict[str, Callable[[], Any]], repeat: int) -> dict[str, list[float]]:
    """Processor times of each call, the calls taking turns (load hits them alike)."""
    for call in calls.values():  # untimed: imports, font cache, first-figure costs
        call()
    times: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(repeat):
        for name, call in calls.items():
            times[name].append(cpu(call))
    return times


def report(title: str, times: dict[str, list[float]], sizes: dict[str, int]) -> None:
    print(title)
    print(f"{'code':<10}{'best ms':>10}{'median ms':>11}{'x before':>10}{'PNG kB':>9}")
    before = min(times["before"])
    for name, values in times.items():
        best = min(values)
        print(
            f"{name:<10}{1e3 * best:>10.1f}{1e3 * statistics.median(values):>11.1f}"
            f"{before / best:>10.2f}{sizes[name] / 1e3:>9.0f}"
        )


def illustrative_curves() -> tuple[dict[str, list[tuple[float, float]]], dict[str, float]]:
    angles = np.linspace(30.0, 150.0, 25)
    curves, optima = {}, {}
    for n in range(10):
        best = 80.0 + 2.0 * n
        energy = 0.2 + 0.05 * n + 1e-4 * (1 + n) * (angles - best) ** 2
        curves[f"fabric-{n}"] = list(zip(angles.tolist(), energy.tolist(), strict=True))
        optima[f"fabric-{n}"] = best
    return curves, optima


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--fresh", type=int, default=3)
    parser.add_argument("--fabric", default="E-BXhd-936")
    parser.add_argument("--keep", type=Path, default=None)
    args = parser.parse_args()
    print(f"load average before {os.getloadavg()[0]:.2f} (1 min)")
    result, energy, part, every = default_case(args.fabric)
    with tempfile.TemporaryDirectory(prefix="preform-figures-") as scratch:
        out = args.keep or Path(scratch)
        out.mkdir(parents=True, exist_ok=True)
        codes = {"before": baseline, "today": fig_drape}
        paths = {name: out / f"fibre_pattern_{name}.png" for name in codes}

        def pattern(module: Any, path: Path) -> Callable[[], Any]:
            return lambda: module.fibre_pattern_figure(
                result, energy, path, title=args.fabric, tow_every=every, part=part
            )

        times = alternate(
            {name: pattern(module, paths[name]) for name, module in codes.items()}, args.repeat
        )
        sizes = {name: path.stat().st_size for name, path in paths.items()}
        report(
            f"Fig. 11, {args.fabric}, net {result.shape[0]} x {result.shape[1]}, warm, "
            f"{args.repeat} each",
            times,
            sizes,
        )

        case = Path(scratch) / "case.pkl"
        case.write_bytes(pickle.dumps((result, energy, part, every)))
        fresh: dict[str, list[float]] = {name: [] for name in codes}
        for _ in range(args.fresh):
            for name in ("before", "today"):
                script = FRESH.format(here=str(HERE), case=str(case), out=str(paths[name]))
                done = subprocess.run(
                    [sys.executable, "-c", script, name], check=True, capture_output=True, text=True
                )
                fresh[name].append(float(done.stdout.split()[-1]))
        report(f"Fig. 11, first figure of a fresh process, {args.fresh} each", fresh, sizes)

        curves, optima = illustrative_curves()
        library = {name: out / f"library_energy_{name}.png" for name in codes}
        saves = {"before": baseline.save_figure, "today": fig_curves.save_figure}

        def fig10(name: str) -> Callable[[], Any]:
            def draw() -> None:
                kept = fig_curves.save_figure
                fig_curves.save_figure = saves[name]
                try:
                    fig_curves.energy_vs_angle_figure(curves, library[name], optima=optima)
                finally:
                    fig_curves.save_figure = kept

            return draw

        times = alternate({name: fig10(name) for name in codes}, args.repeat)
        sizes = {name: path.stat().st_size for name, path in library.items()}
        report(f"Fig. 10, ten fabrics, warm, {args.repeat} each", times, sizes)
    print(f"load average after {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
