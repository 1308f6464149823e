"""Speed of the pin-jointed-net engine: nodes placed per second and peak memory.

A square ply of side 2R centred on the pole of a unit hemisphere, α = 90°, n × n nodes; the
closed-form (sphere) placement, for the smaller nets the general Newton placement that any
surface gets, and a triangle mesh of the hemisphere (the bundled STL's tessellation, 5184
triangles: the cost of a tool read from a CAD file), which places by its exact walk whatever
``use_closed_form`` says (issue 30; before, that flag sent it to Newton on k-d-tree queries). Time is the best of ``--repeat`` runs (the machine may be shared); peak memory is
traced by tracemalloc on a separate run, since tracing slows numpy down.

    python benchmarks/bench_drape.py [--sizes 25 50 100 200 500 1000] [--repeat 3]
        [--newton-max 500] [--mesh-max 200]
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.plugins.surfaces.basic import Hemisphere
from preform.plugins.surfaces.mesh import tessellate_hemisphere

MESH = tessellate_hemisphere(1.0, 36)


def run(n: int, closed_form: bool, mesh: bool = False) -> tuple[int, float]:
    radius = 1.0
    d = 2.0 * radius / (n - 1) * (1 - 1e-12)
    side = (n - 1) * d
    start = time.perf_counter()
    result = drape(
        MESH if mesh else Hemisphere(radius),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((side, side)),
        use_closed_form=closed_form,
    )
    return result.nodes_placed, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 200, 500, 1000])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--newton-max", type=int, default=500, help="largest n for Newton runs")
    parser.add_argument("--mesh-max", type=int, default=200, help="largest n for mesh runs")
    args = parser.parse_args()
    print(
        f"{'placement':<12}{'n':>6}{'nodes':>10}{'placed':>10}{'time s':>10}"
        f"{'nodes/s':>12}{'peak MB':>10}{'B/node':>8}"
    )
    for label, closed_form, mesh, largest in (
        ("closed form", True, False, max(args.sizes)),
        ("newton", False, False, args.newton_max),
        ("mesh", False, True, args.mesh_max),
    ):
        for n in args.sizes:
            if n > largest:
                continue
            best = np.inf
            placed = 0
            for _ in range(args.repeat):
                placed, seconds = run(n, closed_form, mesh)
                best = min(best, seconds)
            tracemalloc.start()
            run(n, closed_form, mesh)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            print(
                f"{label:<12}{n:>6}{n * n:>10}{placed:>10}{best:>10.3f}{placed / best:>12.3g}"
                f"{peak / 1e6:>10.1f}{peak / (n * n):>8.0f}"
            )


if __name__ == "__main__":
    main()
